"""Per-camera orchestration of the forward kernels, and `rasterize_numpy` (the env hot path).

One camera = project (parallel) -> bin offsets -> bin fill (parallel) -> order the tiles ->
sort + composite per tile (parallel, tiles claimed longest first). `render_camera` runs these stages and returns what the
backward pass needs (`FrameState`).
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass
from typing import Optional

import numba
import numpy as np

from ._jit import NREC
from .binning import bin_fill, bin_offsets, plan_tiles, sorted_fill
from .forward import raster_forward
from .projection import project_forward

__all__ = ["rasterize_numpy", "render_camera", "FrameState", "StageTimer", "Workspace"]

_KEY_DTYPE = {np.dtype(np.float32): np.uint32, np.dtype(np.float64): np.uint64}
_MAX_TILE_LIST = {np.dtype(np.float32): 1 << 24, np.dtype(np.float64): 1 << 53}
_PRESORT_ENTRIES_PER_TILE = 128   # below this mean list length a serial presort beats parallel per-tile sorts


@dataclass
class FrameState:
    """What one camera's forward pass leaves for its backward pass.

    rec [N, 16] projected records; tile_start [n_tiles + 1] and lst [n_entries] the depth-sorted
    per-tile lists; order [n_tiles] the tiles longest list first; tfinal [H, W] final
    transmittance; last [H, W] int32 per-pixel stop position in its tile's list.
    """

    rec: np.ndarray
    tile_start: np.ndarray
    lst: np.ndarray
    order: np.ndarray
    max_len: int
    tiles_x: int
    tfinal: Optional[np.ndarray]
    last: Optional[np.ndarray]


class Workspace:
    """Scratch buffers reused across calls (grow-only), so that a steady stream of frames does
    not pay page faults on megabytes of fresh memory each frame. One per Python thread."""

    def __init__(self) -> None:
        self._bufs: dict[str, np.ndarray] = {}
        self._views: dict[tuple, np.ndarray] = {}

    def get(self, name: str, shape: tuple, dtype) -> np.ndarray:
        key = (name, shape, dtype)
        view = self._views.get(key)
        if view is not None:
            return view
        size = math.prod(shape)
        dt = np.dtype(dtype)
        buf = self._bufs.get(name)
        if buf is None or buf.dtype != dt or buf.size < size:
            buf = np.empty(max(size + size // 4, 16), dt)
            self._bufs[name] = buf
            self._views = {k: v for k, v in self._views.items() if k[0] != name}
        if len(self._views) > 64:
            self._views.clear()
        view = self._views[key] = buf[:size].reshape(shape)
        return view


_LOCAL = threading.local()


def thread_workspace(name: str = "single") -> Workspace:
    """This thread's `Workspace` called `name` (the single-camera and batched paths keep their own, so
    a batch's outputs, views into its buffers, survive single renders in between)."""
    spaces = getattr(_LOCAL, "spaces", None)
    if spaces is None:
        spaces = _LOCAL.spaces = {}
    ws = spaces.get(name)
    if ws is None:
        ws = spaces[name] = Workspace()
    return ws


class StageTimer:
    """Accumulates wall time per stage (only when passed to `render_camera`)."""

    def __init__(self) -> None:
        self.totals: dict[str, float] = {}
        self._t = 0.0

    def start(self) -> None:
        self._t = time.perf_counter()

    def lap(self, name: str) -> None:
        t = time.perf_counter()
        self.totals[name] = self.totals.get(name, 0.0) + (t - self._t)
        self._t = t


def render_camera(means, quats, scales, opacities, colors, feat, ids,
                  viewmat,   # [4, 4] (float dtype of the Gaussians)
                  K,         # [3, 3]
                  near: float, width: int, height: int,
                  bg,        # [3]
                  rgb, depth, alpha, inst, feat_out,   # output views for this camera
                  save: bool = False, timer: Optional[StageTimer] = None,
                  ws: Optional[Workspace] = None) -> Optional[FrameState]:
    """Render one camera into the given output views; with `save`, return the backward state.

    Scratch comes from `ws` when given (forward-only use), else is freshly allocated (the
    backward pass keeps it).
    """
    if ws is None:
        ws = Workspace()
    dtype = means.dtype
    F = dtype.type
    n = means.shape[0]
    nthr = numba.get_num_threads()
    tiles_x = (width + 15) // 16
    tiles_y = (height + 15) // 16
    ntiles = tiles_x * tiles_y
    if timer:
        timer.start()
    rec = ws.get("rec", (n, NREC), dtype)
    trect = ws.get("trect", (4, n), np.int32)
    counts = ws.get("counts", (nthr, ntiles), np.int32)
    project_forward(means, quats, scales, opacities, colors, feat, viewmat, K, width, height, F(near),
                    rec, trect, tiles_x, counts)
    if timer:
        timer.lap("project")
    tile_start = ws.get("tile_start", (ntiles + 1,), np.int64)
    thread_off = ws.get("thread_off", (nthr, ntiles), np.int64)
    total = bin_offsets(counts, tile_start, thread_off)
    lst = ws.get("lst", (total,), np.int32)
    # one depth sort of the visible Gaussians on one thread, or per-tile sorts in the parallel
    # raster when there are threads to share them and the lists are long (same lists either way)
    presorted = nthr == 1 or total <= _PRESORT_ENTRIES_PER_TILE * ntiles
    if presorted:
        sorted_fill(np.array([[0, n]], np.int64), trect, rec, tiles_x, tile_start, lst)
    else:
        bin_fill(trect, tiles_x, thread_off, lst)
    order = ws.get("order", (ntiles,), np.int32)
    max_len = plan_tiles(tile_start, order)
    if max_len >= _MAX_TILE_LIST[dtype]:
        raise ValueError(f"Expected at most {_MAX_TILE_LIST[dtype] - 1} Gaussians over one 16x16 tile in "
                         f"{dtype.name}, found {max_len} (list positions are kept as floats)")
    if timer:
        timer.lap("bin")
    kd = _KEY_DTYPE[dtype]
    m = max(int(max_len), 1)
    keys = ws.get("keys", (nthr, m), kd)
    keys2 = ws.get("keys2", (nthr, m), kd)
    idx = ws.get("idx", (nthr, m), np.int32)
    idx2 = ws.get("idx2", (nthr, m), np.int32)
    if save:
        tfinal = np.empty((height, width), dtype)
        last = np.empty((height, width), np.int32)
    else:
        tfinal = _DUMMY_F[dtype]
        last = _DUMMY_I
    raster_forward(order, ws.get("claim", (1,), np.int64), keys, keys2, idx, idx2, tile_start, lst, rec, ids, feat,
                   width, height, tiles_x, bg, rgb, depth, alpha, inst, feat_out, tfinal, last, save, presorted)
    if timer:
        timer.lap("raster")
    if not save:
        return None
    return FrameState(rec, tile_start, lst, order, int(max_len), tiles_x, tfinal, last)


