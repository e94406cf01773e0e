"""Projection of 3D Gaussians into one camera (EWA splatting), forward and backward.

Kernel twin of `morphosim_gym.render.reference.project_torch`: same culling (camera z <= near,
opacity < 1/255, non-positive or non-finite 2D determinant), same Jacobian clamp at 1.3x the
field of view, +0.3 blur on the 2D covariance diagonal and the same opacity-aware extent.

Each Gaussian becomes one record row (see `_jit.R_*` for the layout) and a tile rectangle;
the forward pass also counts, per thread, how many Gaussians touch each 16x16 tile, which is
the first half of binning (`binning.py`).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ._jit import (ALPHA_MIN, BLUR, EXTENT_MARGIN, FOV_CLAMP, R_B, R_CA, R_CB, R_CC, R_EX, R_EY, R_G, R_MX, R_MY,
                   R_OP, R_R, R_X0, R_X1, R_Y0, R_Y1, R_Z, jit, pjit, splat_log)

__all__ = ["project_forward", "project_backward"]

_BLOCK = 512  # Gaussians projected before their tile counts are taken (keeps the block in L1)


@jit
def _project_block(lo, hi,
                   means,       # [N, 3]
                   quats,       # [N, 4]
                   scales,      # [N, 3]
                   opacities,   # [N]
                   colors,      # [N, 3]
                   viewmat,     # [4, 4]
                   K,           # [3, 3]
                   width, height, near,
                   rec,         # [N, 16] out
                   trect):      # [4, N] int32 out: tile x0, x1, y0, y1 inclusive (x1 = -1 when culled)
    F = rec.dtype.type
    fx = K[0, 0]
    fy = K[1, 1]
    cx = K[0, 2]
    cy = K[1, 2]
    r00, r01, r02, t0 = viewmat[0, 0], viewmat[0, 1], viewmat[0, 2], viewmat[0, 3]
    r10, r11, r12, t1 = viewmat[1, 0], viewmat[1, 1], viewmat[1, 2], viewmat[1, 3]
    r20, r21, r22, t2 = viewmat[2, 0], viewmat[2, 1], viewmat[2, 2], viewmat[2, 3]
    Wf = F(width)
    Hf = F(height)
    clampm = F(FOV_CLAMP - 1.0)
    tan_fovx = F(0.5) * Wf / fx
    tan_fovy = F(0.5) * Hf / fy
    lim_x_pos = (Wf - cx) / fx + clampm * tan_fovx
    lim_x_neg = cx / fx + clampm * tan_fovx
    lim_y_pos = (Hf - cy) / fy + clampm * tan_fovy
    lim_y_neg = cy / fy + clampm * tan_fovy
    one = F(1.0)
    zero = F(0.0)
    half = F(0.5)
    blur = F(BLUR)
    amin = F(ALPHA_MIN)
    margin = F(EXTENT_MARGIN)
    inf = F(np.inf)
    for i in range(lo, hi):
        # camera space
        m0 = means[i, 0]
        m1 = means[i, 1]
        m2 = means[i, 2]
        x = r00 * m0 + r01 * m1 + r02 * m2 + t0
        y = r10 * m0 + r11 * m1 + r12 * m2 + t1
        z = r20 * m0 + r21 * m1 + r22 * m2 + t2
        zok = z > near
        zs = z if zok else one
        # rotation of the normalised quaternion, times the scales (M = R S)
        qw = quats[i, 0]
        qx = quats[i, 1]
        qy = quats[i, 2]
        qz = quats[i, 3]
        qn = one / np.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
        qw *= qn
        qx *= qn
        qy *= qn
        qz *= qn
        s0 = scales[i, 0]
        s1 = scales[i, 1]
        s2 = scales[i, 2]
        m00 = (one - F(2.0) * (qy * qy + qz * qz)) * s0
        m01 = F(2.0) * (qx * qy - qw * qz) * s1
        m02 = F(2.0) * (qx * qz + qw * qy) * s2
        m10 = F(2.0) * (qx * qy + qw * qz) * s0
        m11 = (one - F(2.0) * (qx * qx + qz * qz)) * s1
        m12 = F(2.0) * (qy * qz - qw * qx) * s2
        m20 = F(2.0) * (qx * qz - qw * qy) * s0
        m21 = F(2.0) * (qy * qz + qw * qx) * s1
        m22 = (one - F(2.0) * (qx * qx + qy * qy)) * s2
        # W = R_cam M, so cov_cam = W W^T
        w00 = r00 * m00 + r01 * m10 + r02 * m20
        w01 = r00 * m01 + r01 * m11 + r02 * m21
        w02 = r00 * m02 + r01 * m12 + r02 * m22
        w10 = r10 * m00 + r11 * m10 + r12 * m20
        w11 = r10 * m01 + r11 * m11 + r12 * m21
        w12 = r10 * m02 + r11 * m12 + r12 * m22
        w20 = r20 * m00 + r21 * m10 + r22 * m20
        w21 = r20 * m01 + r21 * m11 + r22 * m21
        w22 = r20 * m02 + r21 * m12 + r22 * m22
        # EWA Jacobian at the clamped direction
        iz = one / zs
        u = min(max(x * iz, -lim_x_neg), lim_x_pos)
        v = min(max(y * iz, -lim_y_neg), lim_y_pos)
        j00 = fx * iz
        j02 = -fx * u * iz
        j11 = fy * iz
        j12 = -fy * v * iz
        a0 = j00 * w00 + j02 * w20
        a1 = j00 * w01 + j02 * w21
        a2 = j00 * w02 + j02 * w22
        b0 = j11 * w10 + j12 * w20
        b1 = j11 * w11 + j12 * w21
        b2 = j11 * w12 + j12 * w22
        ca = a0 * a0 + a1 * a1 + a2 * a2 + blur
        cb = a0 * b0 + a1 * b1 + a2 * b2
        cc = b0 * b0 + b1 * b1 + b2 * b2 + blur
        det = ca * cc - cb * cb
        idet = one / det
        mx = fx * x * iz + cx
        my = fy * y * iz + cy
        op = opacities[i]
        level = F(2.0) * splat_log(max(F(255.0) * op, one))
        ex = np.sqrt(level * ca) + margin
        ey = np.sqrt(level * cc) + margin
        ica = cc * idet
        icb = -cb * idet
        icc = ca * idet
        # culled: behind the near plane, too transparent, degenerate or non-finite footprint
        # (NaN fails every comparison, so it is culled too)
        ok = zok & (op >= amin) & (det > zero) & (abs(ica) < inf) & (abs(icb) < inf) & (abs(icc) < inf)
        ok = ok & (mx == mx) & (my == my) & (ex == ex) & (ey == ey)
        # inclusive pixel box: pixel j is drawn when its centre j + 0.5 lies in [mx - ex, mx + ex]
        bx0 = min(max(np.ceil(mx - ex - half), zero), Wf)
        bx1 = max(min(np.floor(mx + ex - half), Wf - one), -one)
        by0 = min(max(np.ceil(my - ey - half), zero), Hf)
        by1 = max(min(np.floor(my + ey - half), Hf - one), -one)
        ok = ok & (bx0 <= bx1) & (by0 <= by1)
        bx0 = bx0 if ok else zero
        bx1 = bx1 if ok else -one
        by0 = by0 if ok else zero
        by1 = by1 if ok else -one
        rec[i, R_MX] = mx
        rec[i, R_MY] = my
        rec[i, R_CA] = ica
        rec[i, R_CB] = icb
        rec[i, R_CC] = icc
        rec[i, R_OP] = op
        rec[i, R_Z] = z
        rec[i, R_R] = colors[i, 0]
        rec[i, R_G] = colors[i, 1]
        rec[i, R_B] = colors[i, 2]
        rec[i, R_EX] = ex
        rec[i, R_EY] = ey
        rec[i, R_X0] = bx0
        rec[i, R_X1] = bx1
        rec[i, R_Y0] = by0
        rec[i, R_Y1] = by1
        # tile rectangle (inclusive); culled Gaussians get x1 = -1 < x0 = 0
        trect[0, i] = np.int32(bx0) >> np.int32(4)
        trect[1, i] = np.int32(bx1) >> np.int32(4)
        trect[2, i] = np.int32(by0) >> np.int32(4)
        trect[3, i] = np.int32(by1) >> np.int32(4)


@jit
def _count_block(lo, hi, trect, tiles_x, counts):
    for i in range(lo, hi):
        tx0 = trect[0, i]
        tx1 = trect[1, i]
        ty0 = trect[2, i]
        ty1 = trect[3, i]
        if tx1 < tx0:
            continue
        if tx0 == tx1 and ty0 == ty1:   # single tile: the common case
            counts[ty0 * tiles_x + tx0] += 1
            continue
        for ty in range(ty0, ty1 + 1):
            for tx in range(tx0, tx1 + 1):
                counts[ty * tiles_x + tx] += 1


@jit
def _project_range(lo, hi, means, quats, scales, opacities, colors, viewmat, K, width, height, near,
                   rec, trect, tiles_x, counts):
    counts[:] = 0
    for b in range(lo, hi, _BLOCK):
        e = min(b + _BLOCK, hi)
        _project_block(b, e, means, quats, scales, opacities, colors, viewmat, K, width, height, near, rec, trect)
        _count_block(b, e, trect, tiles_x, counts)


@pjit
def project_forward(means,      # [N, 3]
                    quats,      # [N, 4]
                    scales,     # [N, 3]
                    opacities,  # [N]
                    colors,     # [N, 3]
                    viewmat,    # [4, 4]
                    K,          # [3, 3]
                    width, height, near,
                    rec,        # [N, 16] out
                    trect,      # [4, N] int32 out
                    tiles_x,
                    counts):    # [n_threads, n_tiles] int32 out
    """Project all Gaussians into one camera, in `counts.shape[0]` parallel chunks.

    Writes one record per Gaussian into `rec` [N, 16] (layout `_jit.R_*`), its inclusive tile
    rectangle into `trect` [4, N] (tx0, tx1, ty0, ty1; tx1 = -1 when culled) and, per
    chunk, the number of Gaussians touching each tile into `counts` [n_threads, n_tiles].
    """
    n = means.shape[0]
    nthr = counts.shape[0]
    for t in prange(nthr):
        _project_range(n * t // nthr, n * (t + 1) // nthr, means, quats, scales, opacities, colors, viewmat, K,
                       width, height, near, rec, trect, tiles_x, counts[t])
