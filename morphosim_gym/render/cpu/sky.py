"""Compiled sky compositing: `scene.sky.composite_sky` as one numba loop over the pixels.

The numpy version builds index, ray and colour arrays for every uncovered pixel (~40 % of an
84 px env step's render on sky-heavy views); this kernel walks the pixels once with the same
arithmetic in the same precision (rays in float64, the lookup in float32, no FMA contraction).
The only difference is the float32 `atan2` / `asin`, which numpy may take from its SIMD library
and numba from libm: colours agree to a few float32 ulps (tests/render/test_sky_kernel.py), far
below a uint8 step. Every renderer (`render`, `render_batch`) uses this one kernel, so single
and batched renders stay bit-identical to each other.
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
def _composite(out, alpha, image, R, fx, fy, cx, cy):      # pragma: no cover - compiled
    """Add (1 - alpha) x sky colour to `out` [H, W, 3] (in place) where alpha < SKY_VISIBLE_BELOW;
    R: world_to_camera[:3, :3] (float64), fx, fy, cx, cy: intrinsics (float64)."""
    hgt, wid = out.shape[0], out.shape[1]
    sh, sw = image.shape[0], image.shape[1]
    one, half, zero = _F(1.0), _F(0.5), _F(0.0)
    for r in range(hgt):
        y = (r + 0.5 - cy) / fy
        for c in range(wid):
            a = alpha[r, c]
            if not a < _VISIBLE_BELOW:
                continue
            x = (c + 0.5 - cx) / fx
            dx = _F(x * R[0, 0] + y * R[1, 0] + R[2, 0])
            dy = _F(x * R[0, 1] + y * R[1, 1] + R[2, 1])
            dz = _F(x * R[0, 2] + y * R[1, 2] + R[2, 2])
            nrm = _F(math.sqrt(dx * dx + dy * dy + dz * dz))
            nrm = max(nrm, _F(1e-12))
            dx, dy, dz = dx / nrm, dy / nrm, dz / nrm
            u = (half - _F(math.atan2(dy, dx)) * _INV_2PI) * _F(sw) - half
            v = (half - _F(math.asin(min(max(dz, _F(-1.0)), one))) * _INV_PI) * _F(sh) - half
            v = min(max(v, zero), _F(sh - 1))
            u0f, v0f = _F(math.floor(u)), _F(math.floor(v))
            fu, fv = u - u0f, v - v0f
            u0 = np.int64(u0f)          # in [-1, sw - 1]: `% sw` without a division
            if u0 < 0:
                u0 += sw
            u1 = u0 + 1 if u0 + 1 < sw else 0
            v0 = np.int64(v0f)
            v1 = min(v0 + 1, sh - 1)
            w = one - a
            for k in range(3):
                top = image[v0, u0, k] * (one - fu) + image[v0, u1, k] * fu
                bottom = image[v1, u0, k] * (one - fu) + image[v1, u1, k] * fu
                out[r, c, k] += w * (top * (one - fv) + bottom * fv)


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
    for c, camera in enumerate(cameras):
        K = camera.K
        R = np.ascontiguousarray(np.asarray(camera.world_to_camera, dtype=np.float64)[:3, :3])
        _composite(out[c], a32[c], sky, R, float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]))
    return out.astype(rgb.dtype, copy=False)
