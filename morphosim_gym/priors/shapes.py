"""Numbered instances of one planned object share a shape: their overlap is shared out by it.

"three ducks swim across the water" plans "duck 1", "duck 2" and "duck 3", one box each, and the
three move in step, one in front of the other. Motion cannot tell them apart
(`overlaps.split_by_motion` needs their motions to part), their colours are the same, and the
nearest-box rule of `masks.label_regions` gives the one in front every pixel of its box, which is
looser than the duck: the ones behind lose most of their bodies (estimated masks' IoU 0.17 / 0.58 /
0.29 against the generator's).

Siblings are one kind of thing at one scale relative to their planned boxes, so their masks, each
mapped into its own box, are one shape. Which cells of that shared shape an object covers can be
read off the frames without knowing who is who: where a sibling stands, the pixel is foreground
(its own, or a sibling's in front of it); where it does not, the pixel is foreground only when
another sibling happens to be there. So per sibling, the share of frames in which a cell of its
box is foreground, and per cell the least of those shares over the siblings
(`shared_shape`): near 1 where the object is, near 0 where at least one sibling's surroundings
are clear. Then each pixel of the group goes to the nearest sibling (the lowest box bottom: things
stand or swim on the ground) whose shape, placed in its box, covers it with at least `threshold`;
a pixel no placed shape covers keeps its id (`split_by_shape`).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from .protocol import BoxTrack
from .siblings import base_name

__all__ = ["sibling_groups", "shared_shape", "place_shape", "split_by_shape"]


def sibling_groups(targets: Sequence[BoxTrack]) -> list[list[int]]:
    """Indices of the targets that are numbered instances of one planned object ("duck 1",
    "duck 2"), groups of two or more."""
    groups: dict[str, list[int]] = {}
    for k, tg in enumerate(targets):
        name = base_name(tg.label)
        if name != tg.label:
            groups.setdefault(name, []).append(k)
    return [g for g in groups.values() if len(g) >= 2]


def _cells(size: int, margin: float) -> np.ndarray:
    """[size] cell centres in box coordinates (0 and 1 are the box's edges), `margin` beyond each."""
    return (np.arange(size) + 0.5) / size * (1.0 + 2.0 * margin) - margin


def shared_shape(foreground: np.ndarray, boxes: Sequence[np.ndarray], size: int = 32,
                 margin: float = 0.1) -> np.ndarray:
    """[size, size] the least, over the siblings, of the share of frames in which each cell of the
    sibling's box (a grid `margin` beyond the box on each side) is `foreground` [T, H, W]; a
    sibling whose cell lies outside the image in every frame does not count there (NaN where none
    sees it). `boxes`: one [T, 4] normalised (x0, y0, x1, y1) track per sibling."""
    t_all, h, w = foreground.shape
    g = _cells(size, margin)
    shares = []
    for track in boxes:
        hits = np.zeros((size, size))
        seen = np.zeros((size, size))
        for t in range(t_all):
            x0, y0, x1, y1 = np.asarray(track[t], np.float64) * (w, h, w, h)
            if x1 <= x0 or y1 <= y0:
                continue
            c = np.floor(x0 + g * (x1 - x0)).astype(int)
            r = np.floor(y0 + g * (y1 - y0)).astype(int)
            inside = ((r >= 0) & (r < h))[:, None] & ((c >= 0) & (c < w))[None, :]
            fg = foreground[t][np.clip(r, 0, h - 1)[:, None], np.clip(c, 0, w - 1)[None, :]]
            hits += fg & inside
            seen += inside
        with np.errstate(invalid="ignore", divide="ignore"):
            shares.append(np.where(seen > 0, hits / seen, np.nan))
    stack = np.stack(shares)
    out = np.full((size, size), np.nan)
    any_seen = np.isfinite(stack).any(axis=0)
    out[any_seen] = np.nanmin(stack[:, any_seen], axis=0)
    return out


def place_shape(shape: np.ndarray, box: np.ndarray, h: int, w: int, margin: float = 0.1) -> np.ndarray:
    """[H, W] a `shared_shape` placed in one normalised box (bilinear; 0 outside its grid, and
    where the shape is NaN)."""
    size = shape.shape[0]
    x0, y0, x1, y1 = np.asarray(box, np.float64) * (w, h, w, h)
    if x1 <= x0 or y1 <= y0:
        return np.zeros((h, w), np.float32)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64) + 0.5
    u = ((xx - x0) / (x1 - x0) + margin) / (1.0 + 2.0 * margin) * size - 0.5
    v = ((yy - y0) / (y1 - y0) + margin) / (1.0 + 2.0 * margin) * size - 0.5
    grid = np.nan_to_num(shape, nan=0.0).astype(np.float32)
    return cv2.remap(grid, u.astype(np.float32), v.astype(np.float32), cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)


def split_by_shape(ids: np.ndarray, targets: Sequence[BoxTrack], size: int = 32, margin: float = 0.1,
                   threshold: float = 0.6) -> np.ndarray:
    """[T, H, W] ids with each sibling group's pixels (target k is id k + 1) shared out by their
    shared shape: a pixel of the group that one or more of the siblings' placed shapes cover
    with at least `threshold` goes to the nearest of those (lowest box bottom); the others keep
    their ids (see the module docstring). The input is not changed.

    Siblings that differ in shape lose by it: two cows of two looks (a white one, a spotted
    one) kept apart by their colours at IoU 0.88 / 0.91 come out 0.77 / 0.87. Gating the split
    by whether colour can tell the siblings apart (`colour_refine`'s colour models) did not help:
    it judged those cows alike and two identical ducks, whose first masks mixed their colours,
    apart."""
    if ids.ndim != 3:
        raise ValueError(f"Expected ids [T, H, W], found shape {ids.shape}")
    if not 0.0 < threshold <= 1.0:
        raise ValueError(f"Expected threshold in (0, 1], found {threshold}")
    out = np.array(ids, copy=True)
    t_all, h, w = ids.shape
    for group in sibling_groups(targets):
        members = np.array(group) + 1
        fg = np.isin(ids, members)
        tracks = [np.asarray(targets[k].boxes, np.float64) for k in group]
        shape = shared_shape(fg, tracks, size, margin)
        for t in range(t_all):
            if not fg[t].any():
                continue
            owner = np.zeros((h, w), np.int32)
            # far to near (box bottom rising in the image), so the nearest covering sibling is last
            for j in np.argsort([tr[t, 3] for tr in tracks], kind="stable"):
                owner[place_shape(shape, tracks[j][t], h, w, margin) >= threshold] = members[j]
            take = fg[t] & (owner > 0)
            out[t][take] = owner[take]
    return out
