"""Compiled sky compositing: `scene.sky.composite_sky` as three numba passes over the pixels.

The numpy version builds index, ray and colour arrays for every uncovered pixel with a dozen
temporaries each. Here one compiled pass lists the uncovered pixels and their ray directions
(float64, rounded to float32, as `sky_rays` gives them), a second turns the list into
texel coordinates with a float32 `atan2` written out as a polynomial (`_atan2f`: no libm call, so
the loop runs in SIMD lanes; within 3e-7 rad of the exact angle, as close as numpy's float32
`arctan2`; the elevation is `atan2(z, hypot(x, y))`, equal to `sky_colors`' `arcsin` of the unit
ray), and a third adds the bilinear colours. The result agrees with `composite_sky` to float32
rounding (tests/render/test_sky_kernel.py). The kernels compile with the renderer's options
(`_jit.jit`: FMA contraction allowed), so the sky composited inside a view's compiled render
(`claimed.ClaimedBatch`) and after one (`composite_sky_compiled`: `render`, `render_batch`)
gives the same bits. Compiled without contraction they did not: inlined into the renderer's
contraction-enabled kernel they gave other last bits on a third of the sky pixels than called
on their own (tests/render/test_claimed.py holds the two paths equal).
"""

from __future__ import annotations

import math
from typing import Sequence

import numba
import numpy as np

from ...scene.camera import Camera
from ...scene.sky import SKY_VISIBLE_BELOW
from ._jit import jit

__all__ = ["composite_sky_compiled", "composite_view", "sky_camera", "atan2_f32"]

_F = np.float32
_VISIBLE_BELOW = np.float32(SKY_VISIBLE_BELOW)
_INV_2PI = np.float32(1 / (2 * np.pi))
_INV_PI = np.float32(1 / np.pi)
_PI, _HALF_PI, _QUARTER_PI = np.float32(np.pi), np.float32(np.pi / 2), np.float32(np.pi / 4)
_TAN_PI_8 = np.float32(np.tan(np.pi / 8))
_CHUNK_PIXELS = 1024       # pixels `composite_view` lists at a time (its scratch: 28 bytes each)
# atan(r) = r + r z (A1 + A2 z + A3 z^2 + A4 z^3), z = r^2, |r| <= tan(pi / 8): a least-squares fit
# of the relative error on 20,000 Chebyshev nodes (max relative error 2.1e-8, under float32's 6e-8)
_A1, _A2, _A3, _A4 = np.float32(-0.33332938), np.float32(0.1997736), np.float32(-0.13874442), np.float32(0.08044441)


