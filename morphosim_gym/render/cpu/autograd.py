"""`rasterize_cpu`: the differentiable torch entry point of the CPU kernels.

A `torch.autograd.Function` whose forward runs the compiled forward pass per camera and keeps
what the backward needs (projected records, depth-sorted tile lists, per-pixel final
transmittance and stop position, as 3DGS does), and whose backward runs the hand-written
kernels: `backward.raster_backward` (pixels -> 2D records) then
`projection.project_backward` (2D records -> means, quats, scales, opacities, colours,
features). float32 and float64 inputs run kernels compiled for that type (float64 with exact
exp, for gradient checks).
"""

from __future__ import annotations

from typing import Optional

import numba
import numpy as np
import torch

from .backward import NGRAD, raster_backward, reduce_entries
from .pipeline import render_camera, thread_workspace
from .projection import project_backward

__all__ = ["rasterize_cpu"]

#: optional `pipeline.StageTimer` collecting per-stage times (set by benchmarks/render.py)
_STAGE_TIMER = None


def _np(t: torch.Tensor) -> np.ndarray:
    return t.detach().contiguous().numpy()


class _RasterizeCPU(torch.autograd.Function):
    @staticmethod
    def forward(ctx, means, quats, scales, opacities, colors, features, viewmats, Ks, nears, width, height,
                ids, bg):
        npdt = np.float64 if means.dtype == torch.float64 else np.float32
        m, q, s, o, c, f = (_np(x) for x in (means, quats, scales, opacities, colors, features))
        C = viewmats.shape[0]
        D = f.shape[1]
        rgb = np.empty((C, height, width, 3), npdt)
        depth = np.empty((C, height, width), npdt)
        alpha = np.empty((C, height, width), npdt)
        inst = np.empty((C, height, width), np.int32)
        fout = np.empty((C, height, width, D), npdt)
        save = any(ctx.needs_input_grad[:6])   # no input needs a gradient: forward only, reuse scratch
        ws = None if save else thread_workspace()
        states = []
        for ci in range(C):
            states.append(render_camera(m, q, s, o, c, f, ids, viewmats[ci], Ks[ci], float(nears[ci]), width, height,
                                        bg, rgb[ci], depth[ci], alpha[ci], inst[ci], fout[ci], save=save,
                                        timer=_STAGE_TIMER, ws=ws))
        outs = [torch.from_numpy(x) for x in (rgb, depth, alpha, inst, fout)]
        ctx.mark_non_differentiable(outs[3])
        ctx.states = states
        ctx.cams = (viewmats, Ks, width, height)
        ctx.save_for_backward(means, quats, scales, opacities, colors, features, outs[0], outs[1], outs[4])
        return tuple(outs)

    @staticmethod
    def backward(ctx, g_rgb, g_depth, g_alpha, g_inst, g_feat):
        means, quats, scales, opacities, colors, features, rgb_t, depth_t, fout_t = ctx.saved_tensors
        viewmats, Ks, width, height = ctx.cams
        dtype = means.dtype
        npdt = np.float64 if dtype == torch.float64 else np.float32
        m, q, s, f = (_np(x) for x in (means, quats, scales, features))
        rgb, depth, fout = _np(rgb_t), _np(depth_t), _np(fout_t)
        C, H, W = depth.shape
        N, D = f.shape

        def grad_or_zeros(g, shape):
            if g is None:
                return np.zeros(shape, npdt)
            return np.ascontiguousarray(g.detach().numpy(), dtype=npdt)

        g_rgb = grad_or_zeros(g_rgb, (C, H, W, 3))
        g_depth = grad_or_zeros(g_depth, (C, H, W))
        g_alpha = grad_or_zeros(g_alpha, (C, H, W))
        g_feat = grad_or_zeros(g_feat, (C, H, W, D))
        gm = np.zeros((N, 3), npdt)
        gq = np.zeros((N, 4), npdt)
        gs = np.zeros((N, 3), npdt)
        go = np.zeros(N, npdt)
        gc = np.zeros((N, 3), npdt)
        gf = np.zeros((N, D), npdt)
        timer = _STAGE_TIMER
        nthr = numba.get_num_threads()
        grad2d = np.empty((N, NGRAD), npdt)
        gfeat2d = np.empty((N, D), npdt)
        claim = np.zeros(1, np.int64)
        for ci, st in enumerate(ctx.states):
            if timer:
                timer.start()
            total = st.lst.shape[0]
            grad_e = np.empty((total, NGRAD), npdt)
            gfeat_e = np.empty((total, D), npdt)
            raster_backward(st.order, claim, nthr, st.tile_start, st.lst, st.rec, f, width, height, st.tiles_x,
                            rgb[ci], depth[ci], fout[ci], st.tfinal, st.last, g_rgb[ci], g_depth[ci], g_alpha[ci],
                            g_feat[ci], grad_e, gfeat_e)
            reduce_entries(nthr, st.lst, grad_e, gfeat_e, grad2d, gfeat2d)
            if timer:
                timer.lap("bwd_raster")
            project_backward(nthr, m, q, s, viewmats[ci], Ks[ci], width, height, st.rec, grad2d, gfeat2d,
                             gm, gq, gs, go, gc, gf)
            if timer:
                timer.lap("bwd_project")
        grads = [torch.from_numpy(x) for x in (gm, gq, gs, go, gc, gf)]
        needs = ctx.needs_input_grad
        grads = [g if needs[k] else None for k, g in enumerate(grads)]
        return (*grads, None, None, None, None, None, None, None)


