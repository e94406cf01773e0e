"""Public rendering layer: shape and dtype contracts, then dispatch to a backend.

`render` is the user-facing call (scenes or Gaussians, one or several cameras, numpy
out); `rasterize` is the functional, differentiable call on torch tensors that
reconstruction optimises through.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any, Optional, Sequence, Union

import numpy as np

from ..errors import BackendUnavailableError
from ..limits import check_render_size
from ..parallel import serialised
from ..scene.camera import Camera
from ..scene.gaussians import Gaussians
from ..scene.scene4d import Scene4D
from ..scene.sky import check_sky

__all__ = ["RenderOutput", "render", "render_batch", "open_batch", "submit_batch", "PendingRender", "rasterize", "BACKENDS", "cameras_to_arrays"]

BACKENDS = ("cpu", "torch", "gsplat")
_OUTPUT_KEYS = ("rgb", "depth", "alpha", "instance", "features")


@dataclass
class RenderOutput:
    """What one render returns. Arrays are numpy, or torch tensors when the inputs required gradients.

    With a single camera: `rgb` [H, W, 3] float32 in [0, 1], `depth` [H, W] expected camera-z
    depth of the visible Gaussians (0 where nothing is drawn), `alpha` [H, W], `instance` [H, W]
    int32 object id (-1 background), `features` [H, W, D] when asked. With a list of cameras,
    every array gains a leading [C] axis.
    """

    rgb: Any
    depth: Any
    alpha: Any
    instance: Any
    features: Any = None

    def rgb_uint8(self) -> np.ndarray:
        """`rgb` as uint8 (numpy), for images and videos."""
        from .cpu.uint8 import to_uint8

        return to_uint8(self.rgb.detach().cpu().numpy() if hasattr(self.rgb, "detach") else self.rgb)


Source = Union[Scene4D, Gaussians, Sequence[Union[Scene4D, Gaussians]]]


@serialised                 # one kernel launch at a time under numba's workqueue layer
def render(
    source: Source,
    camera: Union[Camera, Sequence[Camera]],
    t: float = 0.0,
    *,
    backend: str = "cpu",
    background: Optional[Sequence[float]] = None,
    features: bool = False,
    sky: Optional[np.ndarray] = None,
    lod: bool = False,
    lod_tol: float = 1.0,
) -> RenderOutput:
    """Render a scene at time `t` (or plain Gaussians) from one or several cameras in one pass.

    Args:
        source: a `Scene4D`, a `Gaussians`, or a list of them composited together (e.g. a scene
            plus an agent's Gaussians). Gaussians holding torch tensors that require gradients
            give differentiable torch outputs.
        camera: a `Camera`, or a list of Cameras of one resolution (outputs gain a leading [C]).
        t: seconds into the clip, for scenes (`ValueError` outside [0, duration]).
        backend: "cpu" (compiled kernels, default), "torch" (reference) or "gsplat" (CUDA).
        background: RGB in [0, 1]; default the first scene's sky (numpy renders) or background, else black.
        features: also render the D-channel latent feature map.
        sky: an equirectangular sky image [H', W', 3] in [0, 1] (`scene.sky`) shown behind what the
            Gaussians leave uncovered (numpy renders); default the first scene's when no
            `background` is given. Envs pass their scene's sky with their plain Gaussians.
        lod, lod_tol: on "cpu" with numpy Gaussians, draw far object runs as coarser merged sets
            whose cells project to at most `lod_tol` pixels (an approximation, off by default; see
            `render_batch` and `morphosim_gym.render.lod`).

    Returns:
        RenderOutput: rgb [H, W, 3], depth [H, W], alpha [H, W], instance [H, W] and, with
        `features`, features [H, W, D] (each with a leading [C] for a list of cameras).

    Examples:
        >>> cam = Camera.look_at(eye=(0, -4, 2), target=(0, 0, 0.5), width=128, height=128)
        >>> out = render(scene, cam, t=1.0)   # doctest: +SKIP
        >>> out.rgb.shape, out.instance.dtype  # doctest: +SKIP
        ((128, 128, 3), dtype('int32'))
    """
    if backend not in BACKENDS:
        raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")
    g, bg, sky = _resolve_source(source, t, background, sky)
    if features and g.feature_dim == 0:
        raise ValueError("Expected Gaussians with features for features=True, found none "
                         "(this scene has no distilled feature field)")
    single = isinstance(camera, Camera)
    cams = [camera] if single else list(camera)
    viewmats, Ks, nears, width, height = cameras_to_arrays(cams)
    if lod and backend == "cpu" and not g.is_torch and _lod_changes(source, t, cams, lod_tol):
        parts = list(source) if isinstance(source, (list, tuple)) else [source]
        outs = render_batch([(parts, c, background, sky) for c in cams], t, features=features, lod=True,
                            lod_tol=lod_tol)
        if single:
            return outs[0]
        return RenderOutput(**{k: (None if getattr(outs[0], k) is None else np.stack([getattr(o, k) for o in outs]))
                               for k in _OUTPUT_KEYS})
    check_render_size(len(cams), width, height, g.feature_dim if features else 0)

    if g.is_torch:
        import torch

        tensors = {k: getattr(g, k) for k in ("means", "quats", "scales", "opacities", "colors")}
        dtype = tensors["means"].dtype
        out = rasterize(**tensors, viewmats=torch.as_tensor(viewmats, dtype=dtype),
                        Ks=torch.as_tensor(Ks, dtype=dtype), width=width, height=height,
                        features=g.features if features else None, object_ids=g.object_ids,
                        background=torch.as_tensor(bg, dtype=dtype), nears=torch.as_tensor(nears),
                        backend=backend)
    else:
        out = _render_numpy(g, viewmats, Ks, nears, width, height, np.zeros(3) if sky is not None else bg, features,
                            backend)
        if sky is not None:
            out["rgb"] = _composite_sky(out["rgb"], out["alpha"], sky, cams)
    if single:
        out = {k: (None if v is None else v[0]) for k, v in out.items()}
    return RenderOutput(**{k: out.get(k) for k in _OUTPUT_KEYS})


def _lod_changes(source: Source, t: float, cams: Sequence[Camera], tol: float) -> bool:
    """Whether level of detail would draw any part of `source` coarser from any of these cameras
    (if not, `render` takes its exact path: same images, no batching cost)."""
    from .lod import lod_parts

    parts = _source_parts(source, t, None)[0]
    return any(len(got) != len(parts) or any(a is not b for a, b in zip(got, parts))
               for got in (lod_parts(parts, c.world_to_camera, c.K, c.near, tol) for c in cams))


View = tuple   # (source, camera), (source, camera, background) or (source, camera, background, sky)


@serialised
def render_batch(views: Sequence[View], t: float = 0.0, *, backend: str = "cpu",
                 features: bool = False, cull: bool = False, lod: bool = False,
                 lod_tol: float = 1.0) -> list[RenderOutput]:
    """Render several views, each its own source, camera and background, in one batched pass.

    Args:
        views: (source, camera) or (source, camera, background) tuples; `source` as for `render`
            (a `Scene4D`, a `Gaussians` or a list of them composited together), `camera` one
            `Camera` (views may differ in resolution), `background` as for `render` (None: the
            source's scene background, else black).
        t: seconds into the clip, for `Scene4D` sources.
        backend: "cpu" (one compiled pass over all views' tiles on all numba threads), "gsplat"
            (one CUDA launch per resolution; `BackendUnavailableError` without gsplat and CUDA)
            or "torch" (the reference, view by view).
        features: also render the feature maps (every view's Gaussians need features of one D).
        cull: on "cpu", skip runs of one object's Gaussians whose bounding sphere is outside the
            view before projecting them (images identical either way; a speed switch, off by
            default: the projection already culls off-screen Gaussians for ~5 ns each, so on
            200k-Gaussian scenes at 128 px it saved at most a few percent, and cost about as
            much when nothing could be dropped).
        lod: on "cpu", draw each far object run (one object id, >= 256 Gaussians) as the
            coarsest of its cached merged levels whose cell projects to at most `lod_tol`
            pixels at the run's nearest point (`morphosim_gym.render.lod`): an approximation,
            off by default; object ids and instance labels are kept. Ignored on other backends.
        lod_tol: that largest projected cell side in pixels (> 0; default 1).

    Returns:
        One `RenderOutput` per view (numpy, no leading camera axis), each exactly what
        `render(source, camera, t, background=background, features=features)` gives on the
        same backend (bit-identical on "cpu"). With one resolution the arrays of all views are
        views into one stacked buffer per field (`np.stack` them for a [V, ...] batch).

    Examples:
        >>> outs = render_batch([(scene_a, cam_a), (scene_b, cam_b, (1, 1, 1))], t=0.5)  # doctest: +SKIP
        >>> outs[1].rgb.shape  # doctest: +SKIP
        (84, 84, 3)
    """
    staged = _stage_batch(views, t, backend, features, lod, lod_tol)
    if isinstance(staged, list):
        return staged
    resolved, flat = staged
    if backend == "gsplat":
        from .gsplat_backend import render_batch_gsplat

        outs = render_batch_gsplat(flat, features=features)
    else:
        from .cpu.batch import rasterize_batch_numpy

        outs = rasterize_batch_numpy(_batch_views(flat), features=features, cull=cull)
    return _batch_outputs(outs, resolved)


class PendingRender:
    """A batched render under way (`open_batch`, `submit_batch`): views are `add`ed one at a
    time (helper threads start on the first while the caller prepares the next), then the batch
    is `close`d, and `partial(lo, hi)` / `result()` give `render_batch`'s outputs for them.

    Arguments as for `open_batch`.
    """

    def __init__(self, helpers: Any = None, t: float = 0.0, *, backend: str = "cpu", features: bool = False,
                 cull: bool = False, lod: bool = False, lod_tol: float = 1.0, workspace: Any = None,
                 capacity: Optional[tuple[int, int, int]] = None) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")
        if capacity is not None and (len(capacity) != 3 or any(int(c) < 0 for c in capacity)):
            raise ValueError(f"Expected capacity as (views, Gaussians, pixels) >= 0, found {capacity!r}")
        if helpers is None:
            from .cpu.claimed import RenderHelpers

            helpers = RenderHelpers(0)
        self._helpers, self._t, self._backend = helpers, t, backend
        self._features, self._cull, self._lod, self._lod_tol = features, cull, lod, lod_tol
        self._workspace = workspace
        self._hint = tuple(int(c) for c in capacity) if capacity is not None else None
        self._resolved: list = []        # per view: (parts, camera, background, sky)
        self._where: list = []           # per view: (ClaimedBatch, index in it), a RenderOutput, or None (deferred)
        self._deferred: list = []        # gsplat: (view index, view) rendered together at close
        self._batch: Any = None          # the open ClaimedBatch
        self._staged = [0, 0, 0]         # views, Gaussians, pixels staged into batches so far
        self._closed = False

    # --------------------------------------------------------------- adding views
    def add(self, view: View) -> int:
        """Add a view ((source, camera[, background[, sky]]), as `render_batch` takes them) and
        return its index; checked first (`ValueError`, with nothing added)."""
        if self._closed:
            raise ValueError("Expected an open batch to add a view to, found it closed")
        i = len(self._resolved)
        self._add_resolved(view, _resolve_view(i, view, self._t))
        return i

    def _add_resolved(self, view: View, resolved: tuple) -> None:
        parts, cam, bg, sky = resolved
        i = len(self._resolved)
        check_render_size(i + 1, cam.width, cam.height)
        if self._features and Gaussians.concat(parts).feature_dim == 0:
            raise ValueError(f"Expected Gaussians with features for features=True, found none in view {i}")
        if self._backend == "torch" or any(p.is_torch for p in parts):
            where: Any = render(parts, cam, backend=self._backend, background=bg, features=self._features)
        elif self._backend == "gsplat":
            where = None
            self._deferred.append((i, view))
        else:
            if self._lod:
                from .lod import lod_parts

                parts = lod_parts(parts, cam.world_to_camera, cam.K, cam.near, self._lod_tol)
            where = self._stage(parts, cam, np.zeros(3) if sky is not None else bg, sky)
        self._resolved.append(resolved)
        self._where.append(where)

    def _stage(self, parts: list, cam: Camera, bg: np.ndarray, sky: Optional[np.ndarray]) -> tuple:
        """Stage a view's numpy Gaussian parts into the open batch (a new one when none is open or
        it is full); its sky, if any, is composited by the thread that renders it."""
        view = (cam.world_to_camera, cam.K, cam.near, cam.width, cam.height, bg, None if sky is None else (sky, cam))
        if self._batch is not None and self._batch.add_parts(parts, *view):
            return self._staged_into(parts, cam, self._batch.num_views - 1)
        if self._batch is not None:
            self._batch.close()
        from .cpu.claimed import ClaimedBatch
        from .cpu.pipeline import Workspace

        first = self._staged[0] == 0
        dims = {0 if p.features is None else p.features.shape[1] for p in parts}
        dim = max(dims) if self._features else 0
        n = sum(len(p.means) for p in parts)
        batch = ClaimedBatch(features=self._features, cull=self._cull, capacity=self._capacity_for(n, cam), dim=dim,
                             workspace=self._workspace if first and self._workspace is not None else Workspace())
        if not batch.add_parts(parts, *view):
            raise AssertionError("a batch sized for a view must hold it")
        self._batch = batch
        self._helpers.submit(batch, post=False)
        self._helpers.handover(batch)        # posts it; a helper renders this view while the caller prepares the next
        return self._staged_into(parts, cam, 0)

    def _staged_into(self, parts: list, cam: Camera, k: int) -> tuple:
        self._staged[0] += 1
        self._staged[1] += sum(len(p.means) for p in parts)
        self._staged[2] += cam.width * cam.height
        return (self._batch, k)

    def _capacity_for(self, n: int, cam: Camera) -> tuple[int, int, int]:
        """A new batch's capacity: what the hint leaves after the views staged so far, and at
        least this view (`n` Gaussians), or (past the hint) the rest at the average view's size,
        with room to spare."""
        v0, n0, p0 = self._staged
        hv, hn, hp = self._hint if self._hint is not None else (0, 0, 0)
        left = max(hv - v0, 1)
        px = cam.width * cam.height
        mean_n = (n0 + n) / (v0 + 1)
        return (left, max(n, hn - n0, int(1.25 * mean_n * left) + 1), max(px, hp - p0, px * left))

    @property
    def staged(self) -> tuple[int, int, int]:
        """(views, Gaussians, pixels) staged for the compiled CPU renderer so far."""
        return tuple(self._staged)

    def close(self) -> None:
        """No more views: the helpers finish the staged ones (views for gsplat render now)."""
        if self._closed:
            return
        self._closed = True
        if self._batch is not None:
            self._batch.close()
        if self._deferred:
            outs = render_batch([v for _, v in self._deferred], self._t, backend=self._backend,
                                features=self._features, cull=self._cull, lod=self._lod, lod_tol=self._lod_tol)
            for (i, _), out in zip(self._deferred, outs):
                self._where[i] = out

    def cancel(self) -> None:
        """Close the batch and wait until no thread is rendering into its buffers (after an error
        part way through adding views: the workspace can then be reused)."""
        self.close()
        for batch in {id(w[0]): w[0] for w in self._where if isinstance(w, tuple)}.values():
            self._helpers.complete(batch)

    # --------------------------------------------------------------- outputs
    def result(self) -> list[RenderOutput]:
        """Close, render what the helpers have not claimed on this thread, wait for the rest, and
        return one `RenderOutput` per view (as `render_batch`)."""
        self.close()
        return self.partial(0, len(self._where))

    def partial(self, lo: int, hi: int, timeout_s: float = 600.0) -> list[RenderOutput]:
        """The outputs of views lo..hi - 1 of the closed batch as soon as they are rendered (this
        thread renders views nobody has claimed meanwhile), so the caller can use the first views
        while the helpers render the rest (`TimeoutError` after `timeout_s` seconds of waiting)."""
        if not self._closed:
            raise RuntimeError("Expected a closed batch before its outputs, found it open (close() it first)")
        out: list = []
        i = lo
        while i < hi:
            where = self._where[i]
            if not isinstance(where, tuple):
                out.append(where)
                i += 1
                continue
            batch, k = where
            j = i + 1
            while j < hi and isinstance(self._where[j], tuple) and self._where[j][0] is batch:
                j += 1
            dicts = self._helpers.partial(batch, k, k + (j - i), timeout_s)
            out.extend(_render_outputs(dicts))          # skies composited in the batch already
            i = j
        return out

    def first_ready(self, spans: Sequence[tuple[int, int]], timeout_s: float = 600.0) -> int:
        """The position in `spans` of the first (lo, hi) whose views lo..hi - 1 of the closed batch
        are all rendered; meanwhile this thread renders views nobody has claimed, the last one
        first, so a caller that uses the spans in any order (`partial(lo, hi)` of the span given)
        works on the first views while the helpers render the rest (`TimeoutError` after
        `timeout_s` seconds of waiting)."""
        if not self._closed:
            raise RuntimeError("Expected a closed batch before its outputs, found it open (close() it first)")
        return self._helpers.first_ready([[w for w in self._where[lo:hi] if isinstance(w, tuple)] for lo, hi in spans],
                                         timeout_s)

    def __del__(self, _finalizing: Any = sys.is_finalizing) -> None:   # bound now: at exit the module's globals are gone
        batch = getattr(self, "_batch", None)
        if batch is not None and not _finalizing():         # (and the helper threads with them)
            batch.close()                     # a helper waiting for more views returns


def open_batch(t: float = 0.0, *, helpers: Any = None, backend: str = "cpu", features: bool = False,
               cull: bool = False, lod: bool = False, lod_tol: float = 1.0, workspace: Any = None,
               capacity: Optional[tuple[int, int, int]] = None) -> PendingRender:
    """An open batched render: `add` views one at a time, `close` it, then take `result()` (or
    `partial(lo, hi)`), which equals `render_batch(views, t, ...)` (bit-identical on "cpu").

    On "cpu" with numpy Gaussians each view is staged and published as it is added, and a
    helper thread of `helpers` (a `cpu.claimed.RenderHelpers`; None: none, this thread renders
    at `result`) starts on it at once and renders it without the GIL while the caller prepares
    the next view; torch views render as they are added, gsplat views at `close`.

    Args:
        t, backend, features, cull, lod, lod_tol: as for `render_batch`.
        helpers: the threads that render beside the caller.
        workspace: a `cpu.pipeline.Workspace` holding the staged inputs until the outputs are
            taken (reuse one from batch to batch, one per batch in flight); None: fresh arrays.
        capacity: (views, Gaussians, pixels) expected, so that one set of buffers holds them all
            (more is fine: a full batch is closed and another one takes the next views).

    Examples:
        >>> pending = open_batch(helpers=RenderHelpers(1), capacity=(2, 8000, 2 * 84 * 84))  # doctest: +SKIP
        >>> for view in [(g_a, cam_a), (g_b, cam_b)]:  # doctest: +SKIP
        ...     pending.add(view)
        >>> pending.close(); outs = pending.result()  # doctest: +SKIP
    """
    return PendingRender(helpers, t, backend=backend, features=features, cull=cull, lod=lod, lod_tol=lod_tol,
                         workspace=workspace, capacity=capacity)


def submit_batch(views: Sequence[View], t: float = 0.0, *, helpers: Any, backend: str = "cpu",
                 features: bool = False, cull: bool = False, lod: bool = False,
                 lod_tol: float = 1.0, workspace: Any = None) -> PendingRender:
    """Start `render_batch(views, t, ...)` on `helpers` (a `cpu.claimed.RenderHelpers`) and return
    at once, closed; `.result()` of the returned `PendingRender` joins in on the calling thread
    and gives the outputs (bit-identical to `render_batch`'s). Every view is checked before any
    is staged. Arguments as for `render_batch` and `open_batch`.

    Examples:
        >>> helpers = RenderHelpers(1)  # doctest: +SKIP
        >>> pending = submit_batch([(g_a, cam_a), (g_b, cam_b)], helpers=helpers)  # doctest: +SKIP
        >>> outs = pending.result()  # doctest: +SKIP
    """
    resolved = [_resolve_view(i, view, t) for i, view in enumerate(views)]
    capacity = (len(views), sum(len(p) for parts, _, _, _ in resolved for p in parts),
                sum(cam.width * cam.height for _, cam, _, _ in resolved))
    pending = open_batch(t, helpers=helpers, backend=backend, features=features, cull=cull, lod=lod,
                         lod_tol=lod_tol, workspace=workspace, capacity=capacity)
    try:
        for view, res in zip(views, resolved):
            pending._add_resolved(view, res)
    except BaseException:
        pending.cancel()
        raise
    pending.close()
    return pending


def _stage_batch(views: Sequence[View], t: float, backend: str, features: bool, lod: bool,
                 lod_tol: float) -> Any:
    """`render_batch`'s checks; the finished outputs where the torch path renders view by view,
    else (resolved views, flat (parts, camera, background) views with level of detail applied)."""
    if backend not in BACKENDS:
        raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")
    resolved = [_resolve_view(i, view, t) for i, view in enumerate(views)]
    for _, cam, _, _ in resolved:
        check_render_size(len(resolved), cam.width, cam.height)
    if features:
        for i, (parts, _, _, _) in enumerate(resolved):
            if Gaussians.concat(parts).feature_dim == 0:
                raise ValueError(f"Expected Gaussians with features for features=True, found none in view {i}")
    if backend == "torch" or any(p.is_torch for parts, _, _, _ in resolved for p in parts):
        return [render(parts, cam, backend=backend, background=bg, features=features) for parts, cam, bg, _ in resolved]
    flat = [(parts, cam, np.zeros(3) if sky is not None else bg) for parts, cam, bg, sky in resolved]
    if lod and backend == "cpu":
        from .lod import lod_parts

        flat = [(lod_parts(parts, cam.world_to_camera, cam.K, cam.near, lod_tol), cam, bg) for parts, cam, bg in flat]
    return resolved, flat


def _batch_views(flat: list) -> list:
    from .cpu.batch import batch_view

    return [batch_view(parts, cam.world_to_camera, cam.K, cam.near, cam.width, cam.height, bg)
            for parts, cam, bg in flat]


def _batch_outputs(outs: list, resolved: list) -> list[RenderOutput]:
    for o, (_, cam, _, sky) in zip(outs, resolved):
        if sky is not None:          # as `render` does: the sky behind what the Gaussians leave uncovered
            o["rgb"] = _composite_sky(o["rgb"][None], o["alpha"][None], sky, [cam])[0]
    return _render_outputs(outs)


def _render_outputs(outs: list) -> list[RenderOutput]:
    return [RenderOutput(**{k: o.get(k) for k in _OUTPUT_KEYS}) for o in outs]


def _resolve_view(i: int, view: View, t: float) -> tuple[list[Gaussians], Camera, np.ndarray, Optional[np.ndarray]]:
    if not isinstance(view, (tuple, list)) or len(view) not in (2, 3, 4):
        raise ValueError(f"Expected view {i} as (source, camera), (source, camera, background) or (source, camera, "
                         f"background, sky), found {view!r}")
    source, camera = view[0], view[1]
    if not isinstance(camera, Camera):
        raise ValueError(f"Expected one Camera in view {i}, found {type(camera).__name__}")
    parts, bg, sky = _source_parts(source, t, view[2] if len(view) >= 3 else None, view[3] if len(view) == 4 else None)
    return parts, camera, bg, sky


def _resolve_source(source: Source, t: float, background: Optional[Sequence[float]],
                    sky: Optional[np.ndarray] = None) -> tuple[Gaussians, np.ndarray, Optional[np.ndarray]]:
    """The Gaussians of a render source at time t (parts concatenated), its checked background and
    its sky (given, or the first scene's when no background is given, else None)."""
    parts, bg, sky = _source_parts(source, t, background, sky)
    return Gaussians.concat(parts), bg, sky


def _source_parts(source: Source, t: float, background: Optional[Sequence[float]],
                  sky: Optional[np.ndarray] = None) -> tuple[list[Gaussians], np.ndarray, Optional[np.ndarray]]:
    """The parts of a render source as Gaussians at time t, the checked background (default: the
    first scene's, else black) and the sky behind it (the first scene's, only when no background
    is given)."""
    parts = list(source) if isinstance(source, (list, tuple)) else [source]
    if not parts:
        raise ValueError("Expected a Scene4D or Gaussians to render, found an empty list")
    gaussians = []
    for p in parts:
        if isinstance(p, Scene4D):
            gaussians.append(p.drawn_at(t))
        elif isinstance(p, Gaussians):
            gaussians.append(p)
        else:
            raise ValueError(f"Expected a Scene4D or Gaussians to render, found {type(p).__name__}")
    if sky is not None and not (isinstance(sky, np.ndarray) and sky.dtype == np.float32 and sky.ndim == 3
                                and not sky.flags.writeable):      # a scene's sky is checked (and frozen) already
        sky = check_sky(sky)
    elif sky is None and background is None:
        first = next((p for p in parts if isinstance(p, Scene4D)), None)
        sky = first.sky if first is not None else None
    if background is None:
        first = next((p for p in parts if isinstance(p, Scene4D)), None)
        background = first.background if first is not None else (0.0, 0.0, 0.0)
    if type(background) is tuple and len(background) == 3 and all(
            type(x) is float and 0.0 <= x <= 1.0 for x in background):     # a scene's (checked): the per-view path
        return gaussians, np.array(background), sky
    bg = np.asarray(background, dtype=np.float64)
    if bg.shape != (3,) or not np.all(np.isfinite(bg)) or bg.min() < 0 or bg.max() > 1:
        raise ValueError(f"Expected background as 3 numbers in [0, 1], found {background!r}")
    return gaussians, bg, sky


def _composite_sky(rgb: np.ndarray, alpha: np.ndarray, sky: np.ndarray, cams: Sequence[Camera]) -> np.ndarray:
    """The sky behind what the Gaussians leave uncovered (`scene.sky.composite_sky`, compiled), for
    every backend's numpy output."""
    from .cpu.sky import composite_sky_compiled

    return composite_sky_compiled(rgb, alpha, sky, cams)


def cameras_to_arrays(cams: Sequence[Camera]) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
    """viewmats [C, 4, 4], Ks [C, 3, 3], nears [C], width, height of cameras of one resolution."""
    if not cams:
        raise ValueError("Expected at least one Camera, found none")
    for c in cams:
        if not isinstance(c, Camera):
            raise ValueError(f"Expected Camera objects, found {type(c).__name__}")
    width, height = cams[0].width, cams[0].height
    for i, c in enumerate(cams):
        if (c.width, c.height) != (width, height):
            raise ValueError(f"Expected all cameras at {width}x{height}, found camera {i} at {c.width}x{c.height}")
    viewmats = np.stack([c.world_to_camera for c in cams])
    Ks = np.stack([c.K for c in cams])
    nears = np.array([c.near for c in cams])
    return viewmats, Ks, nears, width, height


def _render_numpy(g: Gaussians, viewmats, Ks, nears, width, height, bg, features, backend) -> dict:
    if backend == "cpu":
        from .cpu import rasterize_numpy

        return rasterize_numpy(g.means, g.quats, g.scales, g.opacities, g.colors, viewmats, Ks, width, height,
                               features=g.features if features else None, object_ids=g.object_ids,
                               background=bg, nears=nears)
    import torch

    def t32(x):
        return None if x is None else torch.from_numpy(np.array(x, dtype=np.float32))

    with torch.no_grad():
        out = rasterize(t32(g.means), t32(g.quats), t32(g.scales), t32(g.opacities), t32(g.colors),
                        t32(viewmats), t32(Ks), width, height,
                        features=t32(g.features) if features else None,
                        object_ids=None if g.object_ids is None else torch.from_numpy(np.array(g.object_ids)),
                        background=t32(bg), nears=torch.as_tensor(nears), backend=backend)
    return {k: (None if v is None else v.cpu().numpy()) for k, v in out.items()}


@serialised
def rasterize(
    means,        # [N, 3]
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
    backend: str = "cpu",
) -> dict:
    """Differentiable splatting of torch tensors (the functional core of `render`).

    Args:
        means: [N, 3]. quats: [N, 4] w, x, y, z (normalised inside). scales: [N, 3].
        opacities: [N]. colors: [N, 3]. viewmats: [C, 4, 4] world->camera. Ks: [C, 3, 3].
        width, height: pixels. features: [N, D] or None. object_ids: [N] or None.
        background: [3] or None (black). nears: [C] or None (0.01). backend: "cpu", "torch", "gsplat".

    Returns:
        dict: rgb [C, H, W, 3], depth [C, H, W], alpha [C, H, W], instance [C, H, W] int32,
        features [C, H, W, D] (None without features). Gradients flow to means, quats,
        scales, opacities, colors and features.
    """
    import torch

    n = means.shape[0]
    shapes = {"means": (means, (n, 3)), "quats": (quats, (n, 4)), "scales": (scales, (n, 3)),
              "opacities": (opacities, (n,)), "colors": (colors, (n, 3))}
    for name, (x, shape) in shapes.items():
        if tuple(x.shape) != shape:
            raise ValueError(f"Expected {name} of shape {shape}, found {tuple(x.shape)}")
    if features is not None and (features.ndim != 2 or features.shape[0] != n):
        raise ValueError(f"Expected features of shape ({n}, D), found {tuple(features.shape)}")
    if viewmats.ndim != 3 or viewmats.shape[1:] != (4, 4) or Ks.shape != (viewmats.shape[0], 3, 3):
        raise ValueError(f"Expected viewmats [C, 4, 4] and Ks [C, 3, 3], found {tuple(viewmats.shape)} "
                         f"and {tuple(Ks.shape)}")
    check_render_size(viewmats.shape[0], width, height, 0 if features is None else features.shape[1])
    if nears is None:
        nears = torch.full((viewmats.shape[0],), 0.01, dtype=torch.float64)
    if backend == "cpu":
        from .cpu import rasterize_cpu

        return rasterize_cpu(means, quats, scales, opacities, colors, viewmats, Ks, width, height,
                             features=features, object_ids=object_ids, background=background, nears=nears)
    if backend == "torch":
        from .reference import rasterize_torch

        out = rasterize_torch(means, quats, scales, opacities, colors, viewmats, Ks, width, height,
                              features=features, object_ids=object_ids, background=background, nears=nears)
        out.setdefault("features", None)
        return out
    if backend == "gsplat":
        from .gsplat_backend import rasterize_gsplat

        return rasterize_gsplat(means, quats, scales, opacities, colors, viewmats, Ks, width, height,
                                features=features, object_ids=object_ids, background=background, nears=nears)
    raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")


def backend_available(backend: str) -> bool:
    """Whether a backend can run here (gsplat needs the package and a CUDA GPU)."""
    if backend in ("cpu", "torch"):
        return True
    try:
        from .gsplat_backend import check_gsplat

        check_gsplat()
        return True
    except BackendUnavailableError:
        return False