_DUMMY_F = {np.dtype(np.float32): np.empty((1, 1), np.float32), np.dtype(np.float64): np.empty((1, 1), np.float64)}
_DUMMY_I = np.empty((1, 1), np.int32)


def _as(x, dtype, shape: tuple, name: str) -> np.ndarray:
    """C-contiguous array of `dtype` with `shape` (-1 entries free), else ValueError naming `name`."""
    a = np.ascontiguousarray(x, dtype=dtype)
    if a.ndim != len(shape) or any(s != -1 and s != t for s, t in zip(shape, a.shape)):
        want = "(" + ", ".join("*" if s == -1 else str(s) for s in shape) + ")"
        raise ValueError(f"Expected {name} of shape {want}, found {a.shape}")
    return a


def rasterize_numpy(means,        # [N, 3]
                    quats,        # [N, 4]
                    scales,       # [N, 3]
                    opacities,    # [N]
                    colors,       # [N, 3]
                    viewmats,     # [C, 4, 4]
                    Ks,           # [C, 3, 3]
                    width: int,
                    height: int,
                    features=None,    # [N, D]
                    object_ids=None,  # [N]
                    background=None,  # [3]
                    nears=None,       # [C]
                    timer: Optional[StageTimer] = None) -> dict:
    """Forward-only float32 splatting of numpy arrays into C cameras (the env observation path).

    Args:
        means: [N, 3]. quats: [N, 4] w, x, y, z, any norm. scales: [N, 3] standard deviations.
        opacities: [N]. colors: [N, 3]. viewmats: [C, 4, 4] world->camera (OpenCV axes).
        Ks: [C, 3, 3]. width, height: pixels. features: [N, D] or None. object_ids: [N] int or
        None (instance -1 everywhere). background: [3] or None (black). nears: [C] or None (0.01).
        timer: optional `StageTimer` collecting per-stage wall time.

    Returns:
        dict of numpy arrays: `rgb` [C, H, W, 3] float32, `depth` [C, H, W] float32, `alpha`
        [C, H, W] float32, `instance` [C, H, W] int32, `features` [C, H, W, D] float32 or None.

    Examples:
        >>> out = rasterize_numpy(means, quats, scales, opacities, colors, viewmats, Ks, 64, 48)  # doctest: +SKIP
        >>> out["rgb"].shape, out["instance"].dtype  # doctest: +SKIP
        ((1, 48, 64, 3), dtype('int32'))
    """
    f32 = np.float32
    means = _as(means, f32, (-1, 3), "means")
    n = means.shape[0]
    quats = _as(quats, f32, (n, 4), "quats")
    scales = _as(scales, f32, (n, 3), "scales")
    opacities = _as(opacities, f32, (n,), "opacities")
    colors = _as(colors, f32, (n, 3), "colors")
    viewmats = _as(viewmats, f32, (-1, 4, 4), "viewmats")
    C = viewmats.shape[0]
    Ks = _as(Ks, f32, (C, 3, 3), "Ks")
    width = int(width)
    height = int(height)
    if width < 1 or height < 1:
        raise ValueError(f"Expected a positive image size, found {width}x{height}")
    feat = np.empty((n, 0), f32) if features is None else _as(features, f32, (n, -1), "features")
    D = feat.shape[1]
    ids = np.full(n, -1, np.int32) if object_ids is None else _as(object_ids, np.int32, (n,), "object_ids")
    bg = np.zeros(3, f32) if background is None else _as(background, f32, (3,), "background")
    near = np.full(C, 0.01) if nears is None else _as(nears, np.float64, (C,), "nears")
    rgb = np.empty((C, height, width, 3), np.float32)
    depth = np.empty((C, height, width), np.float32)
    alpha = np.empty((C, height, width), np.float32)
    inst = np.empty((C, height, width), np.int32)
    fout = np.empty((C, height, width, D), np.float32)
    ws = thread_workspace()
    for c in range(C):
        render_camera(means, quats, scales, opacities, colors, feat, ids, viewmats[c], Ks[c], float(near[c]),
                      width, height, bg, rgb[c], depth[c], alpha[c], inst[c], fout[c], timer=timer, ws=ws)
    return {"rgb": rgb, "depth": depth, "alpha": alpha, "instance": inst,
            "features": fout if features is not None else None}