def rasterize_cpu(
    means: torch.Tensor,        # [N, 3]
    quats: torch.Tensor,        # [N, 4]
    scales: torch.Tensor,       # [N, 3]
    opacities: torch.Tensor,    # [N]
    colors: torch.Tensor,       # [N, 3]
    viewmats: torch.Tensor,     # [C, 4, 4]
    Ks: torch.Tensor,           # [C, 3, 3]
    width: int,
    height: int,
    features: Optional[torch.Tensor] = None,    # [N, D]
    object_ids: Optional[torch.Tensor] = None,  # [N]
    background: Optional[torch.Tensor] = None,  # [3]
    nears: Optional[torch.Tensor] = None,       # [C]
) -> dict:
    """Differentiable CPU splatting of N Gaussians into C cameras. Compiled twin of
    `morphosim_gym.render.reference.rasterize_torch`.

    Args:
        means: [N, 3]. quats: [N, 4] (w, x, y, z; normalised inside). scales: [N, 3] std devs.
        opacities: [N]. colors: [N, 3]. viewmats: [C, 4, 4] world->camera (OpenCV). Ks: [C, 3, 3].
        width, height: image size. features: optional [N, D]. object_ids: optional [N] int.
        background: optional [3] colour (default black). nears: optional [C] near planes (0.01).
        Float inputs are computed in the dtype of `means` (float32, or float64 for checks).

    Returns:
        dict with `rgb` [C, H, W, 3], `depth` [C, H, W], `alpha` [C, H, W], `instance` [C, H, W]
        int32 and `features` [C, H, W, D] (None without features). Gradients flow to means, quats,
        scales, opacities, colors and features (not to cameras or the background).

    Examples:
        >>> out = rasterize_cpu(means, quats, scales, opacities, colors, viewmats, Ks, 64, 48)  # doctest: +SKIP
        >>> out["rgb"].shape  # doctest: +SKIP
        torch.Size([1, 48, 64, 3])
    """
    dtype = means.dtype if means.dtype in (torch.float32, torch.float64) else torch.float32
    for name, t in (("means", means), ("quats", quats), ("scales", scales), ("opacities", opacities),
                    ("colors", colors), ("features", features)):
        if t is not None and t.device.type != "cpu":
            raise ValueError(f"Expected {name} on the CPU for the cpu backend, found device {t.device}")
    n = means.shape[0]
    npdt = np.float64 if dtype == torch.float64 else np.float32
    vm = np.ascontiguousarray(np.asarray(viewmats.detach().cpu().numpy(), dtype=npdt).reshape(-1, 4, 4))
    C = vm.shape[0]
    K = np.ascontiguousarray(np.asarray(Ks.detach().cpu().numpy(), dtype=npdt).reshape(C, 3, 3))
    near = np.full(C, 0.01) if nears is None else np.asarray(nears.detach().cpu().numpy(), np.float64).reshape(C)
    if object_ids is None:
        ids = np.full(n, -1, np.int32)
    else:
        ids = np.ascontiguousarray(object_ids.detach().cpu().numpy(), dtype=np.int32).reshape(n)
    bg = np.zeros(3, npdt) if background is None else np.asarray(background.detach().cpu().numpy(), npdt).reshape(3)
    feat = features.to(dtype) if features is not None else means.new_zeros((n, 0), dtype=dtype)
    rgb, depth, alpha, inst, fout = _RasterizeCPU.apply(
        means.to(dtype), quats.to(dtype), scales.to(dtype), opacities.to(dtype).reshape(n), colors.to(dtype), feat,
        vm, K, near, int(width), int(height), ids, bg)
    return {"rgb": rgb, "depth": depth, "alpha": alpha, "instance": inst,
            "features": fout if features is not None else None}
