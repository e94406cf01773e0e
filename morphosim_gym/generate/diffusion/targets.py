"""Guidance targets: the motion words of a prompt and the boxes they should stay in.

A `GuidanceTarget` is what the trajectory planner hands to the diffusion backend: the prompt
words whose text tokens are the paper's "motion tokens" y_n, and one image-space box B_i per
video frame (the paper's "Bounding Box Definition" / "Frame-Wise Bounding Box Allocation").

This module also holds the three pure mappings the guidance needs:

- `latent_frame_groups` / `boxes_to_latent_frames`: video frames -> latent frames of a causal
  video VAE with temporal compression r (CogVideoX: r = 4; latent frame 0 encodes video frame 0
  alone, latent frame k >= 1 encodes video frames 4(k-1)+1 .. 4k, so T_lat = 1 + (T - 1) / r).
- `rasterize_boxes`: normalised boxes -> soft coverage masks on the latent H x W grid (the
  grid *before* patchification, as the paper asks for DiT models).
- `token_indices_for_words`: prompt words -> text-token indices, with the pipeline's tokenizer.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "GuidanceTarget",
    "latent_frame_groups",
    "boxes_to_latent_frames",
    "rasterize_boxes",
    "token_indices_for_words",
]

_BOX_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class GuidanceTarget:
    """One moving object to steer: its prompt words and a box per video frame.

    Attributes:
        words: prompt words whose tokens are the motion tokens n, e.g. ``["bus"]`` or
            ``["red", "ball"]`` (matched case-insensitively as whole words of the prompt).
        boxes: [T_video, 4] float normalised ``(x0, y0, x1, y1)`` in [0, 1], x right, y down,
            x0 < x1 and y0 < y1; one box per generated video frame.
        token_indices: explicit text-token indices (into the prompt embedding sequence) to use
            instead of tokenizing `words`; needed when the pipeline has no tokenizer (prompt
            embeddings passed directly). Empty means "map `words` with the tokenizer".
        label: mask label text; defaults to the words joined by spaces.

    Examples:
        >>> t = GuidanceTarget(["ball"], np.tile([0.6, 0.4, 0.8, 0.6], (9, 1)))
        >>> t.boxes.shape, t.label
        ((9, 4), 'ball')
    """

    words: Sequence[str]
    boxes: np.ndarray  # [T_video, 4]
    token_indices: Sequence[int] = field(default_factory=tuple)
    label: str = ""

    def __post_init__(self) -> None:
        words = [self.words] if isinstance(self.words, str) else list(self.words)
        if not words or not all(isinstance(w, str) and w.strip() for w in words):
            raise ValueError(f"Expected words as a non-empty list of non-empty strings, found {self.words!r}")
        object.__setattr__(self, "words", tuple(w.strip() for w in words))
        b = np.array(self.boxes, dtype=np.float64)
        if b.ndim != 2 or b.shape[1] != 4 or b.shape[0] < 1:
            raise ValueError(f"Expected boxes of shape [T_video, 4], found {b.shape}")
        if not np.all(np.isfinite(b)):
            raise ValueError("Expected finite boxes, found NaN or infinite values")
        if b.min() < -_BOX_TOL or b.max() > 1 + _BOX_TOL:
            raise ValueError(f"Expected normalised boxes in [0, 1], found values in [{b.min():.4g}, {b.max():.4g}]")
        b = np.clip(b, 0.0, 1.0)
        bad = np.flatnonzero((b[:, 2] <= b[:, 0]) | (b[:, 3] <= b[:, 1]))
        if bad.size:
            raise ValueError(f"Expected x0 < x1 and y0 < y1 in every box, found empty boxes at frames "
                             f"{bad[:8].tolist()} (first: {b[bad[0]].round(4).tolist()})")
        b.setflags(write=False)
        object.__setattr__(self, "boxes", b)
        idx = tuple(int(i) for i in self.token_indices)
        if any(i < 0 for i in idx):
            raise ValueError(f"Expected non-negative token_indices, found {list(idx)}")
        object.__setattr__(self, "token_indices", idx)
        object.__setattr__(self, "label", str(self.label) or " ".join(self.words))

    @property
    def num_frames(self) -> int:
        """T_video."""
        return int(self.boxes.shape[0])

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly description."""
        return {"words": list(self.words), "boxes": self.boxes.tolist(),
                "token_indices": list(self.token_indices), "label": self.label}


