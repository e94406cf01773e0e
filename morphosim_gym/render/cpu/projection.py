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


# Fields of the per-block scratch (structure of arrays, one flat buffer, constant offsets so
# that LLVM sees a single base pointer and vectorises the projection without alias checks).
_IN_M0, _IN_M1, _IN_M2, _IN_QW, _IN_QX, _IN_QY, _IN_QZ, _IN_S0, _IN_S1, _IN_S2, _IN_OP = range(11)
(_OUT_MX, _OUT_MY, _OUT_CA, _OUT_CB, _OUT_CC, _OUT_Z, _OUT_EX, _OUT_EY,
 _OUT_X0, _OUT_X1, _OUT_Y0, _OUT_Y1) = range(11, 23)
_NFIELD = 23


@jit
def _project_soa(n,
                 buf,       # [_NFIELD * _BLOCK] block scratch: inputs in, outputs out
                 viewmat,   # [4, 4]
                 K,         # [3, 3]
                 width, height, near):
    """Branch-free projection of n <= _BLOCK Gaussians held field by field in `buf`."""
    F = buf.dtype.type
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
    two = F(2.0)
    blur = F(BLUR)
    amin = F(ALPHA_MIN)
    margin = F(EXTENT_MARGIN)
    inf = F(np.inf)
    B = np.uint64(_BLOCK)
    for jj in range(n):
        j = np.uint64(jj)
        # camera space
        m0 = buf[np.uint64(_IN_M0) * B + j]
        m1 = buf[np.uint64(_IN_M1) * B + j]
        m2 = buf[np.uint64(_IN_M2) * B + j]
        x = r00 * m0 + r01 * m1 + r02 * m2 + t0
        y = r10 * m0 + r11 * m1 + r12 * m2 + t1
        z = r20 * m0 + r21 * m1 + r22 * m2 + t2
        zok = z > near
        zs = z if zok else one
        # rotation of the normalised quaternion, times the scales (M = R S)
        qw = buf[np.uint64(_IN_QW) * B + j]
        qx = buf[np.uint64(_IN_QX) * B + j]
        qy = buf[np.uint64(_IN_QY) * B + j]
        qz = buf[np.uint64(_IN_QZ) * B + j]
        qn = one / np.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
        qw *= qn
        qx *= qn
        qy *= qn
        qz *= qn
        s0 = buf[np.uint64(_IN_S0) * B + j]
        s1 = buf[np.uint64(_IN_S1) * B + j]
        s2 = buf[np.uint64(_IN_S2) * B + j]
        m00 = (one - two * (qy * qy + qz * qz)) * s0
        m01 = two * (qx * qy - qw * qz) * s1
        m02 = two * (qx * qz + qw * qy) * s2
        m10 = two * (qx * qy + qw * qz) * s0
        m11 = (one - two * (qx * qx + qz * qz)) * s1
        m12 = two * (qy * qz - qw * qx) * s2
        m20 = two * (qx * qz - qw * qy) * s0
        m21 = two * (qy * qz + qw * qx) * s1
        m22 = (one - two * (qx * qx + qy * qy)) * s2
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
        # EWA Jacobian at the clamped direction: T = J W, cov2d = T T^T
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
        ica = cc * idet
        icb = -cb * idet
        icc = ca * idet
        mx = fx * x * iz + cx
        my = fy * y * iz + cy
        op = buf[np.uint64(_IN_OP) * B + j]
        level = two * splat_log(max(F(255.0) * op, one))
        ex = np.sqrt(level * ca) + margin
        ey = np.sqrt(level * cc) + margin
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
        buf[np.uint64(_OUT_MX) * B + j] = mx
        buf[np.uint64(_OUT_MY) * B + j] = my
        buf[np.uint64(_OUT_CA) * B + j] = ica
        buf[np.uint64(_OUT_CB) * B + j] = icb
        buf[np.uint64(_OUT_CC) * B + j] = icc
        buf[np.uint64(_OUT_Z) * B + j] = z
        buf[np.uint64(_OUT_EX) * B + j] = ex
        buf[np.uint64(_OUT_EY) * B + j] = ey
        buf[np.uint64(_OUT_X0) * B + j] = bx0 if ok else zero
        buf[np.uint64(_OUT_X1) * B + j] = bx1 if ok else -one
        buf[np.uint64(_OUT_Y0) * B + j] = by0 if ok else zero
        buf[np.uint64(_OUT_Y1) * B + j] = by1 if ok else -one


