"""Batched forward rendering: many views (each its own Gaussians, camera, size and background)
in one projection, one binning and one raster pass, parallel over the views' work together.

A view is exactly what `pipeline.render_camera` renders, and its pixels are bit-identical to it:
the stages call the same per-range kernels (`projection._project_range`, `binning._fill_range`,
`binning.plan_tiles`, `forward._raster_tiles`) on the same per-view data, only scheduled
together. The Gaussians of all views are concatenated into one set of arrays; view v owns the
index range goff[v]:goff[v + 1], its own tile grid, its own segment of the tile lists and its
own output block.

* projection and list filling run over work items (v, lo, hi): about four equal slices of the
  total per thread, never crossing a view, each with its own tile counts; as a `prange` from
  `SERIAL_BELOW` Gaussians on, on the calling thread below that;
* with `cull=True`, object-level culling (`cull.cull_view`) first drops runs of one object's
  Gaussians whose bounding sphere is outside the view's frustum, so they get no work item;
* offsets are a serial prefix sum over views, tiles and items (each view's list segment starts
  where the previous view's ends, and within a tile items follow in index order, which keeps
  each tile list in ascending index order as the single path does);
* rasterisation runs one task per thread; each walks the views in order and claims their tiles
  (longest list first within a view) from a per-view counter shared by all threads, so both
  cores work on one view's tiles together and move on to the next view when it runs out.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numba
import numpy as np
from numba import prange

from ._jit import NREC, jit, pjit
from .binning import _fill_range, plan_tiles, sorted_fill
from .cull import cull_view
from .forward import _raster_tiles
from .pipeline import _PRESORT_ENTRIES_PER_TILE, Workspace, thread_workspace
from .projection import _project_range

__all__ = ["rasterize_batch_numpy", "BatchView", "batch_view", "Staged", "stage_views", "view_outputs"]

_KEY_DTYPE = np.uint32
_MAX_TILE_LIST = 1 << 24
_ITEMS_PER_THREAD = 4
_MIN_ITEM = 1024
SERIAL_BELOW = 1 << 16
"""Batches of fewer Gaussians project and bin on the calling thread (a few hundred microseconds
at most) and run only the raster as a parallel region: every parallel region ends in a join that
waits for the slowest thread, which costs milliseconds when the cores are shared."""


class BatchView:
    """One view of a batch: its Gaussians as one or more parts (lists of arrays, composited
    together in list order as `Gaussians.concat` would), one camera, an image size and a
    background. Build it with `batch_view`."""

    __slots__ = ("means", "quats", "scales", "opacities", "colors", "ids", "features", "viewmat", "K", "near",
                 "width", "height", "background")

    def __init__(self, means: list, quats: list, scales: list, opacities: list, colors: list, ids: list,
                 features: Optional[list], viewmat, K, near: float, width: int, height: int, background) -> None:
        self.means, self.quats, self.scales, self.opacities, self.colors = means, quats, scales, opacities, colors
        self.ids, self.features = ids, features
        self.viewmat, self.K, self.near = viewmat, K, float(near)
        self.width, self.height = int(width), int(height)
        self.background = background

    @property
    def size(self) -> int:
        """Number of Gaussians of the view (all parts)."""
        return sum(len(m) for m in self.means)


@pjit
def _project_items(items,      # [n_items, 3] int64: view, lo, hi (global Gaussian indices)
                   means, quats, scales, opacities, colors, feat,
                   viewmats,   # [V, 4, 4]
                   Ks,         # [V, 3, 3]
                   sizes,      # [V, 3] int64: width, height, tiles_x
                   nears,      # [V] float32
                   rec, trect,
                   counts):    # [n_items, max_tiles] int32 out
    for k in prange(items.shape[0]):
        v = items[k, 0]
        _project_range(items[k, 1], items[k, 2], 0, means, quats, scales, opacities, colors, feat, viewmats[v], Ks[v],
                       sizes[v, 0], sizes[v, 1], nears[v], rec, trect, sizes[v, 2], counts[k])


@jit
def _project_items_serial(items, means, quats, scales, opacities, colors, feat, viewmats, Ks, sizes, nears, rec, trect,
                          counts):
    """`_project_items` on the calling thread (small batches: no parallel region to join)."""
    for k in range(items.shape[0]):
        v = items[k, 0]
        _project_range(items[k, 1], items[k, 2], 0, means, quats, scales, opacities, colors, feat, viewmats[v], Ks[v],
                       sizes[v, 0], sizes[v, 1], nears[v], rec, trect, sizes[v, 2], counts[k])


@jit
def _offsets(items,        # [n_items, 3] int64 (items of a view contiguous, in index order)
             item_start,   # [V + 1] int64: items of view v are item_start[v]:item_start[v + 1]
             ntiles,       # [V] int64
             tstart,       # [V + 1] int64: view v's tile_start is tile_start[tstart[v]:tstart[v + 1]]
             counts,       # [n_items, max_tiles] int32
             tile_start,   # [sum(ntiles) + V] int64 out (per view, relative to its list segment)
             item_off,     # [n_items, max_tiles] int64 out (global list positions, consumed by the fill)
             lst_base,     # [V + 1] int64 out: view v's list segment
             order,        # [sum(ntiles)] int32 out: per view, its tiles longest list first
             max_len):     # [V] int64 out
    acc = 0
    for v in range(ntiles.shape[0]):
        lst_base[v] = acc
        base = tstart[v]
        for t in range(ntiles[v]):
            tile_start[base + t] = acc - lst_base[v]
            for k in range(item_start[v], item_start[v + 1]):
                item_off[k, t] = acc
                acc += counts[k, t]
        tile_start[base + ntiles[v]] = acc - lst_base[v]
        ob = base - v
        max_len[v] = plan_tiles(tile_start[base:base + ntiles[v] + 1], order[ob:ob + ntiles[v]])
    lst_base[ntiles.shape[0]] = acc
    return acc


@pjit
def _fill_items(items, sizes, trect, item_off, lst):
    for k in prange(items.shape[0]):
        _fill_range(items[k, 1], items[k, 2], trect, sizes[items[k, 0], 2], item_off[k], lst)


@jit
def _fill_items_serial(items, sizes, trect, item_off, lst):
    """`_fill_items` on the calling thread."""
    for k in range(items.shape[0]):
        _fill_range(items[k, 1], items[k, 2], trect, sizes[items[k, 0], 2], item_off[k], lst)


@pjit
def _sorted_fill_views(ranges, rstart, sizes, tstart, tile_start, lst_base, trect, rec, lst):
    """`binning.sorted_fill` of every view (views in parallel)."""
    for v in prange(sizes.shape[0]):
        sorted_fill(ranges[rstart[v]:rstart[v + 1]], trect, rec, sizes[v, 2], tile_start[tstart[v]:tstart[v + 1]],
                    lst[lst_base[v]:lst_base[v + 1]])


@jit
def _sorted_fill_views_serial(ranges, rstart, sizes, tstart, tile_start, lst_base, trect, rec, lst):
    """`_sorted_fill_views` on the calling thread."""
    for v in range(sizes.shape[0]):
        sorted_fill(ranges[rstart[v]:rstart[v + 1]], trect, rec, sizes[v, 2], tile_start[tstart[v]:tstart[v + 1]],
                    lst[lst_base[v]:lst_base[v + 1]])


@jit
def _raster_views(v_lo, v_hi, claims, order, tstart, tile_start, lst_base, lst, rec, ids, feat, sizes, bgs,
                  pix_off, rgb, depth, alpha, inst, feat_out, tfinal, last, keys, keys2, idx, idx2, presorted):
    D = feat.shape[1]
    for v in range(v_lo, v_hi):
        w = sizes[v, 0]
        h = sizes[v, 1]
        npx = w * h
        p0 = pix_off[v]
        ob = tstart[v] - v
        nt = tstart[v + 1] - tstart[v] - 1
        _raster_tiles(order[ob:ob + nt], claims[v:v + 1], tile_start[tstart[v]:tstart[v + 1]],
                      lst[lst_base[v]:lst_base[v + 1]], rec, ids, feat, w, h, sizes[v, 2], bgs[v],
                      rgb[3 * p0:3 * (p0 + npx)].reshape((h, w, 3)), depth[p0:p0 + npx].reshape((h, w)),
                      alpha[p0:p0 + npx].reshape((h, w)), inst[p0:p0 + npx].reshape((h, w)),
                      feat_out[D * p0:D * (p0 + npx)].reshape((h, w, D)), tfinal, last, False,
                      keys, keys2, idx, idx2, presorted)


@pjit
def _raster_items(claims, order, tstart, tile_start, lst_base, lst, rec, ids, feat, sizes, bgs, pix_off,
                  rgb, depth, alpha, inst, feat_out, tfinal, last, keys, keys2, idx, idx2, presorted):
    nthr = keys.shape[0]
    claims[:] = 0
    V = sizes.shape[0]
    for k in prange(nthr):
        _raster_views(0, V, claims, order, tstart, tile_start, lst_base, lst, rec, ids, feat, sizes, bgs, pix_off,
                      rgb, depth, alpha, inst, feat_out, tfinal, last, keys[k], keys2[k], idx[k], idx2[k],
                      presorted)


def _work_items(goff: np.ndarray, nthr: int, kept: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(items [n, 3] of (view, lo, hi), item_start [V + 1]): each view's kept ranges cut into
    slices of about total / (4 * threads) Gaussians (at least `_MIN_ITEM`)."""
    total = sum(int((r[:, 1] - r[:, 0]).sum()) for r in kept)
    step = max(_MIN_ITEM, -(-total // max(1, nthr * _ITEMS_PER_THREAD)))
    rows, starts = [], [0]
    for v, ranges in enumerate(kept):
        for lo, hi in ranges.tolist():
            for b in range(lo, hi, step):
                rows.append((v, b, min(b + step, hi)))
        starts.append(len(rows))
    items = np.array(rows, np.int64).reshape(-1, 3)
    return items, np.array(starts, np.int64)


def _kept_ranges(goff, means, scales, opac, ids, viewmats, Ks, sizes, nears, cull: bool) -> list[np.ndarray]:
    """Per view, the [k, 2] index ranges left after object-level culling (`cull.cull_view`)."""
    out = []
    for v in range(len(goff) - 1):
        lo, hi = int(goff[v]), int(goff[v + 1])
        if not cull or hi == lo:
            out.append(np.array([[lo, hi]] if hi > lo else [], np.int64).reshape(-1, 2))
            continue
        keep = np.empty((hi - lo, 2), np.int64)      # at most one range per Gaussian
        k = cull_view(means, scales, opac, ids, lo, hi, viewmats[v].astype(np.float64), Ks[v].astype(np.float64),
                      int(sizes[v, 0]), int(sizes[v, 1]), float(nears[v]), keep)
        out.append(keep[:k])
    return out


def _concat(views: Sequence[BatchView], name: str, width: int, dtype, ws: Optional[Workspace] = None) -> np.ndarray:
    """One field of every view's parts, concatenated (into `ws`'s buffer of that name when given:
    a fresh array of megabytes costs page faults on every call)."""
    parts = [x for v in views for x in getattr(v, name)]
    if not parts:
        return np.empty((0, width), dtype) if width else np.empty(0, dtype)
    if len(parts) == 1:
        return np.ascontiguousarray(parts[0], dtype=dtype)
    if ws is None:
        return np.ascontiguousarray(np.concatenate(parts), dtype=dtype)
    n = sum(len(p) for p in parts)
    out = ws.get("in_" + name, (n, width) if width else (n,), dtype)
    return np.concatenate(parts, out=out, casting="same_kind")


class Staged:
    """A batch's inputs as the kernels take them (`stage_views`): all views' Gaussians
    concatenated (view v owns goff[v]:goff[v + 1]), per-view cameras, sizes, backgrounds, pixel
    offsets, and the index ranges left after culling (view v's are ranges[rstart[v]:rstart[v + 1]])."""

    __slots__ = ("V", "counts_n", "goff", "means", "quats", "scales", "opac", "colors", "ids", "feat", "sizes",
                 "ntiles", "tstart", "pix_off", "viewmats", "Ks", "nears", "bgs", "kept", "ranges", "rstart",
                 "features")

    def __init__(self, **fields) -> None:
        for k, v in fields.items():
            setattr(self, k, v)


def stage_views(views: Sequence[BatchView], features: bool = False, cull: bool = False,
                ws: Optional[Workspace] = None) -> Staged:
    """The `Staged` inputs of a batch (checks the feature dimensions); the concatenated Gaussians
    go into `ws`'s buffers when given (valid until the next batch staged in `ws`)."""
    f32 = np.float32
    V = len(views)
    counts_n = np.array([v.size for v in views], np.int64)
    goff = np.zeros(V + 1, np.int64)
    np.cumsum(counts_n, out=goff[1:])
    means = _concat(views, "means", 3, f32, ws)
    quats = _concat(views, "quats", 4, f32, ws)
    scales = _concat(views, "scales", 3, f32, ws)
    opac = _concat(views, "opacities", 0, f32, ws)
    colors = _concat(views, "colors", 3, f32, ws)
    ids = _concat(views, "ids", 0, np.int32, ws)
    n = means.shape[0]
    if features:
        dims = {-1 if v.features is None else (v.features[0].shape[1] if v.features else 0) for v in views}
        if len(dims) != 1 or -1 in dims:
            raise ValueError(f"Expected features of one dimension D in every view, found {sorted(dims)}")
        feat = _concat(views, "features", dims.pop(), f32, ws)
    else:
        feat = np.empty((n, 0), f32)
    sizes = np.array([(v.width, v.height, (v.width + 15) // 16) for v in views], np.int64).reshape(-1, 3)
    ntiles = sizes[:, 2] * ((sizes[:, 1] + 15) // 16)
    tstart = np.zeros(V + 1, np.int64)
    np.cumsum(ntiles + 1, out=tstart[1:])
    npx = sizes[:, 0] * sizes[:, 1]
    pix_off = np.zeros(V + 1, np.int64)
    np.cumsum(npx, out=pix_off[1:])
    if V:
        viewmats = np.ascontiguousarray(np.stack([v.viewmat for v in views]), f32)
        Ks = np.ascontiguousarray(np.stack([v.K for v in views]), f32)
        bgs = np.ascontiguousarray(np.stack([v.background for v in views]), f32)
    else:
        viewmats, Ks, bgs = np.empty((0, 4, 4), f32), np.empty((0, 3, 3), f32), np.empty((0, 3), f32)
    nears = np.array([v.near for v in views], f32)
    kept = _kept_ranges(goff, means, scales, opac, ids, viewmats, Ks, sizes, nears, cull)
    rstart = np.zeros(V + 1, np.int64)
    np.cumsum([len(r) for r in kept], out=rstart[1:])
    ranges = np.ascontiguousarray(np.concatenate(kept) if kept else np.empty((0, 2), np.int64), np.int64)
    return Staged(V=V, counts_n=counts_n, goff=goff, means=means, quats=quats, scales=scales, opac=opac,
                  colors=colors, ids=ids, feat=feat, sizes=sizes, ntiles=ntiles, tstart=tstart, pix_off=pix_off,
                  viewmats=viewmats, Ks=Ks, nears=nears, bgs=bgs, kept=kept, ranges=ranges.reshape(-1, 2),
                  rstart=rstart, features=bool(features))


def view_outputs(s: Staged, rgb, depth, alpha, inst, fout, lo: int = 0, hi: Optional[int] = None) -> list[dict]:
    """Per view lo..hi - 1 (default all), its blocks of the flat output buffers as
    `rasterize_batch_numpy` returns them."""
    D = s.feat.shape[1]
    out = []
    for v in range(lo, s.V if hi is None else hi):
        w, h = int(s.sizes[v, 0]), int(s.sizes[v, 1])
        p0, p1 = int(s.pix_off[v]), int(s.pix_off[v + 1])
        out.append({"rgb": rgb[3 * p0:3 * p1].reshape(h, w, 3), "depth": depth[p0:p1].reshape(h, w),
                    "alpha": alpha[p0:p1].reshape(h, w), "instance": inst[p0:p1].reshape(h, w),
                    "features": fout[D * p0:D * p1].reshape(h, w, D) if s.features else None})
    return out


def rasterize_batch_numpy(views: Sequence[BatchView], features: bool = False, cull: bool = False) -> list[dict]:
    """Forward-only float32 splatting of several views in one pass (see the module docstring).

    Args:
        views: the views (`BatchView`: float32 C-contiguous arrays as `rasterize_numpy` takes
            them for one camera; `ids` int32; `features` [N, D] or None).
        features: also render the D feature channels (every view must have the same D).
        cull: skip runs of Gaussians outside a view's frustum before projecting them
            (`cull.cull_view`; the images are identical either way).

    Returns:
        One dict per view, as `rasterize_numpy` returns for one camera without the camera axis:
        `rgb` [H, W, 3], `depth` [H, W], `alpha` [H, W], `instance` [H, W] int32, `features`
        [H, W, D] or None. The arrays are views into one fresh buffer per field.
    """
    f32 = np.float32
    V = len(views)
    if V == 0:
        return []
    nthr = numba.get_num_threads()
    ws = thread_workspace("batch")
    s = stage_views(views, features, cull, ws)
    means, quats, scales, opac, colors, ids, feat = s.means, s.quats, s.scales, s.opac, s.colors, s.ids, s.feat
    sizes, ntiles, tstart, pix_off = s.sizes, s.ntiles, s.tstart, s.pix_off
    viewmats, Ks, nears, bgs = s.viewmats, s.Ks, s.nears, s.bgs
    n = means.shape[0]
    D = feat.shape[1]

    items, item_start = _work_items(s.goff, nthr, s.kept)
    max_tiles = max(int(ntiles.max()), 1)
    rec = ws.get("rec", (n, NREC), f32)
    trect = ws.get("trect", (4, n), np.int32)
    counts = ws.get("counts", (max(len(items), 1), max_tiles), np.int32)
    serial = n < SERIAL_BELOW or nthr == 1
    if len(items):
        project = _project_items_serial if serial else _project_items
        project(items, means, quats, scales, opac, colors, feat, viewmats, Ks, sizes, nears, rec, trect, counts)
    tile_start = ws.get("tile_start", (int(tstart[-1]),), np.int64)
    item_off = ws.get("item_off", (max(len(items), 1), max_tiles), np.int64)
    lst_base = ws.get("lst_base", (V + 1,), np.int64)
    order = ws.get("order", (int(ntiles.sum()),), np.int32)
    max_len = ws.get("max_len", (V,), np.int64)
    total = _offsets(items, item_start, ntiles, tstart, counts, tile_start, item_off, lst_base, order, max_len)
    longest = int(max_len.max())
    if longest >= _MAX_TILE_LIST:
        raise ValueError(f"Expected at most {_MAX_TILE_LIST - 1} Gaussians over one 16x16 tile in float32, "
                         f"found {longest} (list positions are kept as floats)")
    lst = ws.get("lst", (int(total),), np.int32)
    # depth-sorted fills per view (one sort of each view's visible Gaussians) where the lists are
    # short or there is one thread; else per-tile sorts in the parallel raster (same lists)
    presorted = serial or int(total) <= _PRESORT_ENTRIES_PER_TILE * int(ntiles.sum())
    if len(items) and presorted:
        (_sorted_fill_views_serial if serial else _sorted_fill_views)(s.ranges, s.rstart, sizes, tstart, tile_start,
                                                                       lst_base, trect, rec, lst)
    elif len(items):
        (_fill_items_serial if serial else _fill_items)(items, sizes, trect, item_off, lst)
    m = max(longest, 1)
    keys = ws.get("keys", (nthr, m), _KEY_DTYPE)
    keys2 = ws.get("keys2", (nthr, m), _KEY_DTYPE)
    idx = ws.get("idx", (nthr, m), np.int32)
    idx2 = ws.get("idx2", (nthr, m), np.int32)
    P = int(pix_off[-1])
    rgb = np.empty(3 * P, f32)
    depth = np.empty(P, f32)
    alpha = np.empty(P, f32)
    inst = np.empty(P, np.int32)
    fout = np.empty(D * P, f32)
    claims = ws.get("claims", (V,), np.int64)
    _raster_items(claims, order, tstart, tile_start, lst_base, lst, rec, ids, feat, sizes, bgs, pix_off,
                  rgb, depth, alpha, inst, fout, _DUMMY_F, _DUMMY_I, keys, keys2, idx, idx2, presorted)
    return view_outputs(s, rgb, depth, alpha, inst, fout)


_DUMMY_F = np.empty((1, 1), np.float32)
_DUMMY_I = np.empty((1, 1), np.int32)


def batch_view(parts: Sequence, viewmat, K, near: float, width: int, height: int,
               background: Optional[np.ndarray] = None) -> BatchView:
    """A `BatchView` of Gaussian parts (objects with `means`, `quats`, `scales`, `opacities`,
    `colors`, optional `object_ids` and `features`, e.g. `Gaussians`), as `Gaussians.concat`
    composites them: features only when every part has them with one D, ids -1 where missing."""
    parts = list(parts)
    dims = {0 if getattr(p, "features", None) is None else p.features.shape[1] for p in parts}
    keep_features = bool(parts) and 0 not in dims and len(dims) == 1

    def ids(p) -> np.ndarray:
        oid = getattr(p, "object_ids", None)
        return np.full(len(p.means), -1, np.int32) if oid is None else np.asarray(oid, np.int32)

    bg = np.zeros(3, np.float32) if background is None else np.asarray(background, np.float32)
    return BatchView([p.means for p in parts], [p.quats for p in parts], [p.scales for p in parts],
                     [p.opacities for p in parts], [p.colors for p in parts], [ids(p) for p in parts],
                     [p.features for p in parts] if keep_features else None, np.asarray(viewmat, np.float32),
                     np.asarray(K, np.float32), near, width, height, bg)
