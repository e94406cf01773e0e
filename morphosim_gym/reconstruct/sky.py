"""The sky of a fitted scene: an equirectangular image (`scene.sky`) made from the pixels that the
clip's priors leave empty (no depth and no instance: nothing drawn there).

A generated clip draws its setting's sky (an HDR panorama) behind everything; a real video shows
whatever lies far beyond the action. Gaussians cannot stand in for it: they sit at some finite
depth, and a novel view turned away from the input views finds the space beside them empty. As a
sky, the same pixels are seen along every camera ray at infinity, in input views, novel views
and the envs alike.

Each empty pixel's colour is splatted (bilinear weights, the adjoint of `scene.sky.sky_colors`'s
lookup) onto the panorama along its ray (`scene.sky.texel_coords`), averaged per texel, and texels no ray reached are
filled from the seen ones by pull-push (a coarse-to-fine average: the sky beside what was seen
continues its colours). The panorama's angular resolution is twice the finest camera's, so that
looking it up again blurs the input views by little.
"""

from __future__ import annotations

from typing import Sequence

import cv2
import numpy as np

from ..scene import GeneratedClip
from ..scene.camera import Camera
from ..scene.sky import check_sky, sky_rays, texel_coords

__all__ = ["empty_pixels", "estimate_sky", "sky_from_clip", "pull_push", "MIN_SKY_PIXELS"]

#: A clip with fewer empty pixels than this (over all frames) gets no sky: too little to go on.
MIN_SKY_PIXELS = 64
_MAX_WIDTH = 2048


def empty_pixels(clip: GeneratedClip) -> np.ndarray | None:
    """[T, H, W] bool: pixels with no depth and no instance in the clip's priors (None without a
    depth prior)."""
    if clip.depth is None:
        return None
    empty = np.asarray(clip.depth) <= 0
    if clip.masks is not None:
        empty &= np.asarray(clip.masks) < 0
    return empty


def sky_from_clip(clip: GeneratedClip, oversample: float = 2.0) -> np.ndarray | None:
    """The clip's sky (`estimate_sky` over its `empty_pixels`), or None where fewer than
    `MIN_SKY_PIXELS` pixels are empty."""
    empty = empty_pixels(clip)
    if empty is None or int(empty.sum()) < MIN_SKY_PIXELS:
        return None
    return estimate_sky(clip.frames, clip.cameras, empty, oversample)


def estimate_sky(frames: np.ndarray, cameras: Sequence[Camera], mask: np.ndarray, oversample: float = 2.0
                 ) -> np.ndarray:
    """An equirectangular sky [h, 2h, 3] float32 in [0, 1] from the `mask`ed pixels [T, H, W] of
    `frames` [T, H, W, 3] (uint8 or float in [0, 1]) seen by `cameras` (one per frame).
    `ValueError` naming the problem for mismatched shapes or a mask with no pixel."""
    frames = np.asarray(frames)
    mask = np.asarray(mask, bool)
    if frames.ndim != 4 or frames.shape[-1] != 3:
        raise ValueError(f"Expected frames [T, H, W, 3], found {frames.shape}")
    if mask.shape != frames.shape[:3]:
        raise ValueError(f"Expected a sky mask of shape {frames.shape[:3]}, found {mask.shape}")
    if len(cameras) != len(frames):
        raise ValueError(f"Expected one camera per frame ({len(frames)}), found {len(cameras)}")
    if not mask.any():
        raise ValueError("Expected some sky pixels to estimate a sky from, found none")
    scale = 1.0 / 255.0 if frames.dtype == np.uint8 else 1.0
    fx = max(float(c.K[0, 0]) for c in cameras)
    w = int(min(_MAX_WIDTH, max(16, 2 * round(oversample * np.pi * fx))))
    h = w // 2
    acc = np.zeros((h * w, 3))
    wsum = np.zeros(h * w)
    for t, cam in enumerate(cameras):
        rows, cols = np.nonzero(mask[t])
        if not len(rows):
            continue
        u, v = texel_coords(sky_rays(cam, rows, cols), w, h)
        colour = frames[t][rows, cols].astype(np.float64) * scale
        u0, v0 = np.floor(u), np.floor(v)
        fu, fv = u - u0, v - v0
        u0 = u0.astype(np.int64) % w
        v0 = v0.astype(np.int64)
        for du, dv, wt in ((0, 0, (1 - fu) * (1 - fv)), (1, 0, fu * (1 - fv)), (0, 1, (1 - fu) * fv),
                           (1, 1, fu * fv)):
            idx = np.minimum(v0 + dv, h - 1) * w + (u0 + du) % w
            np.add.at(wsum, idx, wt)
            for c in range(3):
                np.add.at(acc[:, c], idx, wt * colour[:, c])
    sky = pull_push(acc.reshape(h, w, 3), wsum.reshape(h, w))
    return check_sky(np.clip(sky, 0.0, 1.0).astype(np.float32))


def pull_push(weighted: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Fill a sparse image: `weighted` [h, w, c] holds sums of weight x colour, `weight` [h, w] the
    sums of weights. Where a texel's weight reaches 1 it keeps its average; below, it is blended
    with the (recursively filled) image at half the resolution. -> [h, w, c]"""
    h, w = weight.shape
    if h <= 1 and w <= 1:
        return weighted / max(float(weight.reshape(-1)[0]), 1e-12)
    # pull: sums over 2x2 blocks (edge-padded to even sizes)
    ph, pw = h + h % 2, w + w % 2
    wt = np.zeros((ph, pw))
    acc = np.zeros((ph, pw, weighted.shape[2]))
    wt[:h, :w], acc[:h, :w] = weight, weighted
    coarse_w = wt.reshape(ph // 2, 2, pw // 2, 2).sum(axis=(1, 3))
    coarse_acc = acc.reshape(ph // 2, 2, pw // 2, 2, -1).sum(axis=(1, 3))
    # a coarse texel counts as fully seen once its weight reaches 1 (as at the fine level)
    k = np.minimum(coarse_w, 1.0) / np.maximum(coarse_w, 1e-12)
    coarse = pull_push(coarse_acc * k[..., None], coarse_w * k)
    # push: the coarse image upsampled, under what this level saw
    up = cv2.resize(coarse, (pw, ph), interpolation=cv2.INTER_LINEAR)[:h, :w]
    up = up.reshape(h, w, -1)
    a = np.minimum(weight, 1.0)[..., None]
    mean = weighted / np.maximum(weight, 1e-12)[..., None]
    return a * mean + (1 - a) * up