@jit
def _project_block(lo, hi,
                   src,         # Gaussian i's inputs are row i - src of means ... colors
                   means,       # [N, 3]
                   quats,       # [N, 4]
                   scales,      # [N, 3]
                   opacities,   # [N]
                   colors,      # [N, 3]
                   feat,        # [N, D] (checked finite only; row i, like rec)
                   viewmat,     # [4, 4]
                   K,           # [3, 3]
                   width, height, near,
                   buf,         # [_NFIELD * _BLOCK] scratch
                   rec,         # [N, 16] out
                   trect,       # [4, N] int32 out: tile x0, x1, y0, y1 inclusive (x1 = -1 when culled)
                   tiles_x,
                   counts):     # [n_tiles] int32 out (+=)
    n = hi - lo
    B = _BLOCK
    F = rec.dtype.type
    one = F(1.0)
    inf = F(np.inf)
    for j in range(n):
        i = lo - src + j
        buf[_IN_M0 * B + j] = means[i, 0]
        buf[_IN_M1 * B + j] = means[i, 1]
        buf[_IN_M2 * B + j] = means[i, 2]
        buf[_IN_QW * B + j] = quats[i, 0]
        buf[_IN_QX * B + j] = quats[i, 1]
        buf[_IN_QY * B + j] = quats[i, 2]
        buf[_IN_QZ * B + j] = quats[i, 3]
        buf[_IN_S0 * B + j] = scales[i, 0]
        buf[_IN_S1 * B + j] = scales[i, 1]
        buf[_IN_S2 * B + j] = scales[i, 2]
        buf[_IN_OP * B + j] = opacities[i]
    _project_soa(n, buf, viewmat, K, width, height, near)
    for j in range(n):
        i = lo + j
        rec[i, R_MX] = buf[_OUT_MX * B + j]
        rec[i, R_MY] = buf[_OUT_MY * B + j]
        rec[i, R_CA] = buf[_OUT_CA * B + j]
        rec[i, R_CB] = buf[_OUT_CB * B + j]
        rec[i, R_CC] = buf[_OUT_CC * B + j]
        rec[i, R_OP] = buf[_IN_OP * B + j]
        rec[i, R_Z] = buf[_OUT_Z * B + j]
        cr = colors[i - src, 0]
        cg = colors[i - src, 1]
        cb = colors[i - src, 2]
        rec[i, R_R] = cr
        rec[i, R_G] = cg
        rec[i, R_B] = cb
        rec[i, R_EX] = buf[_OUT_EX * B + j]
        rec[i, R_EY] = buf[_OUT_EY * B + j]
        bx0 = buf[_OUT_X0 * B + j]
        bx1 = buf[_OUT_X1 * B + j]
        by0 = buf[_OUT_Y0 * B + j]
        by1 = buf[_OUT_Y1 * B + j]
        # a non-finite colour or feature would turn pixels NaN: cull the Gaussian instead
        finite = (abs(cr) < inf) & (abs(cg) < inf) & (abs(cb) < inf)
        for d in range(feat.shape[1]):
            finite &= abs(feat[i, d]) < inf
        if not finite:
            bx1 = -one
            by1 = -one
        rec[i, R_X0] = bx0
        rec[i, R_X1] = bx1
        rec[i, R_Y0] = by0
        rec[i, R_Y1] = by1
        # tile rectangle (inclusive); culled Gaussians get x1 = -1 < x0 = 0
        tx0 = np.int32(bx0) >> np.int32(4)
        tx1 = np.int32(bx1) >> np.int32(4)
        ty0 = np.int32(by0) >> np.int32(4)
        ty1 = np.int32(by1) >> np.int32(4)
        trect[0, i] = tx0
        trect[1, i] = tx1
        trect[2, i] = ty0
        trect[3, i] = ty1
        if tx1 < tx0:
            continue
        if tx0 == tx1 and ty0 == ty1:   # single tile: the common case
            counts[ty0 * tiles_x + tx0] += 1
            continue
        for ty in range(ty0, ty1 + 1):
            for tx in range(tx0, tx1 + 1):
                counts[ty * tiles_x + tx] += 1


