"""Batched forward rendering shared by Python threads: every thread that calls `ClaimedBatch.work`
claims whole views of the batch (largest first) and renders each one start to finish (projection,
binning, raster) in one compiled call that holds no GIL.

This is the batch path for callers that have Python work of their own beside the render (the
vector env: rig, rewards, observations of other envs). A `RenderHelpers` thread works on a batch
while the calling thread does that work, and the caller joins in (`RenderHelpers.complete`) when
it is done: both cores render, without a numba parallel region whose join waits for a thread
the caller's Python work keeps busy, and with projection and binning parallel too (as whole views).

Pixels are bit-identical to `batch.rasterize_batch_numpy` and to the single-camera path: a view
runs the same per-range kernels (`_project_range`, `_fill_range`, `plan_tiles`, `_raster_tiles`)
with its tile lists in ascending Gaussian index order, on whichever thread claims it.
"""

from __future__ import annotations

import queue
import threading
from typing import Optional, Sequence

import numpy as np

from ._jit import NREC, atomic_add, jit
from .batch import _MAX_TILE_LIST, BatchView, Staged, stage_views, view_outputs
from .binning import _fill_range, plan_tiles
from .forward import _raster_tiles
from .projection import _project_range

__all__ = ["ClaimedBatch", "RenderHelpers"]

_WAIT_S = 600.0            # a helper that takes longer over its last view is hung: raise instead of waiting


