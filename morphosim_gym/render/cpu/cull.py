"""Object-level frustum culling for the batched forward pass: skip whole runs of Gaussians that
cannot draw a pixel, before any per-Gaussian projection or binning work.

A view's Gaussians are cut into chunks (runs of one object id, at most `CHUNK` long); each
chunk gets a bounding sphere of its centres plus its largest scale and opacity. A chunk is
dropped when the sphere lies behind the near plane, or beyond one side of the image by more
than the largest pixel extent any of its Gaussians could have there. That bound follows the
projection's own formulas (`projection._project_soa`): the extent is sqrt(level * ca) + margin
with level = 2 log(255 o) <= 2 log(255 o_max) and ca = |J_0 W|^2 + blur <= (f / z)^2
(1 + U^2) s_max^2 + blur, where |u| <= U is the Jacobian clamp and z >= max(near, z_c - r);
one more pixel absorbs float32 rounding. Every dropped Gaussian would have been culled by the
projection (an empty pixel box), so images are bit-identical with and without culling.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import BLUR, EXTENT_MARGIN, FOV_CLAMP, jit

__all__ = ["CHUNK", "cull_view"]

CHUNK = 1024
_SAFETY_PX = 1.0


@jit
def _chunk_visible(means, scales, opac, lo, hi, viewmat, K, width, height, near) -> bool:
    """Whether any Gaussian of means[lo:hi] may draw a pixel of this view (conservative)."""
    x0 = y0 = z0 = np.inf
    x1 = y1 = z1 = -np.inf
    smax = 0.0
    omax = 0.0
    for i in range(lo, hi):
        mx = np.float64(means[i, 0])
        my = np.float64(means[i, 1])
        mz = np.float64(means[i, 2])
        x0, x1 = min(x0, mx), max(x1, mx)
        y0, y1 = min(y0, my), max(y1, my)
        z0, z1 = min(z0, mz), max(z1, mz)
        smax = max(smax, np.float64(scales[i, 0]), np.float64(scales[i, 1]), np.float64(scales[i, 2]))
        omax = max(omax, np.float64(opac[i]))
    if not (math.isfinite(x1 - x0) and math.isfinite(y1 - y0) and math.isfinite(z1 - z0)
            and math.isfinite(smax) and math.isfinite(omax)):
        return True
    cx_, cy_, cz_ = 0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)
    r = 0.5 * math.sqrt((x1 - x0) ** 2 + (y1 - y0) ** 2 + (z1 - z0) ** 2)
    r = r * (1.0 + 1e-5) + 1e-6 * (abs(cx_) + abs(cy_) + abs(cz_) + 1.0)
    # sphere centre in camera space
    xc = viewmat[0, 0] * cx_ + viewmat[0, 1] * cy_ + viewmat[0, 2] * cz_ + viewmat[0, 3]
    yc = viewmat[1, 0] * cx_ + viewmat[1, 1] * cy_ + viewmat[1, 2] * cz_ + viewmat[1, 3]
    zc = viewmat[2, 0] * cx_ + viewmat[2, 1] * cy_ + viewmat[2, 2] * cz_ + viewmat[2, 3]
    if zc + r < near:
        return False
    fx, fy, px, py = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    W = np.float64(width)
    H = np.float64(height)
    clampm = FOV_CLAMP - 1.0
    ux = max((W - px) / fx, px / fx) + clampm * 0.5 * W / fx
    uy = max((H - py) / fy, py / fy) + clampm * 0.5 * H / fy
    zmin = max(near, zc - r)
    level = 2.0 * math.log(max(255.0 * omax, 1.0))
    ex = math.sqrt(level * ((fx / zmin) ** 2 * (1.0 + ux * ux) * smax * smax + BLUR)) + EXTENT_MARGIN + _SAFETY_PX
    ey = math.sqrt(level * ((fy / zmin) ** 2 * (1.0 + uy * uy) * smax * smax + BLUR)) + EXTENT_MARGIN + _SAFETY_PX
    k = (0.5 - px - ex) / fx                      # left of the image: x / z < k everywhere
    if xc - k * zc + r * math.sqrt(1.0 + k * k) < 0.0:
        return False
    k = (W - 0.5 - px + ex) / fx                  # right: x / z > k
    if xc - k * zc - r * math.sqrt(1.0 + k * k) > 0.0:
        return False
    k = (0.5 - py - ey) / fy                      # above
    if yc - k * zc + r * math.sqrt(1.0 + k * k) < 0.0:
        return False
    k = (H - 0.5 - py + ey) / fy                  # below
    if yc - k * zc - r * math.sqrt(1.0 + k * k) > 0.0:
        return False
    return True


@jit
def cull_view(means,     # [N, 3] float32 (all views)
              scales,    # [N, 3]
              opac,      # [N]
              ids,       # [N] int32
              lo, hi,    # this view's range
              viewmat,   # [4, 4] float64
              K,         # [3, 3] float64
              width, height, near,
              keep):     # [>= (hi - lo) // 1 + 1, 2] int64 out: kept ranges (lo, hi), merged
    """Write the ranges of means[lo:hi] that survive culling into `keep`; return how many."""
    n_keep = 0
    i = lo
    while i < hi:
        j = i + 1
        oid = ids[i]
        while j < hi and j - i < CHUNK and ids[j] == oid:
            j += 1
        if _chunk_visible(means, scales, opac, i, j, viewmat, K, width, height, near):
            if n_keep > 0 and keep[n_keep - 1, 1] == i:
                keep[n_keep - 1, 1] = j
            else:
                keep[n_keep, 0] = i
                keep[n_keep, 1] = j
                n_keep += 1
        i = j
    return n_keep
