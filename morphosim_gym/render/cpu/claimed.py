"""Batched forward rendering shared by Python threads: every thread that calls `ClaimedBatch.work`
claims whole views of the batch (in view order) and renders each one start to finish (projection,
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
import time
from typing import Optional, Sequence

import numpy as np

from ._jit import NREC, atomic_add, jit
from .batch import _MAX_TILE_LIST, BatchView, Staged, stage_views, view_outputs
from .pipeline import Workspace
from .binning import _fill_range, bin_offsets, plan_tiles
from .forward import _raster_tiles
from .projection import _project_range

__all__ = ["ClaimedBatch", "RenderHelpers"]

_POLL_S = 50e-6           # sleep between looks at a helper's view that is still rendering
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
    acc = bin_offsets(counts[:nr], tile_start, off[:nr])
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
def _work(state,          # [2] int64: next view to claim, views finished
          limit,          # most views this call renders (< 0: no limit)
          vdone,          # [V] int64: 1 once view v is rendered
          longest,        # [V] int64 out: each view's longest tile list
          ranges, rstart, means, quats, scales, opacities, colors, feat, ids, viewmats, Ks, sizes, nears, bgs,
          pix_off, rec, trect, rgb, depth, alpha, inst, feat_out, dummy_f, dummy_i):
    """Claim views one at a time (in view order) until none is left or `limit` are rendered;
    returns how many this call rendered."""
    V = vdone.shape[0]
    done = 0
    while limit < 0 or done < limit:
        v = atomic_add(state, 0, 1)
        if v >= V:
            break
        longest[v] = _render_view(v, ranges, rstart, means, quats, scales, opacities, colors, feat, ids, viewmats,
                                  Ks, sizes, nears, bgs, pix_off, rec, trect, rgb, depth, alpha, inst, feat_out,
                                  dummy_f, dummy_i)
        atomic_add(vdone, v, 1)            # seq_cst: the view's pixels are written before its flag
        atomic_add(state, 1, 1)
        done += 1
    return done


class ClaimedBatch:
    """A batch of `BatchView`s staged for `work` by any number of threads at once.

    Args:
        views: the views (as `batch.rasterize_batch_numpy` takes them).
        features: also render the feature channels (one D in every view).
        cull: drop runs of Gaussians outside a view's frustum first (`cull.cull_view`).
        workspace: scratch buffers to stage the batch in (reused from batch to batch: fresh
            megabytes cost page faults on every step); None: fresh arrays. Two batches in
            flight at once need two workspaces.

    Call `work()` from each thread that should render (it returns once no view is left to
    claim; a view another thread claimed may still be rendering), then `outputs()` once every
    view is finished (`finished`), or `outputs(lo, hi)` once views lo..hi - 1 are
    (`views_done`). Views are claimed in view order, so the first ones finish first.
    """

    def __init__(self, views: Sequence[BatchView], features: bool = False, cull: bool = False,
                 workspace: Optional[Workspace] = None) -> None:
        s: Staged = stage_views(views, features, cull, workspace)
        self._s = s
        V = s.V
        n = s.means.shape[0]
        ws = workspace if workspace is not None else Workspace()
        self._rec = ws.get("rec", (n, NREC), np.float32)
        self._trect = ws.get("trect", (4, n), np.int32)
        P = int(s.pix_off[-1])
        D = s.feat.shape[1]
        self._rgb = np.empty(3 * P, np.float32)
        self._depth = np.empty(P, np.float32)
        self._alpha = np.empty(P, np.float32)
        self._inst = np.empty(P, np.int32)
        self._fout = np.empty(D * P, np.float32)
        self._state = np.zeros(2, np.int64)
        self._vdone = np.zeros(V, np.int64)
        self._longest = np.zeros(V, np.int64)
        self.error: Optional[BaseException] = None

    @property
    def num_views(self) -> int:
        return self._s.V

    @property
    def finished(self) -> bool:
        """Whether every view has been rendered."""
        return int(self._state[1]) >= self._s.V

    @property
    def claimable(self) -> bool:
        """Whether a view is left for a `work` call to claim."""
        return int(self._state[0]) < self._s.V

    def views_done(self, lo: int, hi: int) -> bool:
        """Whether views lo..hi - 1 have been rendered."""
        return bool(self._vdone[lo:hi].all())

    def work(self, limit: int = -1) -> int:
        """Render views of this batch until none is left to claim, or `limit` of them (holds no
        GIL while rendering); returns how many this call rendered."""
        s = self._s
        if s.V == 0:
            return 0
        return int(_work(self._state, int(limit), self._vdone, self._longest, s.ranges, s.rstart, s.means, s.quats, s.scales,
                         s.opac, s.colors, s.feat, s.ids, s.viewmats, s.Ks, s.sizes, s.nears, s.bgs, s.pix_off,
                         self._rec, self._trect, self._rgb, self._depth, self._alpha, self._inst, self._fout,
                         np.empty((1, 1), np.float32), np.empty((1, 1), np.int32)))

    def outputs(self, lo: int = 0, hi: Optional[int] = None) -> list[dict]:
        """One dict per view lo..hi - 1 (default all), as `batch.rasterize_batch_numpy` returns them."""
        if self.error is not None:
            raise self.error
        s = self._s
        hi = s.V if hi is None else hi
        if not self.views_done(lo, hi):
            raise RuntimeError(f"Expected every view rendered before outputs(), found {int(self._vdone[lo:hi].sum())} "
                               f"of {hi - lo}")
        worst = int(self._longest[lo:hi].max()) if hi > lo else 0
        if worst >= _MAX_TILE_LIST:
            raise ValueError(f"Expected at most {_MAX_TILE_LIST - 1} Gaussians over one 16x16 tile in float32, "
                             f"found {worst} (list positions are kept as floats)")
        return view_outputs(s, self._rgb, self._depth, self._alpha, self._inst, self._fout, lo, hi)


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

    def partial(self, batch: ClaimedBatch, lo: int, hi: int, timeout_s: float = _WAIT_S) -> list[dict]:
        """The outputs of views lo..hi - 1 once they are rendered: until then this thread renders
        views no helper has claimed, one at a time, or waits for the helpers' (so a caller can
        finish the work of the first views while the helpers render the last)."""
        deadline = None
        while not batch.views_done(lo, hi):
            if batch.error is not None:
                raise batch.error
            if batch.claimable:
                batch.work(1)
                continue
            now = time.monotonic()
            deadline = deadline or now + timeout_s
            if now > deadline:
                raise TimeoutError(f"Expected the render helpers to finish within {timeout_s} s, found them busy")
            time.sleep(_POLL_S)                  # releases the GIL; a helper's view takes ~0.1-2 ms
        return batch.outputs(lo, hi)

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
