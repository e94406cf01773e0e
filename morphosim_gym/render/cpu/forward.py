"""Forward rasterisation: front-to-back alpha compositing of depth-sorted Gaussians per 16x16 tile.

Kernel twin of the compositing in `morphosim_gym.render.reference.rasterize_torch` (`_composite`):
alpha = min(0.99, o exp(power)), skipped when alpha < 1/255 or power > 0, and a pixel stops
*before* the Gaussian that would bring its transmittance T below 1e-4.

Inside a tile the loop runs Gaussian by Gaussian over only the tile rows of its box, as one
branch-free loop over whole 16-pixel rows (LLVM vectorises it). Per tile row a bit mask of the
pixels still compositing lets a Gaussian whose box covers only finished pixels be skipped
without being evaluated, and trims its rows to those with live pixels. A Gaussian evaluated at
a pixel outside its box gives alpha < 1/255 (the box is the 1/255 level set plus a margin), so
the box only saves work and never changes a result.

Per pixel the kernel also records, for the backward pass, the final transmittance and `last`:
the list position where the pixel stopped (the list length if it never did); Gaussians at
positions >= last did not contribute.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ._jit import (ALPHA_MAX, ALPHA_MIN, R_B, R_CA, R_CB, R_CC, R_G, R_MX, R_MY, R_OP, R_R, R_X0, R_X1, R_Y0,
                   R_Y1, R_Z, T_MIN, atomic_add, jit, pjit, splat_exp)
from .binning import sort_segment

__all__ = ["raster_forward"]


# Per-pixel compositing state of one tile: one flat float array (a single base pointer, so LLVM
# vectorises without alias checks), fields at constant offsets. Pixels are stored by half tile:
# pixel (column lx, row ly) at p = 128 * (lx // 8) + 8 * ly + lx % 8, so the rows of one 8-pixel
# half are contiguous and a Gaussian whose box lies in one half (about half of all box rows in
# env views) is composited over 8 lanes a row instead of 16.
_S_T = 0        # transmittance
_S_R = 256      # sum w * colour
_S_G = 512
_S_B = 768
_S_D = 1024     # sum w * depth
_S_WMAX = 1280  # largest weight so far
_S_KBEST = 1536  # list position of that weight (as a float)
_S_LAST = 1792  # list position where the pixel stopped (as a float), -1 while compositing
_S_W = 2048     # weight of the current Gaussian (for the feature channels)
_S_PX = 2304    # pixel centre x, y of each pixel of the tile (constant per tile)
_S_PY = 2560
_S_SIZE = 2816
# Positions are stored as floats (exact below 2^24 in float32: `render_camera` checks the
# longest tile list) and every select falls back to `old + 0`, not to `old` itself: a select
# between a new value and the value just loaded from the same address is lowered to a masked
# store, and a masked store cannot forward to the next Gaussian's load of that pixel.


@jit
def _raster_tiles(order,       # [n_tiles] int32 tiles, longest list first
                  claim,       # [1] int64 next position in `order` to render (shared by the threads)
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
                  idx, idx2,    # [max_len] int32 sort scratch
                  presorted=False):   # lists already depth-sorted (`binning.sorted_fill`)
    F = rec.dtype.type
    D = feat.shape[1]
    S = np.empty(_S_SIZE, F)
    facc = np.zeros(max(D, 1) * 256, F)
    rowbits = np.empty(16, np.int64)
    hist = np.empty(256, np.int64)
    one = F(1.0)
    zero = F(0.0)
    half = F(0.5)
    amax = F(ALPHA_MAX)
    amin = F(ALPHA_MIN)
    tmin = F(T_MIN)
    bg0, bg1, bg2 = bg[0], bg[1], bg[2]
    uT = np.uint64(_S_T)
    uR = np.uint64(_S_R)
    uG = np.uint64(_S_G)
    uB = np.uint64(_S_B)
    uD = np.uint64(_S_D)
    uWM = np.uint64(_S_WMAX)
    uKB = np.uint64(_S_KBEST)
    uL = np.uint64(_S_LAST)
    uW = np.uint64(_S_W)
    uPX = np.uint64(_S_PX)
    uPY = np.uint64(_S_PY)
    ntiles = order.shape[0]
    while True:
        # claim the next tile: threads that finish early (or run undisturbed) take more tiles
        q = atomic_add(claim, 0, 1)
        if q >= ntiles:
            break
        tile = order[q]
        start = tile_start[tile]
        L = tile_start[tile + 1] - start
        if not presorted:
            sort_segment(lst, start, L, rec, keys, keys2, idx, idx2, hist)
        x0 = (tile % tiles_x) * 16
        y0 = (tile // tiles_x) * 16
        nx = min(16, width - x0)
        ny = min(16, height - y0)
        # rowbits[ly]: bit lx set while pixel (lx, ly) is still compositing
        full_row = (1 << nx) - 1
        nactive_rows = ny
        for ly in range(16):
            rowbits[ly] = full_row if ly < ny else 0
        S[:] = zero
        for p in range(256):
            plx = ((p >> 7) << 3) + (p & 7)
            ply = (p >> 3) & 15
            S[_S_PX + p] = F(x0 + plx) + half
            S[_S_PY + p] = F(y0 + ply) + half
            S[_S_T + p] = one
            S[_S_LAST + p] = -one if (plx < nx and ply < ny) else zero  # outside the image: stopped
        if D > 0:
            facc[:] = zero
        for k in range(L):
            if nactive_rows == 0:
                break
            i = lst[start + k]
            lx0 = max(np.int64(rec[i, R_X0]) - x0, 0)
            lx1 = min(np.int64(rec[i, R_X1]) - x0, 15)
            ly0 = max(np.int64(rec[i, R_Y0]) - y0, 0)
            ly1 = min(np.int64(rec[i, R_Y1]) - y0, 15)
            # rows of the box that still have an active pixel inside the box's columns
            colmask = ((2 << lx1) - 1) & ~((1 << lx0) - 1)
            while ly0 <= ly1 and (rowbits[ly0] & colmask) == 0:
                ly0 += 1
            while ly1 >= ly0 and (rowbits[ly1] & colmask) == 0:
                ly1 -= 1
            if ly0 > ly1:
                continue
            mx = rec[i, R_MX]
            my = rec[i, R_MY]
            ca = F(-0.5) * rec[i, R_CA]
            cb = rec[i, R_CB]
            cc = F(-0.5) * rec[i, R_CC]
            op = rec[i, R_OP]
            z = rec[i, R_Z]
            cr = rec[i, R_R]
            cg = rec[i, R_G]
            cbl = rec[i, R_B]
            kf = F(k)
            anyterm = False
            # per 8-pixel half of the tile that the box touches, one loop over its rows ly0..ly1
            # (contiguous; trip count unknown at compile time, so LLVM vectorises it instead of
            # unrolling it into scalar code); lanes outside the box get alpha < 1/255 and change
            # nothing
            for hh in range(lx0 >> 3, (lx1 >> 3) + 1):
                for pp in range((hh << 7) + (ly0 << 3), (hh << 7) + ((ly1 + 1) << 3)):
                    p = np.uint64(pp)
                    dx = mx - S[uPX + p]
                    dy = my - S[uPY + p]
                    power = ca * dx * dx + cc * dy * dy - cb * dx * dy
                    al = min(amax, op * splat_exp(power))
                    Tp = S[uT + p]
                    test = Tp * (one - al)
                    ok = (S[uL + p] < zero) & (al >= amin) & (power <= zero)
                    term = ok & (test < tmin)
                    con = ok & (test >= tmin)
                    w = al * Tp if con else zero
                    S[uR + p] += w * cr
                    S[uG + p] += w * cg
                    S[uB + p] += w * cbl
                    S[uD + p] += w * z
                    wm = S[uWM + p]
                    better = w > wm
                    S[uWM + p] = w if better else wm + zero
                    S[uKB + p] = kf if better else S[uKB + p] + zero
                    S[uT + p] = test if con else Tp + zero
                    S[uL + p] = kf if term else S[uL + p] + zero
                    S[uW + p] = w
                    anyterm |= term
            if D > 0:
                for d in range(D):
                    fd = feat[i, d]
                    fb = np.uint64(d * 256)
                    for hh in range(lx0 >> 3, (lx1 >> 3) + 1):
                        for pp in range((hh << 7) + (ly0 << 3), (hh << 7) + ((ly1 + 1) << 3)):
                            p = np.uint64(pp)
                            facc[fb + p] += S[uW + p] * fd
            if anyterm:
                # rare (each pixel stops once): refresh the active bits of the rows touched
                for ly in range(ly0, ly1 + 1):
                    bits = 0
                    for lx in range(nx):
                        if S[_S_LAST + ((lx >> 3) << 7) + (ly << 3) + (lx & 7)] >= zero:
                            continue
                        bits |= 1 << lx
                    if bits == 0 and rowbits[ly] != 0:
                        nactive_rows -= 1
                    rowbits[ly] = bits
        # write out
        for ly in range(ny):
            for lx in range(nx):
                p = ((lx >> 3) << 7) + (ly << 3) + (lx & 7)
                yy = y0 + ly
                xx = x0 + lx
                Tp = S[_S_T + p]
                rgb[yy, xx, 0] = S[_S_R + p] + Tp * bg0
                rgb[yy, xx, 1] = S[_S_G + p] + Tp * bg1
                rgb[yy, xx, 2] = S[_S_B + p] + Tp * bg2
                a = one - Tp
                alpha[yy, xx] = a
                depth[yy, xx] = S[_S_D + p] / a if a > zero else zero
                inst[yy, xx] = ids[lst[start + np.int64(S[_S_KBEST + p])]] if S[_S_WMAX + p] > Tp else np.int32(-1)
                for d in range(D):
                    feat_out[yy, xx, d] = facc[d * 256 + p]
                if save:
                    tfinal[yy, xx] = Tp
                    lp = S[_S_LAST + p]
                    last_out[yy, xx] = np.int32(lp) if lp >= zero else np.int32(L)


@pjit
def raster_forward(order,       # [n_tiles] int32 tiles, longest list first
                   claim,       # [1] int64 work counter (set to 0 here)
                   keys, keys2,  # [n_threads, max_len] uint sort scratch
                   idx, idx2,   # [n_threads, max_len] int32 sort scratch
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
                   presorted=False):   # lists already depth-sorted (`binning.sorted_fill`)
    """Sort each tile's list by depth (unless `presorted`), then composite it. Tiles are claimed
    one at a time from `order` by whichever thread is free (each tile's result is independent of
    the thread)."""
    nthr = keys.shape[0]
    claim[0] = 0
    for k in prange(nthr):
        _raster_tiles(order, claim, tile_start, lst, rec, ids, feat, width, height, tiles_x, bg,
                      rgb, depth, alpha, inst, feat_out, tfinal, last_out, save,
                      keys[k], keys2[k], idx[k], idx2[k], presorted)
