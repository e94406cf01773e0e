"""How far to trust each pixel of a mask prior and each track, read from the priors themselves.

- masks: an estimated (or corrupted) mask is a pixel or two off along its outline, so a pixel's
  confidence grows with its distance to the nearest pixel of another id: `floor` on the outline,
  1 from `radius` pixels inside;
- tracks: a track that jumps (lost on an occluder, snapped to the background) has large second
  differences against the clip's typical jitter; its weight is a Cauchy function of its own
  jitter relative to the clip's (1 for a track as smooth as most, towards 0 for a jumpy one).

Tracks that are the generator's own (`info["priors"]` "ground_truth") are exact: confidence 1.
Exact masks still get the outline weights: an outline pixel mixes two objects' colours in the
frame, so a hard instance target there fights its colour (`prior_confidences`).
"""

from __future__ import annotations

import cv2
import numpy as np

from ..scene import GeneratedClip

__all__ = ["mask_confidence", "prior_confidences", "track_confidence"]


def mask_confidence(masks: np.ndarray, radius: float = 2.0, floor: float = 0.25) -> np.ndarray:
    """[T, H, W] float32 in [floor, 1]: distance (px) to the nearest pixel of another id (the
    image border does not count), over `radius`."""
    m = np.asarray(masks)
    out = np.ones(m.shape, np.float32)
    k = np.ones((3, 3), np.uint8)
    for t in range(len(m)):
        edge = np.zeros(m.shape[1:], bool)
        for inst in np.unique(m[t]):
            sel = (m[t] == inst).astype(np.uint8)
            edge |= (cv2.dilate(sel, k).astype(bool) & ~sel.astype(bool))
        if not edge.any():
            continue
        dist = cv2.distanceTransform((~edge).astype(np.uint8), cv2.DIST_L2, 3)
        out[t] = np.clip(dist / max(radius, 1e-6), floor, 1.0)
    return out


def track_confidence(tracks: np.ndarray, visible: np.ndarray, scale: float = 3.0) -> np.ndarray:
    """[P] float32 in (0, 1]: 1 / (1 + (j / (scale * J + 0.5 px))^2), j a track's largest second
    difference over consecutive visible frames, J the median of j over all tracks."""
    tr = np.asarray(tracks, np.float64)
    vis = np.asarray(visible, bool)
    p, t = vis.shape
    if t < 3 or p == 0:
        return np.ones(p, np.float32)
    d2 = np.linalg.norm(tr[:, :-2] - 2 * tr[:, 1:-1] + tr[:, 2:], axis=-1)
    ok = vis[:, :-2] & vis[:, 1:-1] & vis[:, 2:]
    j = np.where(ok, d2, 0.0).max(axis=1)
    seen = ok.any(axis=1)
    if not seen.any():
        return np.ones(p, np.float32)
    typical = float(np.median(j[seen]))
    w = 1.0 / (1.0 + (j / (scale * typical + 0.5)) ** 2)
    return np.where(seen, w, 1.0).astype(np.float32)


def prior_confidences(clip: GeneratedClip) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(mask confidence [T, H, W] or None, track confidence [P] or None) of a clip's priors; None
    where the prior is missing, and for tracks that are the generator's exact ones ("ground_truth").
    Masks, exact or not, weigh their outlines less (see the module docstring)."""
    origin = clip.info.get("priors") or {}
    if not isinstance(origin, dict):
        origin = {}
    masks = None
    if clip.masks is not None:
        masks = mask_confidence(clip.masks)
    tracks = None
    if clip.tracks is not None and origin.get("tracks") != "ground_truth":
        tracks = track_confidence(clip.tracks, clip.track_visible)
    return masks, tracks
