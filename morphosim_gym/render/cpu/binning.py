"""Binning of projected Gaussians into 16x16 tiles, per-tile depth sort, and thread planning.

Binning is a counting sort by tile: `projection.project_forward` counts per chunk, `bin_offsets`
turns the counts into list offsets, `bin_fill` writes Gaussian indices. Each chunk writes its
Gaussians in index order after those of earlier chunks, so every tile's list starts in
ascending index order; `sort_segment` then sorts one list by depth with a stable LSD radix sort
on the float bits of camera z. Ties therefore keep the original index order, which is what the
reference's stable global sort gives for the Gaussians of any one tile.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ._jit import R_Z, float_bits, jit, pjit

__all__ = ["bin_offsets", "bin_fill", "sorted_fill", "plan_tiles", "sort_segment", "argsort_int"]


@jit
def argsort_int(keys,   # [n] int64 >= 0
                out):   # [n] int64 out: stable ascending order of keys
    """Stable LSD radix argsort of small non-negative integers (cheaper to compile than np.argsort)."""
    n = keys.shape[0]
    tmp = np.empty(n, np.int64)
    hist = np.empty(256, np.int64)
    kmax = 0
    for k in range(n):
        out[k] = k
        kmax = max(kmax, keys[k])
    shift = 0
    src, dst = out, tmp
    swapped = False
    while kmax > 0:
        hist[:] = 0
        for k in range(n):
            hist[(keys[src[k]] >> shift) & 255] += 1
        acc = 0
        for d in range(256):
            c = hist[d]
            hist[d] = acc
            acc += c
        for k in range(n):
            j = src[k]
            d = (keys[j] >> shift) & 255
            dst[hist[d]] = j
            hist[d] += 1
        src, dst = dst, src
        swapped = not swapped
        shift += 8
        kmax >>= 8
    if swapped:
        out[:] = tmp


@jit
def bin_offsets(counts,       # [n_threads, n_tiles] int32
                tile_start,   # [n_tiles + 1] int64 out
                thread_off):  # [n_threads, n_tiles] int64 out
    """Prefix sums: tile t's list is lst[tile_start[t]:tile_start[t + 1]], and chunk k writes its
    entries for tile t from thread_off[k, t] on. Returns the total number of entries."""
    nthr, ntiles = counts.shape
    acc = 0
    for t in range(ntiles):
        tile_start[t] = acc
        for k in range(nthr):
            thread_off[k, t] = acc
            acc += counts[k, t]
    tile_start[ntiles] = acc
    return acc


@jit
def _fill_range(lo, hi, trect, tiles_x, off, lst):
    for i in range(lo, hi):
        tx0 = trect[0, i]
        tx1 = trect[1, i]
        if tx1 < tx0:
            continue
        ty0 = trect[2, i]
        ty1 = trect[3, i]
        if tx0 == tx1 and ty0 == ty1:
            t = ty0 * tiles_x + tx0
            lst[off[t]] = i
            off[t] += 1
            continue
        for ty in range(ty0, ty1 + 1):
            for tx in range(tx0, tx1 + 1):
                t = ty * tiles_x + tx
                lst[off[t]] = i
                off[t] += 1


@jit
def sorted_fill(ranges,      # [k, 2] int64 index ranges of the view's Gaussians, in index order
                trect,       # [4, N] int32
                rec,         # [N, 16]
                tiles_x,
                tile_start,  # [n_tiles + 1] int64 (`bin_offsets` of the projection's counts)
                lst):        # [n_entries] int32 out
    """`bin_fill` followed by `sort_segment` of every tile's list, done the other way round:
    the view's visible Gaussians are sorted by depth once (the same stable radix sort, so ties
    keep index order) and written into the tile lists in that order. Each tile's list comes
    out as the per-tile sort leaves it; one sort of V visible Gaussians costs less than
    sorting their E >= V tile entries in lists of ~100 (a 256-bin histogram per pass per tile)."""
    m = 0
    for r in range(ranges.shape[0]):
        for i in range(ranges[r, 0], ranges[r, 1]):
            if trect[1, i] >= trect[0, i]:
                m += 1
    vis = np.empty(max(m, 1), np.int32)
    m = 0
    for r in range(ranges.shape[0]):
        for i in range(ranges[r, 0], ranges[r, 1]):
            if trect[1, i] >= trect[0, i]:
                vis[m] = i
                m += 1
    n = max(m, 1)
    sort_segment(vis, 0, m, rec, np.empty(n, np.uint64), np.empty(n, np.uint64), np.empty(n, np.int32),
                 np.empty(n, np.int32), np.empty(256, np.int64))       # uint64 keys hold either float width's bits
    ntiles = tile_start.shape[0] - 1
    off = tile_start[:ntiles].copy()
    for k in range(m):
        i = vis[k]
        tx0 = trect[0, i]
        tx1 = trect[1, i]
        ty0 = trect[2, i]
        ty1 = trect[3, i]
        for ty in range(ty0, ty1 + 1):
            for tx in range(tx0, tx1 + 1):
                t = ty * tiles_x + tx
                lst[off[t]] = i
                off[t] += 1


@pjit
def bin_fill(trect,       # [4, N] int32
             tiles_x,
             thread_off,  # [n_threads, n_tiles] int64 (consumed)
             lst):        # [n_entries] int32 out
    """Write each Gaussian's index into the list of every tile its rectangle covers, with the same
    chunking as `project_forward` (so chunk k's entries land after chunk k - 1's)."""
    n = trect.shape[1]
    nthr = thread_off.shape[0]
    for k in prange(nthr):
        _fill_range(n * k // nthr, n * (k + 1) // nthr, trect, tiles_x, thread_off[k], lst)


@jit
def plan_tiles(tile_start,  # [n_tiles + 1] int64
               order_out):  # [n_tiles] int32 out: tiles by decreasing list length
    """Order the tiles longest list first: threads claim tiles in this order, so the long ones
    start early and the short ones fill the gaps at the end. Returns the longest list length."""
    ntiles = tile_start.shape[0] - 1
    lengths = np.empty(ntiles, np.int64)
    longest = 0
    for t in range(ntiles):
        lengths[t] = tile_start[t + 1] - tile_start[t]
        longest = max(longest, lengths[t])
    order = np.empty(ntiles, np.int64)
    for t in range(ntiles):
        lengths[t] = longest - lengths[t]
    argsort_int(lengths, order)   # longest first, ties in tile order
    for q in range(ntiles):
        order_out[q] = order[q]
    return longest


@jit
def sort_segment(lst,     # [n_entries] int32, the segment is sorted in place
                 start, length,
                 rec,     # [N, 16]
                 keys,    # [>= length] uint32 (float32 records) / uint64 (float64) scratch
                 keys2,   # same
                 idx,     # [>= length] int32 scratch
                 idx2,    # [>= length] int32 scratch
                 hist):   # [256] int64 scratch
    """Stable sort of lst[start:start + length] by the camera depth of its Gaussians.

    Camera depths are > near > 0, so their IEEE bits order like the floats. The radix sort works
    on key - min(key) and runs only as many 8-bit passes as the key range needs.
    """
    if length < 2:
        return
    kmin = float_bits(rec[lst[start], R_Z])
    kmax = kmin
    for k in range(length):
        i = lst[start + k]
        kb = float_bits(rec[i, R_Z])
        keys[k] = kb
        idx[k] = i
        kmin = min(kmin, kb)
        kmax = max(kmax, kb)
    if length <= 32:
        # insertion sort (stable: an entry only moves past strictly greater keys)
        for k in range(1, length):
            kb = keys[k]
            v = idx[k]
            j = k - 1
            while j >= 0 and keys[j] > kb:
                keys[j + 1] = keys[j]
                idx[j + 1] = idx[j]
                j -= 1
            keys[j + 1] = kb
            idx[j + 1] = v
        for k in range(length):
            lst[start + k] = idx[k]
        return
    for k in range(length):
        keys[k] -= kmin
    rng = kmax - kmin
    shift = 0
    src_k, dst_k = keys, keys2
    src_i, dst_i = idx, idx2
    while rng > 0:
        hist[:] = 0
        for k in range(length):
            hist[(src_k[k] >> shift) & 255] += 1
        acc = 0
        for d in range(256):
            c = hist[d]
            hist[d] = acc
            acc += c
        for k in range(length):
            kb = src_k[k]
            d = (kb >> shift) & 255
            pos = hist[d]
            hist[d] = pos + 1
            dst_k[pos] = kb
            dst_i[pos] = src_i[k]
        src_k, dst_k = dst_k, src_k
        src_i, dst_i = dst_i, src_i
        shift += 8
        rng >>= 8
    for k in range(length):
        lst[start + k] = src_i[k]
