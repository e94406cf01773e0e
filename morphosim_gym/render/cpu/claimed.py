"""Batched forward rendering shared by Python threads: every thread that calls `ClaimedBatch.work`
claims whole views of the batch (in view order) and renders each one start to finish (projection,
binning, raster) in one compiled call that holds no GIL.

This is the batch path for callers that have Python work of their own beside the render (the
vector env: rig, rewards, observations of other envs). A batch is a stream: the caller `add`s
views one at a time (each is staged and published at once) and `close`s it after the last; a
`RenderHelpers` thread starts on the first view while the caller prepares the next ones (when it
has caught up with them it looks for the next one without the GIL for ~0.5 ms, then sleeps), and
the caller joins in (`RenderHelpers.complete` / `partial`) when its own work is done. Both cores
render, without a numba parallel region whose join waits for a thread the caller's Python work
keeps busy, and with projection and binning parallel too (as whole views).

Pixels are bit-identical to `batch.rasterize_batch_numpy` and to the single-camera path: a view
runs the same per-range kernels (`_project_range`, `_fill_range`, `plan_tiles`, `_raster_tiles`)
with its tile lists in ascending Gaussian index order, on whichever thread claims it.

A view's Gaussians are not copied when their arrays are read-only float32 in C order (the frozen
arrays `Scene4D.at` gives): the batch keeps them and their addresses, and the projection reads them
in place (a staging copy cost this thread ~17 us a view and moved ~0.2 MB between the cores' caches).
Arrays a caller may still write are copied when the view is added.
"""

from __future__ import annotations

import queue
import threading
import time
from typing import Optional, Sequence

import numpy as np

from ._jit import NREC, atomic_add, atomic_cas, f32_rows, f32_vector, jit
from .batch import _MAX_TILE_LIST, BatchView, Staged, view_outputs
from .binning import bin_offsets, plan_tiles, sorted_fill
from .cull import cull_view
from .forward import _raster_tiles
from .pipeline import Workspace
from .projection import _project_range
from .sky import composite_view, sky_camera

__all__ = ["ClaimedBatch", "RenderHelpers"]

_POLL_S = 50e-6           # sleep between looks at a helper's view that is still rendering
_WAIT_S = 600.0            # a helper that takes longer over its last view is hung: raise instead of waiting
_HANDOVER_SPINS = 10_000   # ~50-100 us of looking for a helper to start on a batch (`RenderHelpers.handover`)
_HANDOVER_NAPS = 10        # then this many `_POLL_S` sleeps
_SERVE_SPINS = 30_000     # ~0.5 ms of looking (no GIL) for an open batch's next view before a helper sleeps
_READY_SPINS = 30_000     # ~0.5 ms of looking (no GIL) for a helper's view to be done before sleeping between looks
_IDLE_SPINS = (30_000, 400_000)   # ~0.15 / ~2 ms of looking (no GIL) for the next batch before a helper sleeps

_PARTS_PER_VIEW = 4        # source rows a batch sized by capacity keeps per view (a view with more: concatenated)

# the batch's shared counters (int64, changed only atomically once a thread may be working)
_NEXT, _FINISHED, _PUBLISHED, _CLOSED, _ENTERED, _CLAIMED = range(6)


