"""Ranking assets for a query: word and substring matches, plus embedding similarity when given.

The embedding function is an argument (e.g. `morphosim_gym.language.embeddings.encode_table`), so
this layer never imports the language layer.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence

import numpy as np

from .record import AssetRecord

__all__ = ["EmbedFn", "lexical_scores", "rank"]

EmbedFn = Callable[[Sequence[str]], np.ndarray]   # phrases [N] -> L2-normalised vectors [N, D]

_WORD = re.compile(r"[a-z0-9]+")


def _words(text: str) -> set[str]:
    words = set(_WORD.findall(text.lower()))
    return words | {w[:-1] for w in words if len(w) > 3 and w.endswith("s")}   # crude singulars


def lexical_scores(query: str, records: Sequence[AssetRecord]) -> np.ndarray:
    """Per record: 1.25 if its name's words are the query's words; 1 if every query word is a word
    of its name; 0.75 if of its name, category and tags together; else 0.5 if the query is a
    substring of that text; else 0.  [N]"""
    q = query.strip().lower()
    qwords = _words(q)
    out = np.zeros(len(records), dtype=np.float32)
    if not q:
        return out
    for i, r in enumerate(records):
        text = r.search_text.lower()
        name = _words(r.name)
        if qwords and qwords == name:
            out[i] = 1.25
        elif qwords and qwords <= name:
            out[i] = 1.0
        elif qwords and qwords <= _words(text):
            out[i] = 0.75
        elif q in text:
            out[i] = 0.5
    return out


def rank(query: str | np.ndarray, records: Sequence[AssetRecord], k: int,
         vectors: np.ndarray | None = None, embed: EmbedFn | None = None) -> list[tuple[AssetRecord, float]]:
    """The `k` best records for `query` with their scores, best first (ties by id).

    Args:
        query: text, or a query embedding [D] (then `vectors` is required).
        records: the candidates. [N]
        k: how many to return.
        vectors: the records' embeddings [N, D], rows L2-normalised, or None for words only.
        embed: embeds the query text when `vectors` is given.

    Returns:
        (record, score) pairs; score = lexical score + cosine similarity. Without vectors, only
        records with a lexical match are returned.
    """
    if k < 1:
        raise ValueError(f"Expected k >= 1, found {k}")
    if isinstance(query, str):
        score = lexical_scores(query, records)
        qvec = embed([query])[0] if (vectors is not None and embed is not None) else None
    else:
        score = np.zeros(len(records), dtype=np.float32)
        qvec = np.asarray(query, dtype=np.float32)
        if vectors is None:
            raise ValueError("Expected asset embeddings to search by an embedding, found none (pass embed=)")
    if qvec is not None and vectors is not None:
        if qvec.shape != vectors.shape[1:]:
            raise ValueError(f"Expected a query embedding of shape {vectors.shape[1:]}, found {qvec.shape}")
        score = score + vectors @ (qvec / max(float(np.linalg.norm(qvec)), 1e-12))
        keep = np.arange(len(records))
    else:
        keep = np.flatnonzero(score > 0)
    order = sorted(keep.tolist(), key=lambda i: (-float(score[i]), records[i].id))
    return [(records[i], float(score[i])) for i in order[:k]]
