"""Gradients of the hand-written backward pass against autograd through the torch reference.

Both sides run in float64 with the same random cotangents on rgb, depth, alpha and features;
each input's gradient must agree to 1e-6 relative to its largest entry (the two differ only by
summation order, ~1e-14 in practice). A `torch.autograd.gradcheck` on a tiny scene checks the
backward against finite differences independently of the reference.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from morphosim_gym.render.cpu import rasterize_cpu
from morphosim_gym.render.reference import rasterize_torch

from .helpers import camera_arrays, cameras, random_scene

PARAMS = ("means", "quats", "scales", "opacities", "colors", "features")


def _grads(fn, scene, vm, K, near, W, H, dtype, bg=None, outputs=("rgb", "depth", "alpha", "features"), seed=0):
    ps = {k: torch.tensor(scene[k], dtype=dtype, requires_grad=True) for k in PARAMS if k in scene}
    out = fn(ps["means"], ps["quats"], ps["scales"], ps["opacities"], ps["colors"],
             torch.as_tensor(vm, dtype=dtype), torch.as_tensor(K, dtype=dtype), W, H,
             features=ps.get("features"), object_ids=torch.as_tensor(scene["object_ids"]),
             background=None if bg is None else torch.as_tensor(bg, dtype=dtype), nears=torch.as_tensor(near))
    gen = torch.Generator().manual_seed(seed)
    loss = 0.0
    for k in outputs:
        if out.get(k) is not None:
            cot = torch.randn(out[k].shape, generator=gen, dtype=torch.float64).to(dtype)  # same draws in any dtype
            loss = loss + (out[k] * cot).sum()
    loss.backward()
    return {k: p.grad for k, p in ps.items()}, out


def _assert_grads_close(g, g_ref, rtol):
    for k in g_ref:
        ref = g_ref[k]
        assert g[k] is not None, k
        scale = ref.abs().max().item()
        assert scale > 0, f"{k}: reference gradient is zero, the test scene does not exercise it"
        err = (g[k] - ref).abs().max().item()
        assert err <= rtol * scale, f"{k}: max abs error {err:.3e} vs max |grad| {scale:.3e}"


@pytest.mark.parametrize("seed,n,W,H,C,D,bg", [
    (0, 300, 40, 30, 1, 0, None),
    (1, 500, 33, 19, 2, 3, (0.3, 0.6, 0.1)),
    (2, 200, 24, 24, 4, 2, None),
])
def test_gradients_match_reference_float64(seed, n, W, H, C, D, bg):
    scene = random_scene(seed, n, d=D)
    vm, K, near = camera_arrays(cameras(W, H, C))
    g, out = _grads(rasterize_cpu, scene, vm, K, near, W, H, torch.float64, bg)
    g_ref, out_ref = _grads(rasterize_torch, scene, vm, K, near, W, H, torch.float64, bg)
    for k in ("rgb", "depth", "alpha"):
        torch.testing.assert_close(out[k], out_ref[k], rtol=1e-9, atol=1e-9)
    _assert_grads_close(g, g_ref, rtol=1e-6)


def test_gradients_from_some_outputs_only():
    # cotangents for rgb alone (depth, alpha, features unused: autograd passes None for them)
    scene = random_scene(3, 250, d=2)
    vm, K, near = camera_arrays(cameras(30, 30, 1))
    for outputs in (("rgb",), ("depth",), ("alpha",), ("features",)):
        g, _ = _grads(rasterize_cpu, scene, vm, K, near, 30, 30, torch.float64, outputs=outputs)
        g_ref, _ = _grads(rasterize_torch, scene, vm, K, near, 30, 30, torch.float64, outputs=outputs)
        for k in g:
            # the reference leaves .grad None for inputs the loss does not depend on
            ref = torch.zeros_like(g[k]) if g_ref[k] is None else g_ref[k]
            scale = max(ref.abs().max().item(), 1e-30)
            assert (g[k] - ref).abs().max().item() <= 1e-6 * scale, (outputs, k)


def test_gradcheck_tiny_scene():
    # 4 Gaussians well inside a 12x10 image, opacities below the 0.99 clamp: smooth in all inputs
    rng = np.random.default_rng(4)
    n = 4
    dt = torch.float64
    means = torch.tensor(rng.normal(size=(n, 3)) * 0.15, dtype=dt, requires_grad=True)
    quats = torch.tensor(rng.normal(size=(n, 4)), dtype=dt, requires_grad=True)
    scales = torch.tensor(rng.uniform(0.08, 0.2, size=(n, 3)), dtype=dt, requires_grad=True)
    opac = torch.tensor(rng.uniform(0.3, 0.8, size=n), dtype=dt, requires_grad=True)
    colors = torch.tensor(rng.uniform(size=(n, 3)), dtype=dt, requires_grad=True)
    feats = torch.tensor(rng.normal(size=(n, 2)), dtype=dt, requires_grad=True)
    vm, K, near = camera_arrays(cameras(12, 10, 1))
    vm, K = torch.tensor(vm), torch.tensor(K)
    bg = torch.tensor([0.2, 0.1, 0.4], dtype=dt)

    def f(m, q, s, o, c, ft):
        out = rasterize_cpu(m, q, s, o, c, vm, K, 12, 10, features=ft, background=bg)
        return out["rgb"], out["depth"], out["alpha"], out["features"]

    assert torch.autograd.gradcheck(f, (means, quats, scales, opac, colors, feats), eps=1e-6, atol=1e-5,
                                    rtol=1e-4)


def test_float32_gradients_close_to_float64():
    scene = random_scene(5, 400, d=2)
    vm, K, near = camera_arrays(cameras(32, 32, 1))
    g32, out = _grads(rasterize_cpu, scene, vm, K, near, 32, 32, torch.float32)
    g64, _ = _grads(rasterize_cpu, scene, vm, K, near, 32, 32, torch.float64)
    assert out["rgb"].dtype == torch.float32
    for k in g64:
        assert g32[k].dtype == torch.float32
        scale = g64[k].abs().max().item()
        # float32 rounding of ~1e-7 relative, amplified by the 1 / (1 - alpha) <= 100 factor
        assert (g32[k].double() - g64[k]).abs().max().item() <= 2e-3 * scale, k


def test_multiple_backwards_and_second_forward_before_backward():
    # the forward state is per call: two forwards, then both backwards
    scene = random_scene(6, 200)
    vm, K, near = camera_arrays(cameras(20, 20, 1))
    g1, _ = _grads(rasterize_cpu, scene, vm, K, near, 20, 20, torch.float64, seed=1)
    ps = {k: torch.tensor(scene[k], dtype=torch.float64, requires_grad=True) for k in PARAMS[:5]}
    args = (torch.as_tensor(vm), torch.as_tensor(K), 20, 20)
    o1 = rasterize_cpu(*(ps[k] for k in PARAMS[:5]), *args)
    o2 = rasterize_cpu(*(ps[k] for k in PARAMS[:5]), *args)
    gen = torch.Generator().manual_seed(1)
    cot = [torch.randn(o1[k].shape, generator=gen, dtype=torch.float64) for k in ("rgb", "depth", "alpha")]
    loss1 = sum((o1[k] * c).sum() for k, c in zip(("rgb", "depth", "alpha"), cot))
    loss2 = sum((o2[k] * c).sum() for k, c in zip(("rgb", "depth", "alpha"), cot))
    (loss1 + loss2).backward()
    for k in PARAMS[:5]:
        torch.testing.assert_close(ps[k].grad, 2 * g1[k], rtol=1e-10, atol=1e-12)


def test_gradients_bit_identical_across_runs_and_thread_counts():
    # each tile-list entry's gradient row is written by exactly one tile and rows are summed per
    # Gaussian in list order, so neither dynamic tile claiming nor the thread count changes a bit
    import numba

    scene = random_scene(7, 600, d=2)
    vm, K, near = camera_arrays(cameras(40, 40, 2))
    g1, _ = _grads(rasterize_cpu, scene, vm, K, near, 40, 40, torch.float32)
    g2, _ = _grads(rasterize_cpu, scene, vm, K, near, 40, 40, torch.float32)
    n = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        g3, _ = _grads(rasterize_cpu, scene, vm, K, near, 40, 40, torch.float32)
    finally:
        numba.set_num_threads(n)
    for k in g1:
        assert torch.equal(g1[k], g2[k]) and torch.equal(g1[k], g3[k]), k


def test_public_render_with_torch_gaussians_is_differentiable():
    from morphosim_gym.render import render
    from morphosim_gym.scene import Gaussians

    s = random_scene(9, 300, d=3)
    ps = {k: torch.tensor(s[k], requires_grad=True) for k in PARAMS}
    g = Gaussians(**ps, object_ids=torch.as_tensor(s["object_ids"]))
    cam = cameras(24, 20, 1)[0]
    out = render(g, cam, backend="cpu", features=True)
    ref = render(g, cam, backend="torch", features=True)
    assert out.rgb.shape == (20, 24, 3) and out.features.shape == (20, 24, 3)
    torch.testing.assert_close(out.rgb, ref.rgb, atol=1e-5, rtol=0)
    (out.rgb.sum() + out.depth.sum() + out.alpha.sum() + out.features.sum()).backward()
    for k, p in ps.items():
        assert p.grad is not None and torch.isfinite(p.grad).all() and p.grad.abs().sum() > 0, k