@jit
def _project_range(lo, hi, src, means, quats, scales, opacities, colors, feat, viewmat, K, width, height, near,
                   rec, trect, tiles_x, counts):
    """Project Gaussians lo..hi - 1 into rec[lo:hi] and trect[:, lo:hi], their inputs read from
    rows lo - src..hi - 1 - src of means, quats, scales, opacities and colors (src = 0: the same
    rows; a view's part read in place starts at its first Gaussian's index) and feat's rows lo..hi - 1."""
    counts[:] = 0
    buf = np.empty(_NFIELD * _BLOCK, rec.dtype)
    for b in range(lo, hi, _BLOCK):
        e = min(b + _BLOCK, hi)
        _project_block(b, e, src, means, quats, scales, opacities, colors, feat, viewmat, K, width, height, near,
                       buf, rec, trect, tiles_x, counts)


@pjit
def project_forward(means,      # [N, 3]
                    quats,      # [N, 4]
                    scales,     # [N, 3]
                    opacities,  # [N]
                    colors,     # [N, 3]
                    feat,       # [N, D]
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
    Gaussians with a non-finite colour or feature are culled (they would make pixels NaN).
    """
    n = means.shape[0]
    nthr = counts.shape[0]
    for t in prange(nthr):
        _project_range(n * t // nthr, n * (t + 1) // nthr, 0, means, quats, scales, opacities, colors, feat, viewmat,
                       K, width, height, near, rec, trect, tiles_x, counts[t])


# Fields of the backward projection's block scratch (inputs, then outputs; see _project_soa).
(_B_M0, _B_M1, _B_M2, _B_QW, _B_QX, _B_QY, _B_QZ, _B_S0, _B_S1, _B_S2,
 _B_GMX, _B_GMY, _B_GIA, _B_GIB, _B_GIC, _B_GZ, _B_OK,
 _B_GM0, _B_GM1, _B_GM2, _B_GQW, _B_GQX, _B_GQY, _B_GQZ, _B_GS0, _B_GS1, _B_GS2) = range(27)
_B_NFIELD = 27


@jit
def _project_backward_soa(n,
                          buf,       # [_B_NFIELD * _BLOCK] block scratch
                          viewmat,   # [4, 4]
                          K,         # [3, 3]
                          width, height):
    """Branch-free chain rule for n <= _BLOCK Gaussians held field by field in `buf`
    (culled ones, _B_OK = 0, get zeros)."""
    F = buf.dtype.type
    fx = K[0, 0]
    fy = K[1, 1]
    r00, r01, r02, t0 = viewmat[0, 0], viewmat[0, 1], viewmat[0, 2], viewmat[0, 3]
    r10, r11, r12, t1 = viewmat[1, 0], viewmat[1, 1], viewmat[1, 2], viewmat[1, 3]
    r20, r21, r22, t2 = viewmat[2, 0], viewmat[2, 1], viewmat[2, 2], viewmat[2, 3]
    cx = K[0, 2]
    cy = K[1, 2]
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
    two = F(2.0)
    blur = F(BLUR)
    B = np.uint64(_BLOCK)
    for jj in range(n):
        j = np.uint64(jj)
        ok = buf[np.uint64(_B_OK) * B + j] > zero
        gmx = buf[np.uint64(_B_GMX) * B + j]
        gmy = buf[np.uint64(_B_GMY) * B + j]
        gia = buf[np.uint64(_B_GIA) * B + j]
        gib = buf[np.uint64(_B_GIB) * B + j]
        gic = buf[np.uint64(_B_GIC) * B + j]
        gz = buf[np.uint64(_B_GZ) * B + j]
        # ---- recompute the forward quantities (same formulas as _project_soa)
        m0 = buf[np.uint64(_B_M0) * B + j]
        m1 = buf[np.uint64(_B_M1) * B + j]
        m2 = buf[np.uint64(_B_M2) * B + j]
        x = r00 * m0 + r01 * m1 + r02 * m2 + t0
        y = r10 * m0 + r11 * m1 + r12 * m2 + t1
        z = r20 * m0 + r21 * m1 + r22 * m2 + t2
        qw0 = buf[np.uint64(_B_QW) * B + j]
        qx0 = buf[np.uint64(_B_QX) * B + j]
        qy0 = buf[np.uint64(_B_QY) * B + j]
        qz0 = buf[np.uint64(_B_QZ) * B + j]
        qnorm = np.sqrt(qw0 * qw0 + qx0 * qx0 + qy0 * qy0 + qz0 * qz0)
        qn = one / qnorm
        qw = qw0 * qn
        qx = qx0 * qn
        qy = qy0 * qn
        qz = qz0 * qn
        s0 = buf[np.uint64(_B_S0) * B + j]
        s1 = buf[np.uint64(_B_S1) * B + j]
        s2 = buf[np.uint64(_B_S2) * B + j]
        R00 = one - two * (qy * qy + qz * qz)
        R01 = two * (qx * qy - qw * qz)
        R02 = two * (qx * qz + qw * qy)
        R10 = two * (qx * qy + qw * qz)
        R11 = one - two * (qx * qx + qz * qz)
        R12 = two * (qy * qz - qw * qx)
        R20 = two * (qx * qz - qw * qy)
        R21 = two * (qy * qz + qw * qx)
        R22 = one - two * (qx * qx + qy * qy)
        m00, m01, m02 = R00 * s0, R01 * s1, R02 * s2
        m10, m11, m12 = R10 * s0, R11 * s1, R12 * s2
        m20, m21, m22 = R20 * s0, R21 * s1, R22 * s2
        w00 = r00 * m00 + r01 * m10 + r02 * m20
        w01 = r00 * m01 + r01 * m11 + r02 * m21
        w02 = r00 * m02 + r01 * m12 + r02 * m22
        w10 = r10 * m00 + r11 * m10 + r12 * m20
        w11 = r10 * m01 + r11 * m11 + r12 * m21
        w12 = r10 * m02 + r11 * m12 + r12 * m22
        w20 = r20 * m00 + r21 * m10 + r22 * m20
        w21 = r20 * m01 + r21 * m11 + r22 * m21
        w22 = r20 * m02 + r21 * m12 + r22 * m22
        iz = one / (z if ok else one)
        xu = x * iz
        yv = y * iz
        u = min(max(xu, -lim_x_neg), lim_x_pos)
        v = min(max(yv, -lim_y_neg), lim_y_pos)
        ind_u = one if (xu >= -lim_x_neg) & (xu <= lim_x_pos) else zero
        ind_v = one if (yv >= -lim_y_neg) & (yv <= lim_y_pos) else zero
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
        # ---- conic (cc, -cb, ca) / det  ->  2D covariance entries
        idet2 = one / (det * det if ok else one)
        g_ca = (-cc * cc * gia + cb * cc * gib - cb * cb * gic) * idet2
        g_cb = (two * cb * cc * gia - (det + two * cb * cb) * gib + two * ca * cb * gic) * idet2
        g_cc = (-cb * cb * gia + ca * cb * gib - ca * ca * gic) * idet2
        # ---- cov2d = [A.A, A.B; ., B.B]  ->  rows A, B of J W
        ga0 = two * g_ca * a0 + g_cb * b0
        ga1 = two * g_ca * a1 + g_cb * b1
        ga2 = two * g_ca * a2 + g_cb * b2
        gb0 = two * g_cc * b0 + g_cb * a0
        gb1 = two * g_cc * b1 + g_cb * a1
        gb2 = two * g_cc * b2 + g_cb * a2
        # ---- A = j00 W0 + j02 W2, B = j11 W1 + j12 W2
        gj00 = ga0 * w00 + ga1 * w01 + ga2 * w02
        gj02 = ga0 * w20 + ga1 * w21 + ga2 * w22
        gj11 = gb0 * w10 + gb1 * w11 + gb2 * w12
        gj12 = gb0 * w20 + gb1 * w21 + gb2 * w22
        gw00, gw01, gw02 = ga0 * j00, ga1 * j00, ga2 * j00
        gw10, gw11, gw12 = gb0 * j11, gb1 * j11, gb2 * j11
        gw20 = ga0 * j02 + gb0 * j12
        gw21 = ga1 * j02 + gb1 * j12
        gw22 = ga2 * j02 + gb2 * j12
        # ---- J(x, y, z) and the pixel centre -> camera-space point
        iz2 = iz * iz
        gx = gj02 * (-fx * ind_u * iz2) + gmx * fx * iz
        gy = gj12 * (-fy * ind_v * iz2) + gmy * fy * iz
        gzc = (gz - (fx * gj00 + fy * gj11) * iz2
               + gj02 * fx * (ind_u * x * iz2 * iz + u * iz2)
               + gj12 * fy * (ind_v * y * iz2 * iz + v * iz2)
               - (gmx * fx * x + gmy * fy * y) * iz2)
        # p = R_cam m + t
        buf[np.uint64(_B_GM0) * B + j] = r00 * gx + r10 * gy + r20 * gzc if ok else zero
        buf[np.uint64(_B_GM1) * B + j] = r01 * gx + r11 * gy + r21 * gzc if ok else zero
        buf[np.uint64(_B_GM2) * B + j] = r02 * gx + r12 * gy + r22 * gzc if ok else zero
        # ---- W = R_cam M  ->  M = R diag(s)
        gm00 = r00 * gw00 + r10 * gw10 + r20 * gw20
        gm01 = r00 * gw01 + r10 * gw11 + r20 * gw21
        gm02 = r00 * gw02 + r10 * gw12 + r20 * gw22
        gm10 = r01 * gw00 + r11 * gw10 + r21 * gw20
        gm11 = r01 * gw01 + r11 * gw11 + r21 * gw21
        gm12 = r01 * gw02 + r11 * gw12 + r21 * gw22
        gm20 = r02 * gw00 + r12 * gw10 + r22 * gw20
        gm21 = r02 * gw01 + r12 * gw11 + r22 * gw21
        gm22 = r02 * gw02 + r12 * gw12 + r22 * gw22
        buf[np.uint64(_B_GS0) * B + j] = gm00 * R00 + gm10 * R10 + gm20 * R20 if ok else zero
        buf[np.uint64(_B_GS1) * B + j] = gm01 * R01 + gm11 * R11 + gm21 * R21 if ok else zero
        buf[np.uint64(_B_GS2) * B + j] = gm02 * R02 + gm12 * R12 + gm22 * R22 if ok else zero
        g00, g01, g02 = gm00 * s0, gm01 * s1, gm02 * s2
        g10, g11, g12 = gm10 * s0, gm11 * s1, gm12 * s2
        g20, g21, g22 = gm20 * s0, gm21 * s1, gm22 * s2
        # ---- R(q^) -> q^ -> q (through the normalisation)
        gqw = two * (-qz * g01 + qy * g02 + qz * g10 - qx * g12 - qy * g20 + qx * g21)
        gqx = two * (qy * g01 + qz * g02 + qy * g10 - two * qx * g11 - qw * g12 + qz * g20 + qw * g21
                     - two * qx * g22)
        gqy = two * (-two * qy * g00 + qx * g01 + qw * g02 + qx * g10 + qz * g12 - qw * g20 + qz * g21
                     - two * qy * g22)
        gqz = two * (-two * qz * g00 - qw * g01 + qx * g02 + qw * g10 - two * qz * g11 + qy * g12 + qx * g20
                     + qy * g21)
        dot = qw * gqw + qx * gqx + qy * gqy + qz * gqz
        buf[np.uint64(_B_GQW) * B + j] = (gqw - qw * dot) * qn if ok else zero
        buf[np.uint64(_B_GQX) * B + j] = (gqx - qx * dot) * qn if ok else zero
        buf[np.uint64(_B_GQY) * B + j] = (gqy - qy * dot) * qn if ok else zero
        buf[np.uint64(_B_GQZ) * B + j] = (gqz - qz * dot) * qn if ok else zero




@jit
def _project_backward_range(lo, hi,
                            means,      # [N, 3]
                            quats,      # [N, 4]
                            scales,     # [N, 3]
                            viewmat,    # [4, 4]
                            K,          # [3, 3]
                            width, height,
                            rec,        # [N, 16] forward records (culled ones have X1 < X0)
                            grad2d,     # [N, 10] 2D gradients (columns backward.G_*)
                            gfeat2d,    # [N, D]
                            g_means,    # [N, 3] out (+=)
                            g_quats,    # [N, 4] out (+=)
                            g_scales,   # [N, 3] out (+=)
                            g_opac,     # [N] out (+=)
                            g_colors,   # [N, 3] out (+=)
                            g_feat):    # [N, D] out (+=)
    D = gfeat2d.shape[1]
    B = _BLOCK
    buf = np.zeros(_B_NFIELD * _BLOCK, rec.dtype)
    for b in range(lo, hi, _BLOCK):
        n = min(b + _BLOCK, hi) - b
        for j in range(n):
            i = b + j
            ok = rec[i, R_X1] >= rec[i, R_X0]   # culled: never rasterised, no gradient
            buf[_B_OK * B + j] = 1.0 if ok else 0.0
            buf[_B_M0 * B + j] = means[i, 0]
            buf[_B_M1 * B + j] = means[i, 1]
            buf[_B_M2 * B + j] = means[i, 2]
            buf[_B_QW * B + j] = quats[i, 0]
            buf[_B_QX * B + j] = quats[i, 1]
            buf[_B_QY * B + j] = quats[i, 2]
            buf[_B_QZ * B + j] = quats[i, 3]
            buf[_B_S0 * B + j] = scales[i, 0]
            buf[_B_S1 * B + j] = scales[i, 1]
            buf[_B_S2 * B + j] = scales[i, 2]
            buf[_B_GMX * B + j] = grad2d[i, 0]
            buf[_B_GMY * B + j] = grad2d[i, 1]
            buf[_B_GIA * B + j] = grad2d[i, 2]
            buf[_B_GIB * B + j] = grad2d[i, 3]
            buf[_B_GIC * B + j] = grad2d[i, 4]
            buf[_B_GZ * B + j] = grad2d[i, 6]
            if ok:
                g_opac[i] += grad2d[i, 5]
                g_colors[i, 0] += grad2d[i, 7]
                g_colors[i, 1] += grad2d[i, 8]
                g_colors[i, 2] += grad2d[i, 9]
                for d in range(D):
                    g_feat[i, d] += gfeat2d[i, d]
        _project_backward_soa(n, buf, viewmat, K, width, height)
        for j in range(n):
            i = b + j
            g_means[i, 0] += buf[_B_GM0 * B + j]
            g_means[i, 1] += buf[_B_GM1 * B + j]
            g_means[i, 2] += buf[_B_GM2 * B + j]
            g_quats[i, 0] += buf[_B_GQW * B + j]
            g_quats[i, 1] += buf[_B_GQX * B + j]
            g_quats[i, 2] += buf[_B_GQY * B + j]
            g_quats[i, 3] += buf[_B_GQZ * B + j]
            g_scales[i, 0] += buf[_B_GS0 * B + j]
            g_scales[i, 1] += buf[_B_GS1 * B + j]
            g_scales[i, 2] += buf[_B_GS2 * B + j]


@pjit
def project_backward(nthr,
                     means,      # [N, 3]
                     quats,      # [N, 4]
                     scales,     # [N, 3]
                     viewmat,    # [4, 4]
                     K,          # [3, 3]
                     width, height,
                     rec,        # [N, 16]
                     grad2d,     # [N, 10]
                     gfeat2d,    # [N, D]
                     g_means,    # [N, 3] out (+=)
                     g_quats,    # [N, 4] out (+=)
                     g_scales,   # [N, 3] out (+=)
                     g_opac,     # [N] out (+=)
                     g_colors,   # [N, 3] out (+=)
                     g_feat):    # [N, D] out (+=)
    """Chain one camera's 2D gradients (mean2d, conic, opacity, depth, colour, features) back to
    the 3D parameters, adding into the g_* arrays. Twin of autograd through `project_torch`."""
    n = means.shape[0]
    for t in prange(nthr):
        _project_backward_range(n * t // nthr, n * (t + 1) // nthr, means, quats, scales, viewmat, K, width,
                                height, rec, grad2d, gfeat2d, g_means, g_quats, g_scales, g_opac, g_colors, g_feat)
