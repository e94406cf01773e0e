"""Forward rasterisation: front-to-back alpha compositing of depth-sorted Gaussians per 16x16 tile.

Kernel twin of the compositing in `morphosim_gym.render.reference.rasterize_torch` (`_composite`):
alpha = min(0.99, o exp(power)), skipped when alpha < 1/255 or power > 0, and a pixel stops
*before* the Gaussian that would bring its transmittance T below 1e-4.

Inside a tile the loop runs Gaussian by Gaussian over only the pixel rows of its box, each row
as one branch-free 16-wide loop (LLVM vectorises it), with a mask of tile rows whose pixels have
all stopped so that Gaussians over finished rows are skipped without being evaluated. A
Gaussian evaluated at a pixel outside its box gives alpha < 1/255 (the box is the 1/255 level
set plus a margin), so the box only saves work and never changes a result.

Per pixel the kernel also records, for the backward pass, the final transmittance and `last`:
the list position where the pixel stopped (the list length if it never did); Gaussians at
positions >= last did not contribute.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ._jit import (ALPHA_MAX, ALPHA_MIN, R_B, R_CA, R_CB, R_CC, R_G, R_MX, R_MY, R_OP, R_R, R_X0, R_X1, R_Y0,
                   R_Y1, R_Z, T_MIN, jit, pjit, splat_exp)
from .binning import sort_segment

__all__ = ["raster_forward"]


@jit
def _raster_tiles(tiles,       # [n] int32 tiles of this thread
                  ntiles_mine,
                  tile_start,  # [n_tiles + 1] int64
                  lst,         # [n_entries] int32 (sorted in place)
                  rec,         # [N, 16]
                  ids,         # [N] int32
                  feat,        # [N, D]
                  width, height, tiles_x,
                  bg,          # [3]
                  rgb,         # [H, W, 3] out
                  depth,       # [H, W] out
                  alpha,       # [H, W] out
                  inst,        # [H, W] int32 out
                  feat_out,    # [H, W, D] out
                  tfinal,      # [H, W] out (if save)
                  last_out,    # [H, W] int32 out (if save)
                  save,
                  keys, keys2,  # [max_len] sort scratch (uint of the float width)
                  idx, idx2):   # [max_len] int32 sort scratch
    F = rec.dtype.type
    D = feat.shape[1]
    T = np.empty(256, F)
    acc_r = np.empty(256, F)
    acc_g = np.empty(256, F)
    acc_b = np.empty(256, F)
    acc_d = np.empty(256, F)
    wmax = np.empty(256, F)
    iid = np.empty(256, np.int32)
    last = np.empty(256, np.int32)
    facc = np.zeros(max(D, 1) * 256, F)
    wl = np.zeros(16, F)
    rowcnt = np.empty(16, np.int32)
    hist = np.empty(256, np.int64)
    one = F(1.0)
    zero = F(0.0)
    half = F(0.5)
    amax = F(ALPHA_MAX)
    amin = F(ALPHA_MIN)
    tmin = F(T_MIN)
    bg0, bg1, bg2 = bg[0], bg[1], bg[2]
    for q in range(ntiles_mine):
        tile = tiles[q]
        start = tile_start[tile]
        L = tile_start[tile + 1] - start
        sort_segment(lst, start, L, rec, keys, keys2, idx, idx2, hist)
        x0 = (tile % tiles_x) * 16
        y0 = (tile // tiles_x) * 16
        nx = min(16, width - x0)
        ny = min(16, height - y0)
        done_rows = 0
        for ly in range(16):
            rowcnt[ly] = nx if ly < ny else 0
            if ly >= ny:
                done_rows |= 1 << ly
        for p in range(256):
            T[p] = one
            acc_r[p] = zero
            acc_g[p] = zero
            acc_b[p] = zero
            acc_d[p] = zero
            wmax[p] = zero
            iid[p] = -1
            last[p] = -1 if ((p & 15) < nx and (p >> 4) < ny) else 0   # outside the image: stopped
        if D > 0:
            facc[:] = zero
        x0f = F(x0) + half
        y0f = F(y0) + half
        for k in range(L):
            if done_rows == 0xFFFF:
                break
            i = lst[start + k]
            lx0 = max(np.int64(rec[i, R_X0]) - x0, 0)
            lx1 = min(np.int64(rec[i, R_X1]) - x0, 15)
            ly0 = max(np.int64(rec[i, R_Y0]) - y0, 0)
            ly1 = min(np.int64(rec[i, R_Y1]) - y0, 15)
            gmask = ((2 << ly1) - 1) & ~((1 << ly0) - 1)
            if (done_rows & gmask) == gmask:
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
            gid = ids[i]
            kk = np.int32(k)
            for ly in range(ly0, ly1 + 1):
                if (done_rows >> ly) & 1:
                    continue
                dy = my - (y0f + F(ly))
                pc = F(-0.5) * cc * dy * dy
                bd = cb * dy
                nterm = 0
                base = np.uint64(ly << 4)
                # the whole tile row, with a trip count unknown at compile time: LLVM then
                # vectorises it 16 wide instead of unrolling it into scalar code
                for l in range(nx):
                    p = base + np.uint64(l)
                    dx = mx - (x0f + F(l))
                    power = F(-0.5) * ca * dx * dx + pc - bd * dx
                    al = min(amax, op * splat_exp(power))
                    Tp = T[p]
                    test = Tp * (one - al)
                    ok = (last[p] < 0) & (al >= amin) & (power <= zero)
                    term = ok & (test < tmin)
                    con = ok & (test >= tmin)
                    w = al * Tp if con else zero
                    acc_r[p] += w * cr
                    acc_g[p] += w * cg
                    acc_b[p] += w * cbl
                    acc_d[p] += w * z
                    better = w > wmax[p]
                    wmax[p] = w if better else wmax[p]
                    iid[p] = gid if better else iid[p]
                    T[p] = test if con else Tp
                    last[p] = kk if term else last[p]
                    nterm += np.int32(term)
                    wl[l] = w
                if D > 0:
                    for d in range(D):
                        fd = feat[i, d]
                        fb = np.uint64(d * 256) + base
                        for l in range(nx):
                            facc[fb + np.uint64(l)] += wl[l] * fd
                if nterm > 0:
                    rowcnt[ly] -= nterm
                    if rowcnt[ly] <= 0:
                        done_rows |= 1 << ly
        # write out
        for ly in range(ny):
            for lx in range(nx):
                p = (ly << 4) + lx
                yy = y0 + ly
                xx = x0 + lx
                Tp = T[p]
                rgb[yy, xx, 0] = acc_r[p] + Tp * bg0
                rgb[yy, xx, 1] = acc_g[p] + Tp * bg1
                rgb[yy, xx, 2] = acc_b[p] + Tp * bg2
                a = one - Tp
                alpha[yy, xx] = a
                depth[yy, xx] = acc_d[p] / a if a > zero else zero
                inst[yy, xx] = iid[p] if wmax[p] > Tp else np.int32(-1)
                for d in range(D):
                    feat_out[yy, xx, d] = facc[d * 256 + p]
                if save:
                    tfinal[yy, xx] = Tp
                    last_out[yy, xx] = last[p] if last[p] >= 0 else np.int32(L)


@pjit
def raster_forward(assign,      # [n_threads, n_tiles] int32
                   nper,        # [n_threads] int64
                   tile_start,  # [n_tiles + 1] int64
                   lst,         # [n_entries] int32 (each tile's segment is depth-sorted in place)
                   rec,         # [N, 16]
                   ids,         # [N] int32
                   feat,        # [N, D]
                   width, height, tiles_x,
                   bg,          # [3]
                   rgb,         # [H, W, 3] out
                   depth,       # [H, W] out
                   alpha,       # [H, W] out
                   inst,        # [H, W] int32 out
                   feat_out,    # [H, W, D] out
                   tfinal,      # [H, W] out, written when save
                   last_out,    # [H, W] int32 out, written when save
                   save,
                   keys, keys2,  # [n_threads, max_len] uint sort scratch
                   idx, idx2):   # [n_threads, max_len] int32 sort scratch
    """Sort each tile's list by depth, then composite it; thread k renders tiles assign[k, :nper[k]]."""
    nthr = assign.shape[0]
    for k in prange(nthr):
        _raster_tiles(assign[k], nper[k], tile_start, lst, rec, ids, feat, width, height, tiles_x, bg,
                      rgb, depth, alpha, inst, feat_out, tfinal, last_out, save,
                      keys[k], keys2[k], idx[k], idx2[k])
