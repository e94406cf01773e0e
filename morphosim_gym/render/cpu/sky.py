"""Compiled sky compositing: `scene.sky.composite_sky` as one numba loop over the pixels.

The numpy version builds index, ray and colour arrays for every uncovered pixel with a dozen
temporaries each (~40 % of an 84 px env step's render on sky-heavy views). Here one compiled
pass lists the uncovered pixels and their unit rays (the same arithmetic in the same precision:
rays in float64, then float32, no FMA contraction), numpy's vectorised float32 `arctan2` /
`arcsin` turn them into texel coordinates exactly as `sky_colors` does (numba's scalar libm
calls would differ by an ulp and cost ~10 ns each), and a second pass adds the bilinear colours.
The result equals `composite_sky` (up to the last bit of the float64 ray product, which BLAS may
fuse; tests/render/test_sky_kernel.py). Every renderer (`render`, `render_batch`) uses it, so
single and batched renders stay bit-identical to each other.
"""

from __future__ import annotations

import math
from typing import Sequence

import numba
import numpy as np

from ...scene.camera import Camera
from ...scene.sky import SKY_VISIBLE_BELOW

__all__ = ["composite_sky_compiled"]

_F = np.float32
_VISIBLE_BELOW = np.float32(SKY_VISIBLE_BELOW)
_INV_2PI = np.float32(1 / (2 * np.pi))
_INV_PI = np.float32(1 / np.pi)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _uncovered_rays(alpha, R, fx, fy, cx, cy, pix, d):      # pragma: no cover - compiled
    """Pixels (row-major index into `pix`) with alpha < SKY_VISIBLE_BELOW and their unit ray
    directions (float32 into `d`), as `sky_rays` and `sky_colors`' normalisation compute them;
    returns how many."""
    hgt, wid = alpha.shape[0], alpha.shape[1]
    k = 0
    for r in range(hgt):
        y = (r + 0.5 - cy) / fy
        for c in range(wid):
            if not alpha[r, c] < _VISIBLE_BELOW:
                continue
            x = (c + 0.5 - cx) / fx
            dx = _F(x * R[0, 0] + y * R[1, 0] + R[2, 0])
            dy = _F(x * R[0, 1] + y * R[1, 1] + R[2, 1])
            dz = _F(x * R[0, 2] + y * R[1, 2] + R[2, 2])
            nrm = max(_F(math.sqrt(dx * dx + dy * dy + dz * dz)), _F(1e-12))
            d[k, 0] = dx / nrm
            d[k, 1] = dy / nrm
            d[k, 2] = dz / nrm
            pix[k] = r * wid + c
            k += 1
    return k


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _add_sky(out, alpha, image, pix, u, v):      # pragma: no cover - compiled
    """out[p] += (1 - alpha[p]) x the bilinear sky colour at (u, v) for each listed pixel p
    (out [H * W, 3], alpha [H * W]; u, v: float32 texel coordinates, v already clipped)."""
    sh, sw = image.shape[0], image.shape[1]
    one = _F(1.0)
    for k in range(pix.shape[0]):
        p = pix[k]
        u0f = _F(math.floor(u[k]))
        v0f = _F(math.floor(v[k]))
        fu = u[k] - u0f
        fv = v[k] - v0f
        u0 = np.int64(u0f) % sw
        u1 = (u0 + 1) % sw
        v0 = np.int64(v0f)
        v1 = min(v0 + 1, sh - 1)
        w = one - alpha[p]
        for ch in range(3):
            top = image[v0, u0, ch] * (one - fu) + image[v0, u1, ch] * fu
            bottom = image[v1, u0, ch] * (one - fu) + image[v1, u1, ch] * fu
            out[p, ch] += w * (top * (one - fv) + bottom * fv)


def _texel_coords(d: np.ndarray, h: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    """`sky_colors`' texel coordinates (u, v) of unit directions [k, 3] (numpy's float32 atan2 /
    asin, vectorised)."""
    u = (np.float32(0.5) - np.arctan2(d[:, 1], d[:, 0]) * _INV_2PI) * w - np.float32(0.5)
    v = np.clip((np.float32(0.5) - np.arcsin(np.clip(d[:, 2], -1, 1)) * _INV_PI) * h - np.float32(0.5), 0, h - 1)
    return np.ascontiguousarray(u, np.float32), np.ascontiguousarray(v, np.float32)


def composite_sky_compiled(rgb: np.ndarray, alpha: np.ndarray, image: np.ndarray,
                           cameras: Sequence[Camera]) -> np.ndarray:
    """`scene.sky.composite_sky` (renders on black [C, H, W, 3] with the sky behind what the
    Gaussians leave uncovered), compiled; a fresh array of `rgb`'s dtype."""
    rgb = np.asarray(rgb)
    if rgb.ndim != 4 or rgb.shape[0] != len(cameras) or alpha.shape != rgb.shape[:3]:
        raise ValueError(f"Expected rgb [C, H, W, 3] and alpha [C, H, W] for {len(cameras)} cameras, "
                         f"found {rgb.shape} and {alpha.shape}")
    out = np.array(rgb, dtype=np.float32, copy=True)
    sky = np.ascontiguousarray(image, dtype=np.float32)
    a32 = np.ascontiguousarray(alpha, dtype=np.float32)
    hw = rgb.shape[1] * rgb.shape[2]
    pix = np.empty(hw, np.int64)
    d = np.empty((hw, 3), np.float32)
    for c, camera in enumerate(cameras):
        K = camera.K
        R = np.ascontiguousarray(np.asarray(camera.world_to_camera, dtype=np.float64)[:3, :3])
        k = _uncovered_rays(a32[c], R, float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), pix, d)
        if k:
            u, v = _texel_coords(d[:k], sky.shape[0], sky.shape[1])
            _add_sky(out[c].reshape(hw, 3), a32[c].reshape(hw), sky, pix[:k], u, v)
    return out.astype(rgb.dtype, copy=False)
