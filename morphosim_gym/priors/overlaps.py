"""Pixels where two moving objects' planned boxes overlap, shared out by whose motion they follow.

`masks.label_regions` gives a moving region that several planned boxes cover to the nearest box
(the lowest bottom: objects stand on the ground). A planned box is looser than its object: the
box of a sheep in front reaches rows above its back, where the sheep behind it shows, so the one
behind loses a band of its body to the one in front (two white sheep side by side: the back one's
recall 0.63 in the estimated masks).

Each object moves with its box. A pixel that belongs to object k keeps its colour when frame
t + o is warped back by the motion of k's box between t and t + o (the box's centre shift and
scale); warped by another object's motion it does not, once the two motions part by a pixel or
more. So each contested pixel (labelled one of the objects, inside two or more of their boxes)
gets, per candidate, the median over the offsets `offsets` (both ways in time) of the colour error
after that candidate's warp, summed over a `patch` window, and goes to the candidate whose error
is lowest when
- it is below `ratio` times the next lowest (a flat patch ties and says nothing);
- the two candidates' warps take the pixel at least `min_parting` pixels apart at some offset
  (objects moving alike cannot be told by their motion: three sheep in step, 0.03 px a frame
  apart, were split at random without this);
- the candidate is farther than the pixel's current object (its box bottom higher). Pixels only
  ever leave a nearer object: `label_regions` gave the overlap to the nearest, and the test is
  biased towards the nearer one along the occluding outline, where a farther object's own
  samples a few frames away are hidden (two cars: the red one behind lost 0.06 IoU to the blue one
  in front when pixels could move both ways).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from .masks import box_masks
from .protocol import BoxTrack

__all__ = ["split_by_motion"]


def _box_motion(boxes: np.ndarray, t: int, u: int, w: int, h: int) -> tuple[np.ndarray, np.ndarray, float] | None:
    """(centre at t, centre at u, scale u/t) of a normalised box track in pixels; None for an empty box."""
    size = np.array([w, h, w, h], np.float64)
    a, b = np.asarray(boxes[t], np.float64) * size, np.asarray(boxes[u], np.float64) * size
    wa, ha, wb, hb = a[2] - a[0], a[3] - a[1], b[2] - b[0], b[3] - b[1]
    if min(wa, ha, wb, hb) <= 0:
        return None
    return (a[:2] + a[2:]) / 2, (b[:2] + b[2:]) / 2, float(np.sqrt(wb * hb / (wa * ha)))


def _warps(boxes: np.ndarray, t: int, offsets: Sequence[int], n: int, h: int, w: int) -> dict[int, np.ndarray]:
    """Offset -> [H, W, 2] where each pixel of frame t lands in frame t + o when it moves with the
    box (its centre shift and scale), for the offsets that fit the clip and a non-empty box."""
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64) + 0.5
    out = {}
    for o in offsets:
        motion = _box_motion(boxes, t, t + o, w, h) if 0 <= t + o < n else None
        if motion is not None:
            ca, cb, s = motion
            out[o] = np.stack([cb[0] + s * (xx - ca[0]), cb[1] + s * (yy - ca[1])], -1)
    return out


def _warp_error(frames: np.ndarray, t: int, warps: dict[int, np.ndarray], patch: int) -> np.ndarray:
    """[H, W] median over the offsets of frame t's patch colour error to frame t + o sampled where
    the warp takes each pixel (inf when no offset fits)."""
    errs = []
    for o, pos in warps.items():
        m = (pos - 0.5).astype(np.float32)
        warped = cv2.remap(frames[t + o], m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        errs.append(cv2.blur(np.abs(warped - frames[t]).sum(axis=-1), (patch, patch)))
    return np.median(errs, axis=0) if errs else np.full(frames.shape[1:3], np.inf, np.float32)


def _parting(a: dict[int, np.ndarray], b: dict[int, np.ndarray], shape: tuple[int, int]) -> np.ndarray:
    """[H, W] the most, over the shared offsets, that two warps take each pixel apart (0 when they
    share none: a clip too short for the offsets, or an empty box)."""
    shared = [o for o in a if o in b]
    if not shared:
        return np.zeros(shape)
    return np.max([np.linalg.norm(a[o] - b[o], axis=-1) for o in shared], axis=0)


def split_by_motion(frames: np.ndarray, ids: np.ndarray, targets: Sequence[BoxTrack], box_margin: float = 0.25,
                    offsets: Sequence[int] = (-12, -8, -4, 4, 8, 12), ratio: float = 0.9,
                    patch: int = 3, min_parting: float = 1.0) -> np.ndarray:
    """[T, H, W] ids with the pixels that two or more targets' boxes (grown by `box_margin`) cover
    and that carry one of those targets' ids (target k is id k + 1) given to a farther target
    whose motion they follow (see the module docstring). `frames` [T, H, W, 3]; the input `ids` is not
    changed; other pixels keep their ids."""
    f = np.asarray(frames, np.float32)
    if f.ndim != 4 or f.shape[-1] != 3 or ids.shape != f.shape[:3]:
        raise ValueError(f"Expected frames [T, H, W, 3] and ids [T, H, W] of one size, found {f.shape}, {ids.shape}")
    if not 0.0 < ratio <= 1.0:
        raise ValueError(f"ratio must be in (0, 1], got {ratio}")
    out = np.array(ids, copy=True)
    t_all, h, w = ids.shape
    if len(targets) < 2:
        return out
    movers = np.arange(1, len(targets) + 1)
    for t in range(t_all):
        inside = np.stack(box_masks(targets, t, h, w, box_margin))        # [K, H, W]
        contested = (inside.sum(axis=0) >= 2) & np.isin(out[t], movers)
        if not contested.any():
            continue
        # only the targets some contested pixel may go to need their warps
        cand = [k for k in range(len(targets)) if (inside[k] & contested).any()]
        warps = {k: _warps(np.asarray(targets[k].boxes), t, offsets, t_all, h, w) for k in cand}
        err = np.full((len(targets), h, w), np.inf, np.float32)
        for k in cand:
            err[k] = np.where(inside[k], _warp_error(f, t, warps[k], patch), np.inf)
        order = np.argsort(err, axis=0)
        best, second = order[0], order[1]
        e_best = np.take_along_axis(err, best[None], 0)[0]
        e_second = np.take_along_axis(err, second[None], 0)[0]
        apart = np.zeros((h, w))
        for i, a in enumerate(cand):
            for b in cand[i + 1:]:
                pair = ((best == a) & (second == b)) | ((best == b) & (second == a))
                if (pair & contested).any():
                    apart[pair] = _parting(warps[a], warps[b], (h, w))[pair]
        decisive = np.isfinite(e_second) & (e_best < ratio * e_second) & (apart >= min_parting)
        # only ever away from a nearer object (its box bottom lower): label_regions gave the overlap
        # to the nearest, and a pixel of a farther object that the nearer one covers a few frames
        # away matches the nearer one's motion better than its own (the occluded samples)
        bottom = np.array([np.asarray(tg.boxes, np.float64)[t, 3] for tg in targets])
        current = np.clip(out[t] - 1, 0, len(targets) - 1)
        farther = bottom[best] < bottom[current]
        take = contested & decisive & farther
        out[t][take] = best[take] + 1
    return out
