"""Backward rasterisation: gradients of the per-pixel outputs w.r.t. each Gaussian's 2D record.

For one pixel with contributing Gaussians i = 1..n (front to back), alpha_i, transmittance
T_i = prod_{j<i} (1 - alpha_j), weights w_i = alpha_i T_i and final transmittance T_f:

    rgb = sum w_i c_i + T_f bg,  acc = 1 - T_f,  depth = dsum / acc with dsum = sum w_i z_i,
    features = sum w_i f_i.

With upstream gradients g_rgb, g_depth, g_alpha, g_feat, let g_dsum = g_depth / acc,
g_acc = g_alpha - g_depth depth / acc, G_i = g_rgb . c_i + g_dsum z_i + g_feat . f_i and
Q = sum_j w_j G_j + T_f (g_rgb . bg - g_acc) = g_rgb . rgb + g_dsum dsum + g_feat . features
- T_f g_acc. Then

    dL/dalpha_i = T_i G_i - (Q - sum_{j<=i} w_j G_j) / (1 - alpha_i),

so the pass runs front to back, like the forward pass (same tile loop, same T recurrence, no
division to undo transmittance), keeping the running prefix sum per pixel. Gaussians at list
positions >= the forward pass's `last` for a pixel are skipped there. alpha = min(0.99, o e^p):
where the clamp is active no gradient reaches o or p. Per Gaussian the pass accumulates

    d mean2d (2), d conic (3), d opacity, d depth (camera z), d colour (3)  [+ d features (D)]

into one row per tile-list entry (each entry belongs to one tile, so any thread may render
any tile and the result is the same); `reduce_entries` sums the rows per Gaussian in list
order, so gradients are deterministic.
Reductions over pixels are vectorised, so this module compiles with `reassoc`.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange

from ._jit import (ALPHA_MAX, ALPHA_MIN, R_B, R_CA, R_CB, R_CC, R_G, R_MX, R_MY, R_OP, R_R, R_X0, R_X1, R_Y0,
                   R_Y1, R_Z, atomic_add, splat_exp)
from .binning import argsort_int

__all__ = ["raster_backward", "reduce_entries", "G_MX", "G_MY", "G_CA", "G_CB", "G_CC", "G_OP", "G_Z", "G_R", "G_G", "G_B", "NGRAD"]

# columns of the per-Gaussian 2D gradient buffer
G_MX, G_MY, G_CA, G_CB, G_CC, G_OP, G_Z, G_R, G_G, G_B = range(10)
NGRAD = 10

_OPTS = dict(cache=True, error_model="numpy", fastmath={"contract", "reassoc"}, nogil=True)
_jit_r = numba.njit(**_OPTS)

# per-pixel state of one tile (flat, constant offsets, pixels by 8-pixel half tile as in forward.py:
# p = 128 * (lx // 8) + 8 * ly + lx % 8)
_S_T = 0
_S_P = 256      # prefix sum of w_j G_j
_S_GR = 512     # upstream gradients (rgb, dsum) and Q
_S_GG = 768
_S_GB = 1024
_S_GD = 1280
_S_Q = 1536
_S_LAST = 1792  # list position where the pixel stopped, as a float
_S_W = 2048     # weight of the current Gaussian (feature channels)
_S_GF = 2304    # g_feat . f of the current Gaussian
_S_PX = 2560    # pixel centre x, y of each pixel of the tile
_S_PY = 2816
_S_SIZE = 3072


@_jit_r
def _backward_tiles(order,        # [n_tiles] int32 tiles, longest list first
                    claim,        # [1] int64 next position in `order` (shared by the threads)
                    tile_start,   # [n_tiles + 1] int64
                    lst,          # [n_entries] int32, depth-sorted per tile by the forward pass
                    rec,          # [N, 16]
                    feat,         # [N, D]
                    width, height, tiles_x,
                    rgb,          # [H, W, 3] forward output
                    depth,        # [H, W] forward output
                    feat_out,     # [H, W, D] forward output
                    tfinal,       # [H, W]
                    last,         # [H, W] int32
                    g_rgb,        # [H, W, 3]
                    g_depth,      # [H, W]
                    g_alpha,      # [H, W]
                    g_feat,       # [H, W, D]
                    grad_e,       # [n_entries, NGRAD] out: per list entry
                    gfeat_e):     # [n_entries, D] out: per list entry
    F = rec.dtype.type
    D = feat.shape[1]
    S = np.empty(_S_SIZE, F)
    gfp = np.zeros(max(D, 1) * 256, F)   # g_feat of the tile, channel-major
    rowbits = np.empty(16, np.int64)
    pix_order = np.empty(256, np.int64)
    lastp = np.empty(256, np.int64)
    one = F(1.0)
    zero = F(0.0)
    half = F(0.5)
    amax = F(ALPHA_MAX)
    amin = F(ALPHA_MIN)
    uT = np.uint64(_S_T)
    uP = np.uint64(_S_P)
    uGR = np.uint64(_S_GR)
    uGG = np.uint64(_S_GG)
    uGB = np.uint64(_S_GB)
    uGD = np.uint64(_S_GD)
    uQ = np.uint64(_S_Q)
    uL = np.uint64(_S_LAST)
    uW = np.uint64(_S_W)
    uGF = np.uint64(_S_GF)
    uPX = np.uint64(_S_PX)
    uPY = np.uint64(_S_PY)
    ntiles = order.shape[0]
    while True:
        q = atomic_add(claim, 0, 1)
        if q >= ntiles:
            break
        tile = order[q]
        start = tile_start[tile]
        L = tile_start[tile + 1] - start
        x0 = (tile % tiles_x) * 16
        y0 = (tile // tiles_x) * 16
        nx = min(16, width - x0)
        ny = min(16, height - y0)
        S[:] = zero
        kend = 0
        for p in range(256):
            lastp[p] = 0
            S[_S_PX + p] = F(x0 + ((p >> 7) << 3) + (p & 7)) + half
            S[_S_PY + p] = F(y0 + ((p >> 3) & 15)) + half
        for ly in range(ny):
            for lx in range(nx):
                p = ((lx >> 3) << 7) + (ly << 3) + (lx & 7)
                yy = y0 + ly
                xx = x0 + lx
                Tf = tfinal[yy, xx]
                acc = one - Tf
                gd = g_depth[yy, xx]
                dep = depth[yy, xx]
                g_dsum = gd / acc if acc > zero else zero
                g_acc = g_alpha[yy, xx] - (gd * dep / acc if acc > zero else zero)
                gr = g_rgb[yy, xx, 0]
                gg = g_rgb[yy, xx, 1]
                gb = g_rgb[yy, xx, 2]
                Q = gr * rgb[yy, xx, 0] + gg * rgb[yy, xx, 1] + gb * rgb[yy, xx, 2] + g_dsum * dep * acc - Tf * g_acc
                for d in range(D):
                    gfd = g_feat[yy, xx, d]
                    gfp[d * 256 + p] = gfd
                    Q += gfd * feat_out[yy, xx, d]
                S[_S_T + p] = one
                S[_S_GR + p] = gr
                S[_S_GG + p] = gg
                S[_S_GB + p] = gb
                S[_S_GD + p] = g_dsum
                S[_S_Q + p] = Q
                lp = last[yy, xx]
                S[_S_LAST + p] = F(lp)
                lastp[p] = lp
                kend = max(kend, lp)
        # pixels ordered by their stop position, to clear their active bits as k passes it
        argsort_int(lastp, pix_order)
        for ly in range(16):
            rowbits[ly] = 0
        nev = 0
        for p in range(256):
            if lastp[p] > 0:
                rowbits[(p >> 3) & 15] |= 1 << (((p >> 7) << 3) + (p & 7))
            else:
                nev += 1
        for k in range(kend):
            while nev < 256 and lastp[pix_order[nev]] <= k:
                p = pix_order[nev]
                rowbits[(p >> 3) & 15] &= ~(1 << (((p >> 7) << 3) + (p & 7)))
                nev += 1
            i = lst[start + k]
            lx0 = max(np.int64(rec[i, R_X0]) - x0, 0)
            lx1 = min(np.int64(rec[i, R_X1]) - x0, 15)
            ly0 = max(np.int64(rec[i, R_Y0]) - y0, 0)
            ly1 = min(np.int64(rec[i, R_Y1]) - y0, 15)
            colmask = ((2 << lx1) - 1) & ~((1 << lx0) - 1)
            while ly0 <= ly1 and (rowbits[ly0] & colmask) == 0:
                ly0 += 1
            while ly1 >= ly0 and (rowbits[ly1] & colmask) == 0:
                ly1 -= 1
            if ly0 > ly1:
                for c in range(NGRAD):
                    grad_e[start + k, c] = zero
                for d in range(D):
                    gfeat_e[start + k, d] = zero
                continue
            mx = rec[i, R_MX]
            my = rec[i, R_MY]
            ca = rec[i, R_CA]
            cb = rec[i, R_CB]
            cc = rec[i, R_CC]
            op = rec[i, R_OP]
            z = rec[i, R_Z]
            cr = rec[i, R_R]
            cg = rec[i, R_G]
            cbl = rec[i, R_B]
            kf = F(k)
            h0 = lx0 >> 3            # the 8-pixel halves of the tile the box touches
            h1 = lx1 >> 3
            ra = ly0 << 3
            rb = (ly1 + 1) << 3
            if D > 0:
                for hh in range(h0, h1 + 1):
                    for pp in range((hh << 7) + ra, (hh << 7) + rb):
                        S[uGF + np.uint64(pp)] = zero
                for d in range(D):
                    fd = feat[i, d]
                    fb = np.uint64(d * 256)
                    for hh in range(h0, h1 + 1):
                        for pp in range((hh << 7) + ra, (hh << 7) + rb):
                            p = np.uint64(pp)
                            S[uGF + p] += gfp[fb + p] * fd
            g_mx = zero
            g_my = zero
            g_ca = zero
            g_cb = zero
            g_cc = zero
            g_op = zero
            g_z = zero
            g_r = zero
            g_g = zero
            g_b = zero
            for hh in range(h0, h1 + 1):
                for pp in range((hh << 7) + ra, (hh << 7) + rb):
                    p = np.uint64(pp)
                    dx = mx - S[uPX + p]
                    dy = my - S[uPY + p]
                    power = F(-0.5) * (ca * dx * dx + cc * dy * dy) - cb * dx * dy
                    e = splat_exp(power)
                    aw = op * e
                    al = min(amax, aw)
                    ok = (kf < S[uL + p]) & (al >= amin) & (power <= zero)
                    Tp = S[uT + p]
                    w = al * Tp if ok else zero
                    gR = S[uGR + p]
                    gG = S[uGG + p]
                    gB = S[uGB + p]
                    gD = S[uGD + p]
                    Gv = gR * cr + gG * cg + gB * cbl + gD * z + S[uGF + p]
                    Pold = S[uP + p]
                    Pn = Pold + w * Gv
                    dal = Tp * Gv - (S[uQ + p] - Pn) / (one - al)
                    dal = dal if (ok & (aw <= amax)) else zero
                    dpow = dal * aw
                    g_op += dal * e
                    g_mx -= dpow * (ca * dx + cb * dy)
                    g_my -= dpow * (cc * dy + cb * dx)
                    g_ca -= dpow * half * dx * dx
                    g_cb -= dpow * dx * dy
                    g_cc -= dpow * half * dy * dy
                    g_r += w * gR
                    g_g += w * gG
                    g_b += w * gB
                    g_z += w * gD
                    S[uW + p] = w
                    S[uP + p] = Pn if ok else Pold + zero
                    S[uT + p] = Tp * (one - al) if ok else Tp + zero
            e = start + k
            grad_e[e, G_MX] = g_mx
            grad_e[e, G_MY] = g_my
            grad_e[e, G_CA] = g_ca
            grad_e[e, G_CB] = g_cb
            grad_e[e, G_CC] = g_cc
            grad_e[e, G_OP] = g_op
            grad_e[e, G_Z] = g_z
            grad_e[e, G_R] = g_r
            grad_e[e, G_G] = g_g
            grad_e[e, G_B] = g_b
            for d in range(D):
                fb = np.uint64(d * 256)
                s = zero
                for hh in range(h0, h1 + 1):
                    for pp in range((hh << 7) + ra, (hh << 7) + rb):
                        p = np.uint64(pp)
                        s += S[uW + p] * gfp[fb + p]
                gfeat_e[e, d] = s
        # entries behind every pixel's stop position got no gradient
        for e in range(start + kend, start + L):
            for c in range(NGRAD):
                grad_e[e, c] = zero
            for d in range(D):
                gfeat_e[e, d] = zero


@numba.njit(parallel=True, **_OPTS)
def raster_backward(order,       # [n_tiles] int32 tiles, longest list first
                    claim,       # [1] int64 work counter (set to 0 here)
                    nthr,
                    tile_start,  # [n_tiles + 1] int64
                    lst,         # [n_entries] int32
                    rec,         # [N, 16]
                    feat,        # [N, D]
                    width, height, tiles_x,
                    rgb,         # [H, W, 3]
                    depth,       # [H, W]
                    feat_out,    # [H, W, D]
                    tfinal,      # [H, W]
                    last,        # [H, W] int32
                    g_rgb,       # [H, W, 3]
                    g_depth,     # [H, W]
                    g_alpha,     # [H, W]
                    g_feat,      # [H, W, D]
                    grad_e,      # [n_entries, NGRAD] out
                    gfeat_e):    # [n_entries, D] out
    """Gradients of one camera's outputs w.r.t. each tile-list entry's record (see the module
    docstring). Each entry belongs to one tile, so threads claim tiles freely and results do not
    depend on which thread ran which tile; `reduce_entries` then sums them per Gaussian."""
    claim[0] = 0
    for k in prange(nthr):
        _backward_tiles(order, claim, tile_start, lst, rec, feat, width, height, tiles_x, rgb, depth,
                        feat_out, tfinal, last, g_rgb, g_depth, g_alpha, g_feat, grad_e, gfeat_e)


@_jit_r
def _reduce_range(lo, hi, lst, grad_e, gfeat_e, grad, gfeat):
    for i in range(lo, hi):
        for c in range(NGRAD):
            grad[i, c] = 0.0
        for d in range(gfeat.shape[1]):
            gfeat[i, d] = 0.0
    D = gfeat.shape[1]
    for e in range(lst.shape[0]):
        i = lst[e]
        if i < lo or i >= hi:
            continue
        for c in range(NGRAD):
            grad[i, c] += grad_e[e, c]
        for d in range(D):
            gfeat[i, d] += gfeat_e[e, d]


@numba.njit(parallel=True, **_OPTS)
def reduce_entries(nthr,
                   lst,       # [n_entries] int32
                   grad_e,    # [n_entries, NGRAD]
                   gfeat_e,   # [n_entries, D]
                   grad,      # [N, NGRAD] out
                   gfeat):    # [N, D] out
    """Sum the per-entry gradients of each Gaussian, in list order (deterministic): thread k owns
    a range of Gaussian indices and scans all entries for them."""
    n = grad.shape[0]
    for k in prange(nthr):
        _reduce_range(n * k // nthr, n * (k + 1) // nthr, lst, grad_e, gfeat_e, grad, gfeat)
