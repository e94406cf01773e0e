"""Realistic errors on a clip's priors, to measure how a fit copes with imperfect ones."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np

from ..scene import GeneratedClip

__all__ = ["corrupt_priors"]


def _smooth_field(rng: np.random.Generator, shape: tuple[int, int], amplitude: float) -> np.ndarray:
    """[H, W] smooth random field in [-amplitude, amplitude] (a 4x4 grid upsampled bicubically)."""
    coarse = rng.uniform(-1.0, 1.0, (4, 4)).astype(np.float32)
    f = cv2.resize(coarse, (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)
    return amplitude * f / max(float(np.abs(f).max()), 1e-6)


def _shift_outlines(masks: np.ndarray, pixels: int, grow: bool) -> np.ndarray:
    """[H, W] instance masks with every outline moved by `pixels`: each label (-1, nothing, counts
    as one) dilated in turn, larger labels first when `grow` (so objects grow into the ground and
    the sky around them), smaller first otherwise (the ground and the sky eat into the objects)."""
    labels, areas = np.unique(masks, return_counts=True)
    order = labels[np.argsort(-areas, kind="stable")]
    out = masks.copy()
    k = np.ones((3, 3), np.uint8)
    for lab in (order if grow else order[::-1]):
        out[cv2.dilate((masks == lab).astype(np.uint8), k, iterations=pixels).astype(bool)] = lab
    return out


def corrupt_priors(clip: GeneratedClip, seed: int = 0, depth_field: float = 0.10, depth_noise: float = 0.01,
                   mask_pixels: int = 2, mask_drop: float = 0.05, track_noise: float = 1.0,
                   track_drop: float = 0.10) -> GeneratedClip:
    """A copy of a clip carrying all three priors with realistic errors: depth times a smooth
    +-`depth_field` field and `depth_noise` relative noise; each frame's objects grown or shrunk
    (half the frames each) by 1..`mask_pixels` px (`_shift_outlines`), `mask_drop` of the frames'
    masks dropped (all -1, nothing); tracks plus `track_noise` px Gaussian noise with `track_drop`
    of the observations invisible.
    `info["priors"]` says "corrupted"."""
    for name, value in (("depth_field", depth_field), ("depth_noise", depth_noise), ("mask_pixels", mask_pixels),
                        ("mask_drop", mask_drop), ("track_noise", track_noise), ("track_drop", track_drop)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"Expected {name} >= 0, found {value!r}")
    missing = [n for n in ("depth", "masks", "tracks") if getattr(clip, n) is None]
    if missing:
        raise ValueError(f"Expected a clip carrying depth, masks and tracks to corrupt, missing {missing}")
    rng = np.random.default_rng([int(seed), 11])
    t, h, w = clip.depth.shape
    depth = clip.depth * (1.0 + _smooth_field(rng, (h, w), depth_field))[None]
    depth = depth * (1.0 + depth_noise * rng.standard_normal(depth.shape))
    depth = np.where(clip.depth > 0, depth, 0.0).astype(np.float32)
    masks = clip.masks.copy()
    for i in range(t):
        if rng.random() < mask_drop:
            masks[i] = -1
            continue
        if mask_pixels <= 0:
            continue                    # no border error asked for
        n = int(rng.integers(1, mask_pixels + 1))
        masks[i] = _shift_outlines(clip.masks[i], n, grow=bool(rng.random() < 0.5))
    tracks = (clip.tracks + track_noise * rng.standard_normal(clip.tracks.shape)).astype(np.float32)
    visible = clip.track_visible & (rng.random(clip.track_visible.shape) >= track_drop)
    info = {**clip.info, "priors": {"depth": "corrupted", "masks": "corrupted", "tracks": "corrupted"}}
    return replace(clip, depth=depth, masks=masks, tracks=tracks, track_visible=visible, info=info)