@numba.njit(cache=True, nogil=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _atan2f(y, x):      # pragma: no cover - compiled
    """atan2(y, x) in float32 without a libm call: the ratio of the smaller to the larger
    magnitude in [0, 1], folded to |r| <= tan(pi / 8) about 1, the polynomial, then the octant."""
    ax, ay = abs(x), abs(y)
    hi, lo = max(ax, ay), min(ax, ay)
    t = lo / hi if hi > _F(0) else _F(0)
    folded = t > _TAN_PI_8
    r = (t - _F(1)) / (t + _F(1)) if folded else t
    z = r * r
    a = r + r * z * (_A1 + z * (_A2 + z * (_A3 + z * _A4)))
    if folded:
        a = a + _QUARTER_PI
    if ay > ax:
        a = _HALF_PI - a
    if x < _F(0):
        a = _PI - a
    return -a if y < _F(0) else a


@jit
def atan2_f32(y, x, out):      # pragma: no cover - compiled
    """out[i] = `_atan2f`(y[i], x[i]) (float32 arrays): the kernel's angle, for tests."""
    for i in range(y.shape[0]):
        out[i] = _atan2f(y[i], x[i])


@jit
def _uncovered_rays(alpha, r0, r1, R, fx, fy, cx, cy, pix, dx, dy, dz):      # pragma: no cover - compiled
    """Pixels of rows r0..r1 - 1 (row-major index into `pix`) with alpha < SKY_VISIBLE_BELOW and
    their world ray directions (float32, not normalised: the angles do not need it); returns how
    many."""
    wid = alpha.shape[1]
    k = 0
    for r in range(r0, r1):
        y = (r + 0.5 - cy) / fy
        for c in range(wid):
            if not alpha[r, c] < _VISIBLE_BELOW:
                continue
            x = (c + 0.5 - cx) / fx
            dx[k] = _F(x * R[0, 0] + y * R[1, 0] + R[2, 0])
            dy[k] = _F(x * R[0, 1] + y * R[1, 1] + R[2, 1])
            dz[k] = _F(x * R[0, 2] + y * R[1, 2] + R[2, 2])
            pix[k] = r * wid + c
            k += 1
    return k


@jit
def _texel_uv(dx, dy, dz, k, sh, sw, u, v):      # pragma: no cover - compiled
    """`scene.sky.texel_coords` of the first k directions (separate x, y, z arrays, so the loop
    vectorises): azimuth from atan2(y, x), elevation from atan2(z, hypot(x, y)); v clipped."""
    wf, hf, top = _F(sw), _F(sh), _F(sh - 1)
    for i in range(k):
        x, y, z = dx[i], dy[i], dz[i]
        u[i] = (_F(0.5) - _atan2f(y, x) * _INV_2PI) * wf - _F(0.5)
        e = (_F(0.5) - _atan2f(z, _F(math.sqrt(x * x + y * y))) * _INV_PI) * hf - _F(0.5)
        v[i] = min(max(e, _F(0)), top)


@jit
def _add_sky(out, alpha, image, pix, k, u, v):      # pragma: no cover - compiled
    """out[p] += (1 - alpha[p]) x the bilinear sky colour at (u, v) for the first k listed pixels
    p (out [H * W, 3], alpha [H * W]; u, v: float32 texel coordinates, v already clipped; u wraps
    around the panorama)."""
    sh, sw = image.shape[0], image.shape[1]
    one = _F(1.0)
    for i in range(k):
        p = pix[i]
        u0f = _F(math.floor(u[i]))
        v0f = _F(math.floor(v[i]))
        fu = u[i] - u0f
        fv = v[i] - v0f
        u0 = int(u0f)
        if u0 < 0:            # u lies in [-0.5, sw - 0.5]: one wrap at most
            u0 += sw
        elif u0 >= sw:
            u0 -= sw
        u1 = u0 + 1 if u0 + 1 < sw else 0
        v0 = int(v0f)
        v1 = min(v0 + 1, sh - 1)
        w = one - alpha[p]
        for ch in range(3):
            top = image[v0, u0, ch] * (one - fu) + image[v0, u1, ch] * fu
            bottom = image[v1, u0, ch] * (one - fu) + image[v1, u1, ch] * fu
            out[p, ch] += w * (top * (one - fv) + bottom * fv)


@jit
def composite_view(rgb, alpha, image, R, fx, fy, cx, cy):      # pragma: no cover - compiled
    """One view's sky, in place: rgb [H, W, 3] (float32, rendered on black) += (1 - alpha) x the
    sky image [H', W', 3] along each pixel's ray, where alpha [H, W] < SKY_VISIBLE_BELOW; R: the
    camera's world-to-camera rotation (float64 [3, 3]), fx, fy, cx, cy its intrinsics. Compiled
    renders call it on their own threads (`claimed.ClaimedBatch`), the others through
    `composite_sky_compiled`: one arithmetic, so every path gives the same bits."""
    hgt, wid = alpha.shape[0], alpha.shape[1]
    n = hgt * wid
    rows = max(1, _CHUNK_PIXELS // max(wid, 1))   # a few rows at a time: scratch of ~30 KB, not ~7x a view
    pix = np.empty(rows * wid, np.int64)
    d = np.empty((5, rows * wid), np.float32)     # ray x, y, z, then texel u, v
    flat_rgb, flat_alpha = rgb.reshape((n, 3)), alpha.reshape(n)
    for r0 in range(0, hgt, rows):
        k = _uncovered_rays(alpha, r0, min(r0 + rows, hgt), R, fx, fy, cx, cy, pix, d[0], d[1], d[2])
        if k:
            _texel_uv(d[0], d[1], d[2], k, image.shape[0], image.shape[1], d[3], d[4])
            _add_sky(flat_rgb, flat_alpha, image, pix, k, d[3], d[4])


def sky_camera(camera: Camera) -> tuple[np.ndarray, float, float, float, float]:
    """`composite_view`'s camera arguments: the world-to-camera rotation (float64 [3, 3], C order)
    and fx, fy, cx, cy."""
    K = camera.K
    R = np.ascontiguousarray(np.asarray(camera.world_to_camera, dtype=np.float64)[:3, :3])
    return R, float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2])


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
        composite_view(out[c], a32[c], sky, *sky_camera(camera))
    return out.astype(rgb.dtype, copy=False)