@jit
def _render_view(v, ranges,    # [k, 2] int64 kept index ranges of all views, view by view
                 rsrc,         # [k] int64: the row of `src` each range's inputs are read from
                 rstart,       # [V + 1] int64: view v's ranges are ranges[rstart[v]:rstart[v + 1]]
                 src,          # [S, 7] int64: first Gaussian index, count, then the addresses of means,
                               # quats, scales, opacities and colors (float32, C order) of each input part
                 feat, ids,    # [N, D] float32, [N] int32 staged
                 viewmats,     # [V, 4, 4]
                 Ks,           # [V, 3, 3]
                 sizes,        # [V, 3] int64: width, height, tiles_x
                 nears,        # [V] float32
                 bgs,          # [V, 3]
                 skies,        # [V, 3] int64: address, rows, columns of view v's sky image (float32 [H', W', 3]; 0: none)
                 sky_cam,      # [V, 13] float64: view v's world-to-camera rotation (row-major), fx, fy, cx, cy
                 pix_off,      # [V + 1] int64
                 rec, trect,   # [N, 16], [4, N] shared scratch (view v writes only its own rows)
                 rgb, depth, alpha, inst, feat_out,   # flat outputs, view v's block at pix_off[v]
                 dummy_f, dummy_i):   # [1, 1] float32 / int32 stand-ins for the backward-only outputs
    """Render view v on the calling thread (its sky behind it, when it has one); returns its
    longest tile list."""
    w = sizes[v, 0]
    h = sizes[v, 1]
    tx = sizes[v, 2]
    nt = tx * ((h + 15) // 16)
    r0 = rstart[v]
    nr = rstart[v + 1] - r0
    counts = np.zeros((max(nr, 1), nt), np.int32)
    for r in range(nr):
        s = rsrc[r0 + r]
        m = src[s, 1]
        _project_range(ranges[r0 + r, 0], ranges[r0 + r, 1], src[s, 0], f32_rows(src[s, 2], m, 3),
                       f32_rows(src[s, 3], m, 4), f32_rows(src[s, 4], m, 3), f32_vector(src[s, 5], m),
                       f32_rows(src[s, 6], m, 3), feat, viewmats[v], Ks[v], w, h, nears[v], rec, trect, tx, counts[r])
    # tile lists in depth order (ties in index order), as the per-tile sort of every other path leaves them
    tile_start = np.empty(nt + 1, np.int64)
    off = np.empty((max(nr, 1), nt), np.int64)
    acc = bin_offsets(counts[:nr], tile_start, off[:nr])
    lst = np.empty(max(acc, 1), np.int32)
    sorted_fill(ranges[r0:r0 + nr], trect, rec, tx, tile_start, lst)
    order = np.empty(nt, np.int32)
    longest = plan_tiles(tile_start, order)
    keys = np.empty(1, np.uint32)            # no per-tile sort: no sort scratch
    keys2 = np.empty(1, np.uint32)
    idx = np.empty(1, np.int32)
    idx2 = np.empty(1, np.int32)
    claim = np.zeros(1, np.int64)
    D = feat.shape[1]
    p0 = pix_off[v]
    npx = w * h
    _raster_tiles(order, claim, tile_start, lst, rec, ids, feat, w, h, tx, bgs[v],
                  rgb[3 * p0:3 * (p0 + npx)].reshape((h, w, 3)), depth[p0:p0 + npx].reshape((h, w)),
                  alpha[p0:p0 + npx].reshape((h, w)), inst[p0:p0 + npx].reshape((h, w)),
                  feat_out[D * p0:D * (p0 + npx)].reshape((h, w, D)), dummy_f, dummy_i, False,
                  keys, keys2, idx, idx2, True)
    if skies[v, 0] != 0:
        sh = skies[v, 1]
        sw = skies[v, 2]
        cam = sky_cam[v]
        composite_view(rgb[3 * p0:3 * (p0 + npx)].reshape((h, w, 3)), alpha[p0:p0 + npx].reshape((h, w)),
                       f32_rows(skies[v, 0], sh * sw, 3).reshape((sh, sw, 3)), cam[:9].reshape((3, 3)),
                       cam[9], cam[10], cam[11], cam[12])
    return longest


@jit
def _work(state,          # [6] int64: next view (in order), views finished, published, closed, threads entered, claimed
          limit,          # most views this call renders (< 0: no limit)
          spin,           # while the batch is open, look this many times for a view to be published
          last_first,     # claim the last unclaimed view first (a caller that finishes views in any order)
          claimed,        # [V] int64: 1 once view v is claimed
          vdone,          # [V] int64: 1 once view v is rendered
          longest,        # [V] int64 out: each view's longest tile list
          ranges, rsrc, rstart, src, feat, ids, viewmats, Ks, sizes, nears, bgs, skies, sky_cam,
          pix_off, rec, trect, rgb, depth, alpha, inst, feat_out, dummy_f, dummy_i):
    """Claim published views one at a time (in view order, or the last first with `last_first`)
    and render each, until none is left to claim or `limit` are rendered; returns how many this
    call rendered (never waits). Each view is claimed once, by whichever thread flips its flag."""
    atomic_add(state, 4, 1)                 # _ENTERED: a thread is at work (see `RenderHelpers.handover`)
    done = 0
    idle = 0
    while limit < 0 or done < limit:
        published = atomic_add(state, 2, 0)
        if last_first:
            v = published - 1
            while v >= 0 and (claimed[v] != 0 or atomic_cas(claimed, v, 0, 1) != 0):
                v -= 1
            if v < 0:
                break
        else:
            v = atomic_add(state, 0, 0)     # _NEXT
            if v >= published:              # nothing published left to claim
                if idle >= spin or atomic_add(state, 3, 0) != 0:
                    break
                idle += 1                    # open: the caller is staging the next view
                continue
            if atomic_cas(state, 0, v, v + 1) != v:
                continue                     # another thread moved past v first
            if atomic_cas(claimed, v, 0, 1) != 0:
                continue                     # claimed from the end already
        idle = 0
        atomic_add(state, 5, 1)              # _CLAIMED
        longest[v] = _render_view(v, ranges, rsrc, rstart, src, feat, ids, viewmats, Ks, sizes, nears, bgs,
                                  skies, sky_cam, pix_off, rec, trect, rgb, depth, alpha, inst, feat_out, dummy_f, dummy_i)
        atomic_add(vdone, v, 1)            # seq_cst: the view's pixels are written before its flag
        atomic_add(state, 1, 1)            # _FINISHED
        done += 1
    return done


@jit
def _bump(state, k):
    """state[k] += 1 atomically (publish a view, close the batch)."""
    atomic_add(state, k, 1)


@jit
def _wait_entered(state, posted, post, spins):
    """Count a posted batch first if `post` (`RenderHelpers.submit`), then spin (without the GIL)
    until a thread has entered `_work` on this batch, at most `spins` looks; whether one has."""
    if post:
        atomic_add(posted, 0, 1)
    for _ in range(spins):
        if atomic_add(state, 4, 0) > 0:
            return True
    return False


@jit
def _wait_posted(posted, before, spins):
    """Spin (without the GIL) until the count of posted batches is no longer `before`, at most
    `spins` looks; how many looks that took (-1: it did not change)."""
    for k in range(spins):
        if atomic_add(posted, 0, 0) != before:
            return k
    return -1


@jit
def _wait_done(vdone, views, spins):
    """Spin (without the GIL) until one of these views is rendered, at most `spins` looks; whether
    one is."""
    for _ in range(spins):
        for j in range(views.shape[0]):
            if atomic_add(vdone, views[j], 0) != 0:
                return True
    return False


@jit
def _reference(src, s, first, means, quats, scales, opacities, colors):
    """Source row s: Gaussians first.. are read from these arrays (float32, C order) in place."""
    src[s, 0] = first
    src[s, 1] = means.shape[0]
    src[s, 2] = means.ctypes.data
    src[s, 3] = quats.ctypes.data
    src[s, 4] = scales.ctypes.data
    src[s, 5] = opacities.ctypes.data
    src[s, 6] = colors.ctypes.data


_FROZEN_SHAPES = ((3,), (4,), (3,), (), (3,))       # row shapes of means, quats, scales, opacities, colors


def _input_parts(fields: list, room: int) -> list:
    """A view's non-empty parts as (means, quats, scales, opacities, colors) tuples the kernels
    may read in place: read-only C-order float32 arrays as they are, others copied; more parts
    than `room` source rows left are concatenated into one."""
    parts = [part for part in zip(*fields) if len(part[0])]
    if len(parts) > max(room, 1):
        parts = [tuple(np.concatenate([p[k] for p in parts]).astype(np.float32, copy=False) for k in range(5))]
    out = []
    for part in parts:
        if _in_place(part):
            out.append(part)
        else:
            out.append(tuple(np.array(a, dtype=np.float32, order="C").reshape((len(a),) + shape)
                             for a, shape in zip(part, _FROZEN_SHAPES)))
    return out


def _in_place(part: tuple) -> bool:
    """Whether a part's arrays can be read in place: read-only, float32, C order, rows as expected."""
    for a, shape in zip(part, _FROZEN_SHAPES):
        if a.dtype != np.float32 or a.flags.writeable or not a.flags.c_contiguous or a.shape[1:] != shape:
            return False
    return True


def _copy_parts(buf: np.ndarray, n0: int, n1: int, parts: list) -> None:
    """buf[n0:n1] = the parts concatenated."""
    if len(parts) == 1:
        buf[n0:n1] = parts[0]
    elif parts:
        np.concatenate(parts, out=buf[n0:n1], casting="same_kind")


class ClaimedBatch:
    """A batch of views rendered by any number of threads at once, staged view by view.

    Args:
        views: `BatchView`s to stage at once; the batch is then closed (its capacity is theirs).
            Leave it None to `add` views one at a time and `close` the batch after the last.
        features: also render the feature channels (`dim` of them, one D in every view).
        cull: drop runs of Gaussians outside a view's frustum first (`cull.cull_view`).
        workspace: scratch buffers of the batch (ids, features, projection records; all inputs
            with `cull`), reused from batch to batch: fresh megabytes cost page faults on every
            step; None: fresh arrays. Two batches in flight at once need two workspaces.
        capacity: (views, Gaussians, pixels) the batch can hold when `views` is None; `add`
            returns False for a view that does not fit (start another batch for it).
        dim: the feature dimension D with `features` when `views` is None.

    Call `work()` from each thread that should render (it renders the published views nobody
    has claimed and returns; a view another thread claimed may still be rendering; a
    `RenderHelpers` thread calls it again on each `add` until the batch is closed), then
    `outputs()` once every view is finished (`finished`), or `outputs(lo, hi)` once views
    lo..hi - 1 are (`views_done`). Views are claimed in view order, so the first ones finish first.
    """

    def __init__(self, views: Optional[Sequence[BatchView]] = None, features: bool = False, cull: bool = False,
                 workspace: Optional[Workspace] = None, capacity: Optional[tuple[int, int, int]] = None,
                 dim: int = 0) -> None:
        if views is not None:
            views = list(views)
            dims = {-1 if v.features is None else (v.features[0].shape[1] if v.features else 0) for v in views}
            if features and (len(dims) > 1 or -1 in dims):
                raise ValueError(f"Expected features of one dimension D in every view, found {sorted(dims)}")
            dim = dims.pop() if features and dims else 0
            capacity = (len(views), sum(v.size for v in views), sum(v.width * v.height for v in views))
            parts = sum(len(v.means) for v in views)
        elif capacity is None:
            raise ValueError("Expected views, or a capacity (views, Gaussians, pixels) for a batch staged view by view")
        else:
            parts = _PARTS_PER_VIEW * max(int(capacity[0]), 0)
        V, N, P = (max(int(c), 0) for c in capacity)
        D = int(dim) if features else 0
        ws = workspace if workspace is not None else Workspace()
        f32, i64 = np.float32, np.int64
        self._cull, self._features = bool(cull), bool(features)
        self._cap = (V, N, P)
        self._n = self._p = self._r = self._s = 0      # Gaussians, pixels, ranges and input parts used
        # culling reads the inputs of all views from one staged copy (source row 0); otherwise
        # each view's parts are read in place (`_reference`): one source row per part
        staged = N if cull else 0
        self._means = ws.get("in_means", (staged, 3), f32)
        self._quats = ws.get("in_quats", (staged, 4), f32)
        self._scales = ws.get("in_scales", (staged, 3), f32)
        self._opac = ws.get("in_opacities", (staged,), f32)
        self._colors = ws.get("in_colors", (staged, 3), f32)
        self._ids = ws.get("in_ids", (N,), np.int32)
        self._feat = ws.get("in_features", (N, D), f32)
        self._src = np.zeros((1 if cull else max(parts, 1), 7), i64)
        self._kept: list = []                      # the arrays the source rows point into, alive with the batch
        if cull:
            _reference(self._src, 0, 0, self._means, self._quats, self._scales, self._opac, self._colors)
            self._s = 1
        self._ranges = ws.get("ranges", (N + V if cull else max(parts, 1), 2), i64)
        self._rsrc = np.zeros(len(self._ranges), i64)
        self._rstart = np.zeros(V + 1, i64)
        self._pix_off = np.zeros(V + 1, i64)
        self._viewmats = np.zeros((V, 4, 4), f32)
        self._Ks = np.zeros((V, 3, 3), f32)
        self._sizes = np.zeros((V, 3), i64)
        self._nears = np.zeros(V, f32)
        self._bgs = np.zeros((V, 3), f32)
        self._skies = np.zeros((V, 3), i64)
        self._sky_cam = np.zeros((V, 13), np.float64)
        self._rec = ws.get("rec", (N, NREC), f32)
        self._trect = ws.get("trect", (4, N), np.int32)
        self._rgb = np.empty(3 * P, f32)
        self._depth = np.empty(P, f32)
        self._alpha = np.empty(P, f32)
        self._inst = np.empty(P, np.int32)
        self._fout = np.empty(D * P, f32)
        self._state = np.zeros(6, i64)
        self._claimed = np.zeros(V, i64)
        self._wake = threading.Event()           # set on every publish and on close
        self._vdone = np.zeros(V, i64)
        self._longest = np.zeros(V, i64)
        self.error: Optional[BaseException] = None
        if views is not None:
            for v in views:
                self.add(v)
            self.close()

    # --------------------------------------------------------------- staging
    def add(self, view: BatchView) -> bool:
        """Stage `view` after the published ones and publish it (a thread waiting in `work` starts
        on it at once); False, with nothing changed, when it does not fit in the capacity.
        `ValueError` on a closed batch or a view whose features do not match."""
        fields = [view.means, view.quats, view.scales, view.opacities, view.colors, view.ids]
        if self._features:
            if view.features is None:
                raise ValueError(f"Expected features of dimension {self._feat.shape[1]} in every view, found none")
            fields.append(view.features)
        return self._add(fields, view.size, view.viewmat, view.K, view.near, view.width, view.height,
                         view.background)

    def add_parts(self, parts: Sequence, viewmat: np.ndarray, K: np.ndarray, near: float, width: int, height: int,
                  background: np.ndarray, sky: Optional[tuple] = None) -> bool:
        """`add` of a view given as Gaussian parts (numpy `Gaussians`, composited in order as
        `batch.batch_view` takes them; ids -1 where a part has none) without building its
        `BatchView`: the vector env's per-view hot path. `sky`: (image, camera) to composite the
        sky image (float32 [H', W', 3], `scene.sky.check_sky`) behind what the Gaussians leave
        uncovered, seen from that `Camera` (render such a view on black), as
        `sky.composite_sky_compiled` does after a render, on the thread that renders the view."""
        if self._features and any(p.features is None for p in parts):
            raise ValueError(f"Expected features of dimension {self._feat.shape[1]} in every view, found a part "
                             f"without")
        fields = [[p.means for p in parts], [p.quats for p in parts], [p.scales for p in parts],
                  [p.opacities for p in parts], [p.colors for p in parts],
                  [p.object_ids for p in parts]]
        if self._features:
            fields.append([p.features for p in parts])
        return self._add(fields, sum(len(p.means) for p in parts), viewmat, K, near, width, height, background, sky)

    def _add(self, fields: list, n: int, viewmat, K, near: float, width: int, height: int, background,
             sky: Optional[tuple] = None) -> bool:
        """Stage one view: `fields` are its parts' arrays per field (means, quats, scales,
        opacities, colors, ids[, features]; an id part may be None: -1 over that part). Read-only
        float32 parts (the frozen arrays `Scene4D.at` gives) are read in place by the kernels, the
        others copied first, so a caller's later change to an array it may write never reaches
        the render."""
        if self.closed:
            raise ValueError("Expected an open batch to add a view to, found it closed")
        if sky is not None:
            image = np.ascontiguousarray(sky[0], dtype=np.float32)
            if image.ndim != 3 or image.shape[2] != 3 or min(image.shape[:2]) < 2:
                raise ValueError(f"Expected a sky image of shape (H, W, 3) with H, W >= 2, found {image.shape}")
            R, fx, fy, cx, cy = sky_camera(sky[1])
        if self._features and any(f.shape[1] != self._feat.shape[1] for f in fields[6]):
            raise ValueError(f"Expected features of dimension {self._feat.shape[1]} in every view, found "
                             f"{[f.shape[1] for f in fields[6]]}")
        v, n0, p0, r0 = self.num_views, self._n, self._p, self._r
        width, height = int(width), int(height)
        npx = width * height
        V, N, P = self._cap
        inputs = None if self._cull else _input_parts(fields[:5], len(self._src) - self._s)
        if v >= V or n0 + n > N or p0 + npx > P or (inputs is not None and self._s + len(inputs) > len(self._src)):
            return False
        n1 = n0 + n
        if self._cull:
            for buf, parts in zip((self._means, self._quats, self._scales, self._opac, self._colors), fields[:5]):
                _copy_parts(buf, n0, n1, parts)
        if self._features:
            _copy_parts(self._feat, n0, n1, fields[6])
        k = n0
        for means, ids in zip(fields[0], fields[5]):
            m = len(means)
            self._ids[k:k + m] = -1 if ids is None else ids
            k += m
        self._viewmats[v] = viewmat
        self._Ks[v] = K
        self._sizes[v] = (width, height, (width + 15) // 16)
        self._nears[v] = near
        self._bgs[v] = background
        if sky is None:
            self._skies[v] = 0
        else:
            self._skies[v] = (image.ctypes.data, image.shape[0], image.shape[1])
            self._sky_cam[v, :9] = R.ravel()
            self._sky_cam[v, 9:] = (fx, fy, cx, cy)
            self._kept.append(image)
        if self._cull and n:
            k = cull_view(self._means, self._scales, self._opac, self._ids, n0, n1,
                          self._viewmats[v].astype(np.float64), self._Ks[v].astype(np.float64),
                          width, height, float(self._nears[v]), self._ranges[r0:])
        elif n:
            k = 0
            for part in inputs:
                m = len(part[0])
                _reference(self._src, self._s, n0, *part)
                self._ranges[r0 + k] = (n0, n0 + m)
                self._rsrc[r0 + k] = self._s
                self._kept.append(part)
                self._s += 1
                n0 += m
                k += 1
        else:
            k = 0
        self._n, self._p, self._r = n1, p0 + npx, r0 + k
        self._rstart[v + 1] = r0 + k
        self._pix_off[v + 1] = p0 + npx
        _bump(self._state, _PUBLISHED)       # seq_cst: everything above is visible before the view is
        self._wake.set()                     # a helper waiting for views goes on
        return True

    def close(self) -> None:
        """No more views: `work` returns once the published ones are claimed (idempotent)."""
        if not self.closed:
            _bump(self._state, _CLOSED)
            self._wake.set()

    @property
    def closed(self) -> bool:
        return int(self._state[_CLOSED]) != 0

    @property
    def size(self) -> tuple[int, int, int]:
        """(views, Gaussians, pixels) staged so far."""
        return self.num_views, self._n, self._p

    # --------------------------------------------------------------- rendering
    @property
    def num_views(self) -> int:
        return int(self._state[_PUBLISHED])

    @property
    def finished(self) -> bool:
        """Whether the batch is closed and every view has been rendered."""
        return self.closed and int(self._state[_FINISHED]) >= self.num_views

    @property
    def claimable(self) -> bool:
        """Whether a published view is left for a `work` call to claim."""
        return int(self._state[_CLAIMED]) < self.num_views

    @property
    def entered(self) -> bool:
        """Whether a thread has started `work` on this batch."""
        return int(self._state[_ENTERED]) > 0

    def views_done(self, lo: int, hi: int) -> bool:
        """Whether views lo..hi - 1 have been rendered."""
        return hi <= self.num_views and bool(self._vdone[lo:hi].all())

    def work(self, limit: int = -1, spin: int = 0, last_first: bool = False) -> int:
        """Render published views of this batch until none is left to claim, or `limit` of them
        (holds no GIL while rendering; while the batch is open, looks `spin` more times for a view
        to be published before it returns); returns how many this call rendered. Views are
        claimed in view order, or with `last_first` the last unclaimed one first (a caller that
        takes views in any order, beside helpers that take them from the first)."""
        if self._cap[0] == 0:
            return 0
        return int(_work(self._state, int(limit), int(spin), bool(last_first), self._claimed, self._vdone,
                         self._longest, self._ranges, self._rsrc, self._rstart, self._src, self._feat, self._ids,
                         self._viewmats, self._Ks, self._sizes, self._nears, self._bgs, self._skies,
                         self._sky_cam, self._pix_off, self._rec,
                         self._trect,
                         self._rgb, self._depth, self._alpha, self._inst, self._fout,
                         np.empty((1, 1), np.float32), np.empty((1, 1), np.int32)))

    def outputs(self, lo: int = 0, hi: Optional[int] = None) -> list[dict]:
        """One dict per view lo..hi - 1 (default all), as `batch.rasterize_batch_numpy` returns them."""
        if self.error is not None:
            raise self.error
        hi = self.num_views if hi is None else hi
        if not self.views_done(lo, hi):
            raise RuntimeError(f"Expected every view rendered before outputs(), found {int(self._vdone[lo:hi].sum())} "
                               f"of {hi - lo}")
        worst = int(self._longest[lo:hi].max()) if hi > lo else 0
        if worst >= _MAX_TILE_LIST:
            raise ValueError(f"Expected at most {_MAX_TILE_LIST - 1} Gaussians over one 16x16 tile in float32, "
                             f"found {worst} (list positions are kept as floats)")
        staged = Staged(V=self.num_views, sizes=self._sizes, pix_off=self._pix_off, feat=self._feat,
                        features=self._features)
        return view_outputs(staged, self._rgb, self._depth, self._alpha, self._inst, self._fout, lo, hi)


class RenderHelpers:
    """Helper threads that render `ClaimedBatch`es beside the calling thread.

    `submit(batch)` hands a batch to the helpers (they start on it at once, in submission
    order) and returns; the caller does other work, then `complete(batch)` renders what is
    left itself, waits for the helpers' last views and returns the outputs. With 0 helpers
    `complete` renders the whole batch on the calling thread.

    Args:
        helpers: number of helper threads (started on the first `submit`).
    """

    def __init__(self, helpers: int = 1) -> None:
        if isinstance(helpers, bool) or not isinstance(helpers, (int, np.integer)) or helpers < 0:
            raise ValueError(f"Expected helpers as a non-negative integer, found {helpers!r}")
        self.helpers = int(helpers)
        self._queues: list[queue.SimpleQueue] = []
        self._threads: list[threading.Thread] = []
        self._lock = threading.Lock()            # starting and stopping threads
        self._count = threading.Lock()           # batches' count of helpers still at work
        self._submitted: list = []               # the last two batches submitted
        self._posted = np.zeros(1, np.int64)     # items put on every queue so far (batches, stops)

    def submit(self, batch: ClaimedBatch, post: bool = True) -> ClaimedBatch:
        """Start the helpers on `batch` (no-op without helpers); returns it. A helper that looks
        for its next batch without the GIL sees it once it is posted: at once, or with
        `post=False` from the next `handover(batch)`, which posts it from its own wait without
        the GIL (the helper then takes the GIL at once instead of waiting for it to be handed
        over: an OS wake-up, ~0.1 ms)."""
        if self.helpers == 0:
            return batch
        self._start()
        batch._left = self.helpers                       # helpers still to finish their part
        batch._done = threading.Event()
        self._submitted = (self._submitted + [batch])[-2:]
        for q in self._queues:
            q.put(batch)
        batch._unposted = not post
        if post:
            _bump(self._posted, 0)
        return batch

    def handover(self, batch: ClaimedBatch, spins: int = _HANDOVER_SPINS, naps: int = _HANDOVER_NAPS) -> bool:
        """Let a helper start on `batch` now: wait until a thread has entered its `work`, first
        spinning without the GIL (at most `spins` looks, tens of microseconds: enough for a
        helper on an idle core), then in up to `naps` short sleeps (the core may be shared: a
        sleep lets the OS run the helper). A helper woken while this thread runs Python waits for
        the GIL, up to Python's switch interval (5 ms); call this right after `submit` and the
        first `add`, before more Python work. Whether a thread has entered (True without helpers:
        nothing to wait for; False at once while an earlier batch still has views to render).
        A helper done with the earlier batch may still wait for the GIL to leave its `work`:
        this wait lets it."""
        if self.helpers == 0:
            return True
        post = getattr(batch, "_unposted", False)
        batch._unposted = False
        earlier = self._submitted[0] if self._submitted[-1] is batch and len(self._submitted) > 1 else None
        if batch.entered or (earlier is not None and not earlier.finished):
            if post:
                _bump(self._posted, 0)
            return batch.entered                 # False: the helpers are rendering an earlier batch, no waiting
        if _wait_entered(batch._state, self._posted, post, int(spins)):
            return True
        for _ in range(naps):
            time.sleep(_POLL_S)
            if batch.entered:
                return True
        return False

    def complete(self, batch: ClaimedBatch, timeout_s: float = _WAIT_S) -> list[dict]:
        """Render the views no helper has claimed, wait for the rest and return the outputs (of a
        closed batch: on an open one this thread could wait for a view only it would add)."""
        _check_closed(batch)
        batch.work()
        done = getattr(batch, "_done", None)
        if done is not None and not done.wait(timeout_s):
            raise TimeoutError(f"Expected the render helpers to finish within {timeout_s} s, found them still busy")
        return batch.outputs()

    def partial(self, batch: ClaimedBatch, lo: int, hi: int, timeout_s: float = _WAIT_S) -> list[dict]:
        """The outputs of views lo..hi - 1 once they are rendered: until then this thread renders
        views no helper has claimed, one at a time, or waits for the helpers' (so a caller can
        finish the work of the first views while the helpers render the last)."""
        _check_closed(batch)
        deadline = None
        while not batch.views_done(lo, hi):
            if batch.error is not None:
                raise batch.error
            if batch.claimable:
                batch.work(1)
                continue
            deadline = _nap([batch], deadline, timeout_s)
        return batch.outputs(lo, hi)

    def first_ready(self, spans: Sequence[Sequence[tuple[ClaimedBatch, int]]], timeout_s: float = _WAIT_S) -> int:
        """The position of the first span whose views (each a (closed batch, view index) pair) are
        all rendered. Until one is, this thread renders unclaimed views, the last one first (the
        helpers take them from the first, so the two meet at the end of the batch and the spans
        whose views the helpers finish meanwhile are ready at once), or waits for the helpers'."""
        if not spans:
            raise ValueError("Expected at least one span of views to wait for, found none")
        batches = list({id(b): b for span in spans for b, _ in span}.values())
        for batch in batches:
            _check_closed(batch)
        deadline = None
        while True:
            for pos, span in enumerate(spans):
                if all(batch._vdone[k] for batch, k in span):
                    return pos
            if any(batch.claimable and batch.work(1, last_first=True) for batch in reversed(batches)):
                continue
            if len(batches) == 1:                # a sleep oversleeps by ~50 us: spin for the helper's view first
                views = np.array([k for span in spans for b, k in span if not b._vdone[k]], np.int64)
                if _wait_done(batches[0]._vdone, views, _READY_SPINS):
                    continue
            deadline = _nap(batches, deadline, timeout_s)

    def close(self) -> None:
        """Stop the helper threads (a later `submit` starts new ones). A batch still open is
        closed first: a helper waiting for its next view would otherwise wait for ever."""
        with self._lock:
            queues, threads = self._queues, self._threads
            self._queues, self._threads = [], []
        for batch in self._submitted:
            batch.close()
        for q in queues:
            q.put(None)
        _bump(self._posted, 0)                   # a helper looking for its next batch sees the stop
        for t in threads:
            t.join()

    def _start(self) -> None:
        with self._lock:
            while len(self._threads) < self.helpers:
                q: queue.SimpleQueue = queue.SimpleQueue()
                t = threading.Thread(target=self._loop, args=(q,), daemon=True,
                                     name=f"morphosim-render-helper-{len(self._threads)}")
                self._queues.append(q)
                self._threads.append(t)
                t.start()

    def _loop(self, q: queue.SimpleQueue) -> None:
        """Serve the batches put on `q`. Between batches look for the next one to be posted
        without the GIL before sleeping on the queue (waking a sleeping helper costs its caller
        ~0.1-0.3 ms in `handover`; a vector env posts its next step's batch ~0.3-1.5 ms after a
        helper's last view): up to the longer of `_IDLE_SPINS`, or the shorter after two waits
        in a row that found none (a caller busy between batches, e.g. a policy update, loses
        little of its core)."""
        low, high = _IDLE_SPINS
        misses = 0
        while True:
            posted = int(self._posted[0])
            if q.empty():
                found = _wait_posted(self._posted, posted, high if misses < 2 else low) >= 0
                misses = 0 if found else misses + 1
            batch = q.get()
            if batch is None:
                return
            try:
                self._serve(batch)
            except BaseException as exc:  # noqa: BLE001 - handed to the caller's complete()
                batch.error = exc
            finally:
                with self._count:
                    batch._left -= 1
                    last = batch._left == 0
                if last:
                    batch._done.set()

    @staticmethod
    def _serve(batch: ClaimedBatch) -> None:
        """Render the batch's views as they are published, until it is closed and none is left.
        Between views it first looks for the next one without the GIL for ~0.5 ms (the caller
        stages a view every ~0.1 ms: waking a sleeping thread and handing it the GIL cost more,
        ~4% of a vector-8 Track step), then sleeps until the next `add` or `close`."""
        while True:
            batch._wake.clear()
            batch.work(spin=_SERVE_SPINS)
            if batch.closed and not batch.claimable:
                return
            if not batch.claimable:
                batch._wake.wait()

    def __getstate__(self) -> dict:
        return {"helpers": self.helpers}     # threads and queues do not copy: the copy starts its own

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["helpers"])


def _nap(batches: Sequence[ClaimedBatch], deadline: Optional[float], timeout_s: float) -> float:
    """One short sleep of a thread waiting for helpers' views (it releases the GIL; a view takes
    ~0.1-2 ms), after raising a helper's error or a `TimeoutError` past the deadline (set
    `timeout_s` from the first nap); returns the deadline."""
    for batch in batches:
        if batch.error is not None:
            raise batch.error
    now = time.monotonic()
    deadline = deadline or now + timeout_s
    if now > deadline:
        raise TimeoutError(f"Expected the render helpers to finish within {timeout_s} s, found them busy")
    time.sleep(_POLL_S)
    return deadline


def _check_closed(batch: ClaimedBatch) -> None:
    if not batch.closed:
        raise RuntimeError("Expected a closed batch to render on this thread, found it open (close() it first)")