@jit
def _render_view(v, ranges,    # [k, 2] int64 kept index ranges of all views, view by view
                 rstart,       # [V + 1] int64: view v's ranges are ranges[rstart[v]:rstart[v + 1]]
                 means, quats, scales, opacities, colors, feat, ids,
                 viewmats,     # [V, 4, 4]
                 Ks,           # [V, 3, 3]
                 sizes,        # [V, 3] int64: width, height, tiles_x
                 nears,        # [V] float32
                 bgs,          # [V, 3]
                 pix_off,      # [V + 1] int64
                 rec, trect,   # [N, 16], [4, N] shared scratch (view v writes only its own rows)
                 rgb, depth, alpha, inst, feat_out,   # flat outputs, view v's block at pix_off[v]
                 dummy_f, dummy_i):   # [1, 1] float32 / int32 stand-ins for the backward-only outputs
    """Render view v on the calling thread; returns its longest tile list."""
    w = sizes[v, 0]
    h = sizes[v, 1]
    tx = sizes[v, 2]
    nt = tx * ((h + 15) // 16)
    r0 = rstart[v]
    nr = rstart[v + 1] - r0
    counts = np.zeros((max(nr, 1), nt), np.int32)
    for r in range(nr):
        _project_range(ranges[r0 + r, 0], ranges[r0 + r, 1], means, quats, scales, opacities, colors, feat,
                       viewmats[v], Ks[v], w, h, nears[v], rec, trect, tx, counts[r])
    # offsets: per tile, the ranges in index order (each tile list ascending, as every other path)
    tile_start = np.empty(nt + 1, np.int64)
    off = np.empty((max(nr, 1), nt), np.int64)
    acc = 0
    for t in range(nt):
        tile_start[t] = acc
        for r in range(nr):
            off[r, t] = acc
            acc += counts[r, t]
    tile_start[nt] = acc
    lst = np.empty(max(acc, 1), np.int32)
    for r in range(nr):
        _fill_range(ranges[r0 + r, 0], ranges[r0 + r, 1], trect, tx, off[r], lst)
    order = np.empty(nt, np.int32)
    longest = plan_tiles(tile_start, order)
    m = max(longest, 1)
    keys = np.empty(m, np.uint32)
    keys2 = np.empty(m, np.uint32)
    idx = np.empty(m, np.int32)
    idx2 = np.empty(m, np.int32)
    claim = np.zeros(1, np.int64)
    D = feat.shape[1]
    p0 = pix_off[v]
    npx = w * h
    _raster_tiles(order, claim, tile_start, lst, rec, ids, feat, w, h, tx, bgs[v],
                  rgb[3 * p0:3 * (p0 + npx)].reshape((h, w, 3)), depth[p0:p0 + npx].reshape((h, w)),
                  alpha[p0:p0 + npx].reshape((h, w)), inst[p0:p0 + npx].reshape((h, w)),
                  feat_out[D * p0:D * (p0 + npx)].reshape((h, w, D)), dummy_f, dummy_i, False,
                  keys, keys2, idx, idx2)
    return longest


@jit
def _work(state,          # [2] int64: next position in `vorder` to claim, views finished
          vorder,         # [V] int64 views, largest first
          longest,        # [V] int64 out: each view's longest tile list
          ranges, rstart, means, quats, scales, opacities, colors, feat, ids, viewmats, Ks, sizes, nears, bgs,
          pix_off, rec, trect, rgb, depth, alpha, inst, feat_out, dummy_f, dummy_i):
    """Claim views one at a time until none is left; returns how many this call rendered."""
    V = vorder.shape[0]
    done = 0
    while True:
        q = atomic_add(state, 0, 1)
        if q >= V:
            break
        v = vorder[q]
        longest[v] = _render_view(v, ranges, rstart, means, quats, scales, opacities, colors, feat, ids, viewmats,
                                  Ks, sizes, nears, bgs, pix_off, rec, trect, rgb, depth, alpha, inst, feat_out,
                                  dummy_f, dummy_i)
        atomic_add(state, 1, 1)
        done += 1
    return done


class ClaimedBatch:
    """A batch of `BatchView`s staged for `work` by any number of threads at once.

    Args:
        views: the views (as `batch.rasterize_batch_numpy` takes them).
        features: also render the feature channels (one D in every view).
        cull: drop runs of Gaussians outside a view's frustum first (`cull.cull_view`).

    Call `work()` from each thread that should render (it returns once no view is left to
    claim; a view another thread claimed may still be rendering), then `outputs()` once every
    view is finished (`finished`).
    """

    def __init__(self, views: Sequence[BatchView], features: bool = False, cull: bool = False) -> None:
        s: Staged = stage_views(views, features, cull)
        self._s = s
        V = s.V
        n = s.means.shape[0]
        # scratch of this batch alone: batches in flight at once must not share it
        self._rec = np.empty((n, NREC), np.float32)
        self._trect = np.empty((4, n), np.int32)
        P = int(s.pix_off[-1])
        D = s.feat.shape[1]
        self._rgb = np.empty(3 * P, np.float32)
        self._depth = np.empty(P, np.float32)
        self._alpha = np.empty(P, np.float32)
        self._inst = np.empty(P, np.int32)
        self._fout = np.empty(D * P, np.float32)
        self._state = np.zeros(2, np.int64)
        self._longest = np.zeros(V, np.int64)
        work = (s.counts_n * 4 + s.sizes[:, 0] * s.sizes[:, 1]) if V else np.zeros(0, np.int64)
        self._vorder = np.argsort(-work, kind="stable").astype(np.int64)     # largest first, ties in view order
        self.error: Optional[BaseException] = None

    @property
    def num_views(self) -> int:
        return self._s.V

    @property
    def finished(self) -> bool:
        """Whether every view has been rendered."""
        return int(self._state[1]) >= self._s.V

    def work(self) -> int:
        """Render views of this batch until none is left to claim (holds no GIL while rendering);
        returns how many this call rendered."""
        s = self._s
        if s.V == 0:
            return 0
        return int(_work(self._state, self._vorder, self._longest, s.ranges, s.rstart, s.means, s.quats, s.scales,
                         s.opac, s.colors, s.feat, s.ids, s.viewmats, s.Ks, s.sizes, s.nears, s.bgs, s.pix_off,
                         self._rec, self._trect, self._rgb, self._depth, self._alpha, self._inst, self._fout,
                         np.empty((1, 1), np.float32), np.empty((1, 1), np.int32)))

    def outputs(self) -> list[dict]:
        """One dict per view, as `batch.rasterize_batch_numpy` returns them."""
        if self.error is not None:
            raise self.error
        if not self.finished:
            raise RuntimeError(f"Expected every view rendered before outputs(), found {int(self._state[1])} of "
                               f"{self._s.V}")
        s = self._s
        worst = int(self._longest.max()) if s.V else 0
        if worst >= _MAX_TILE_LIST:
            raise ValueError(f"Expected at most {_MAX_TILE_LIST - 1} Gaussians over one 16x16 tile in float32, "
                             f"found {worst} (list positions are kept as floats)")
        return view_outputs(s, self._rgb, self._depth, self._alpha, self._inst, self._fout)


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

    def submit(self, batch: ClaimedBatch) -> ClaimedBatch:
        """Start the helpers on `batch` (no-op without helpers); returns it."""
        if self.helpers == 0:
            return batch
        self._start()
        batch._left = self.helpers                       # helpers still to finish their part
        batch._done = threading.Event()
        for q in self._queues:
            q.put(batch)
        return batch

    def complete(self, batch: ClaimedBatch, timeout_s: float = _WAIT_S) -> list[dict]:
        """Render the views no helper has claimed, wait for the rest and return the outputs."""
        batch.work()
        done = getattr(batch, "_done", None)
        if done is not None and not done.wait(timeout_s):
            raise TimeoutError(f"Expected the render helpers to finish within {timeout_s} s, found them still busy")
        return batch.outputs()

    def close(self) -> None:
        """Stop the helper threads (a later `submit` starts new ones)."""
        with self._lock:
            queues, threads = self._queues, self._threads
            self._queues, self._threads = [], []
        for q in queues:
            q.put(None)
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
        while True:
            batch = q.get()
            if batch is None:
                return
            try:
                batch.work()
            except BaseException as exc:  # noqa: BLE001 - handed to the caller's complete()
                batch.error = exc
            finally:
                with self._count:
                    batch._left -= 1
                    last = batch._left == 0
                if last:
                    batch._done.set()

    def __getstate__(self) -> dict:
        return {"helpers": self.helpers}     # threads and queues do not copy: the copy starts its own

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["helpers"])