def latent_frame_groups(num_video_frames: int, temporal_compression: int) -> list[range]:
    """Video frames encoded by each latent frame of a causal video VAE.

    CogVideoX's VAE encodes frame 0 alone and then groups of `temporal_compression` frames, so
    ``T_video = 1 + r (T_lat - 1)``. Returns T_lat ranges of video-frame indices.

    Examples:
        >>> [list(g) for g in latent_frame_groups(9, 4)]
        [[0], [1, 2, 3, 4], [5, 6, 7, 8]]
    """
    r = int(temporal_compression)
    t = int(num_video_frames)
    if r < 1 or t < 1 or (t - 1) % r:
        raise ValueError(f"Expected num_video_frames = 1 + {r} k for temporal compression {r}, found {t}")
    return [range(1)] + [range(1 + r * k, 1 + r * (k + 1)) for k in range((t - 1) // r)]


def boxes_to_latent_frames(boxes: np.ndarray, temporal_compression: int) -> np.ndarray:
    """Average the per-video-frame boxes over the frames each latent frame encodes.

    Args:
        boxes: [T_video, 4] normalised boxes, ``T_video = 1 + r (T_lat - 1)``.
        temporal_compression: r (CogVideoX: 4).

    Returns:
        [T_lat, 4] normalised boxes (the mean corner coordinates of each group).
    """
    b = np.asarray(boxes, dtype=np.float64)
    if b.ndim != 2 or b.shape[1] != 4:
        raise ValueError(f"Expected boxes of shape [T_video, 4], found {b.shape}")
    return np.stack([b[list(g)].mean(axis=0) for g in latent_frame_groups(b.shape[0], temporal_compression)])


def rasterize_boxes(boxes: np.ndarray, height: int, width: int) -> np.ndarray:
    """Soft masks of normalised boxes on an H x W grid: each cell's covered area fraction.

    Cell (h, w) spans ``[w / W, (w + 1) / W] x [h / H, (h + 1) / H]`` in normalised image
    coordinates (x right, y down), so a box covering the whole image gives all ones and the mask
    sums to the box area times H W.

    Args:
        boxes: [T, 4] normalised ``(x0, y0, x1, y1)``.
        height, width: grid size (the latent grid before patchification).

    Returns:
        [T, H, W] float32 in [0, 1].
    """
    b = np.clip(np.asarray(boxes, dtype=np.float64), 0.0, 1.0)
    if b.ndim != 2 or b.shape[1] != 4:
        raise ValueError(f"Expected boxes of shape [T, 4], found {b.shape}")

    def cover(lo: np.ndarray, hi: np.ndarray, n: int) -> np.ndarray:  # [T], [T] -> [T, n]
        edges = np.arange(n + 1) / n
        overlap = np.minimum(hi[:, None], edges[None, 1:]) - np.maximum(lo[:, None], edges[None, :-1])
        return np.clip(overlap * n, 0.0, 1.0)

    cy = cover(b[:, 1], b[:, 3], int(height))  # [T, H]
    cx = cover(b[:, 0], b[:, 2], int(width))  # [T, W]
    return (cy[:, :, None] * cx[:, None, :]).astype(np.float32)


def token_indices_for_words(tokenizer: Any, prompt: str, words: Sequence[str], max_sequence_length: int) -> list[int]:
    """Text-token indices of `words` in `prompt`, as the pipeline tokenizes it.

    The prompt is tokenized exactly as `CogVideoXPipeline.encode_prompt` does (padding to
    `max_sequence_length`, truncation, special tokens), so the indices address rows of the
    prompt embeddings. With a fast tokenizer the character offsets pick every token overlapping a
    whole-word, case-insensitive occurrence of each word; otherwise the word's own token ids are
    searched for as a subsequence of the prompt's ids. Bare SentencePiece word-boundary pieces
    ("▁" alone) are left out: they belong to no word in particular.

    Raises:
        ValueError: a word does not occur in the prompt, or its tokens were truncated away.
    """
    if not prompt:
        raise ValueError("Expected a non-empty prompt to find motion words in, found ''")
    kwargs = dict(padding="max_length", max_length=int(max_sequence_length), truncation=True, add_special_tokens=True)
    found: set[int] = set()
    fast = bool(getattr(tokenizer, "is_fast", False))
    enc = tokenizer(prompt, return_offsets_mapping=fast, **kwargs)
    ids = list(enc["input_ids"])
    for word in words:
        hits: set[int] = set()
        spans = [m.span() for m in re.finditer(r"(?<!\w)" + re.escape(word.lower()) + r"(?!\w)", prompt.lower())]
        if not spans:
            raise ValueError(f"Expected the motion word {word!r} in the prompt, found prompt {prompt!r}")
        if fast:
            for k, (a, b) in enumerate(enc["offset_mapping"]):
                if b > a and any(a < e and b > s for s, e in spans):
                    hits.add(k)
        else:
            sub = list(tokenizer(word, add_special_tokens=False)["input_ids"])
            for k in range(len(ids) - len(sub) + 1):
                if sub and ids[k:k + len(sub)] == sub:
                    hits.update(range(k, k + len(sub)))
        if not hits:
            raise ValueError(f"Expected tokens for the motion word {word!r} within the first {max_sequence_length} "
                             f"tokens of the prompt, found none (truncated or tokenized differently)")
        # SentencePiece (T5) may emit a bare word-boundary piece "▁" before a word; it is shared by
        # every word, so it is not a motion token unless it is all there is
        order = sorted(hits)
        pieces = tokenizer.convert_ids_to_tokens([ids[k] for k in order])
        specific = {k for k, piece in zip(order, pieces, strict=True) if str(piece).replace("\u2581", "").strip()}
        found |= specific or hits
    return sorted(found)
