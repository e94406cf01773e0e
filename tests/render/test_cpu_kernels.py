"""Kernel-level equivalence: projection (forward and backward) against `project_torch`, and the
binning / per-tile depth sort against a stable sort.

Tolerances: float64 on both sides, so values agree to ~1e-12 (rounding order only); the
pixel boxes are compared as the set of tiles they touch, which must be identical.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from morphosim_gym.render.cpu import _jit
from morphosim_gym.render.cpu.backward import NGRAD
from morphosim_gym.render.cpu.binning import (argsort_int, bin_fill, bin_offsets, plan_tiles, sort_segment,
                                              sorted_fill)
from morphosim_gym.render.cpu.projection import project_backward, project_forward
from morphosim_gym.render.reference import project_torch

from .helpers import camera_arrays, cameras, random_scene


def _project(scene, vm, K, W, H, near, nthr=2):
    f = lambda k: np.ascontiguousarray(scene[k], np.float64)  # noqa: E731
    n = scene["means"].shape[0]
    tiles_x, tiles_y = (W + 15) // 16, (H + 15) // 16
    rec = np.empty((n, _jit.NREC))
    trect = np.empty((4, n), np.int32)
    counts = np.empty((nthr, tiles_x * tiles_y), np.int32)
    project_forward(f("means"), f("quats"), f("scales"), f("opacities"), f("colors"), np.zeros((n, 0)), vm, K, W, H,
                    near, rec, trect, tiles_x, counts)
    return rec, trect, counts


@pytest.mark.parametrize("seed,n,W,H", [(0, 500, 64, 48), (1, 300, 37, 21)])
def test_projection_matches_project_torch(seed, n, W, H):
    scene = random_scene(seed, n, log_scale=(-4.0, 0.0))
    cams = cameras(W, H, 4)
    for cam in cams:
        vm, K, near = (a[0] for a in camera_arrays([cam]))
        rec, trect, counts = _project(scene, vm, K, W, H, near[()])
        T = lambda k: torch.as_tensor(scene[k], dtype=torch.float64)  # noqa: E731
        ref = project_torch(T("means"), T("quats"), T("scales"), T("opacities"), torch.as_tensor(vm),
                            torch.as_tensor(K), W, H, float(near))
        xy, conic, ext = ref["xy"].numpy(), ref["conic"].numpy(), ref["extent"].numpy()
        # drawn = valid and the box meets the image; the kernels cull the rest
        lo, hi = xy - ext, xy + ext
        on_screen = (hi[:, 0] >= 0.5) & (lo[:, 0] <= W - 0.5) & (hi[:, 1] >= 0.5) & (lo[:, 1] <= H - 0.5)
        drawn = ref["valid"].numpy() & on_screen
        kept = trect[1] >= trect[0]
        np.testing.assert_array_equal(kept, drawn)
        np.testing.assert_allclose(rec[kept][:, [_jit.R_MX, _jit.R_MY]], xy[kept], rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(rec[kept][:, [_jit.R_CA, _jit.R_CB, _jit.R_CC]], conic[kept], rtol=1e-9,
                                   atol=1e-12)
        np.testing.assert_allclose(rec[kept][:, _jit.R_Z], ref["depth"].numpy()[kept], rtol=1e-12)
        np.testing.assert_allclose(rec[kept][:, [_jit.R_EX, _jit.R_EY]], ext[kept], rtol=1e-9)
        # tiles touched, as the reference decides them (pixel centres of the tile inside the box)
        for i in np.flatnonzero(kept)[:200]:
            tx = [t for t in range((W + 15) // 16) if hi[i, 0] >= 16 * t + 0.5 and lo[i, 0] <= 16 * t + 15.5
                  and 16 * t < W]
            ty = [t for t in range((H + 15) // 16) if hi[i, 1] >= 16 * t + 0.5 and lo[i, 1] <= 16 * t + 15.5
                  and 16 * t < H]
            assert (trect[0, i], trect[1, i], trect[2, i], trect[3, i]) == (tx[0], tx[-1], ty[0], ty[-1])
        assert counts.sum() == sum((trect[1, i] - trect[0, i] + 1) * (trect[3, i] - trect[2, i] + 1)
                                   for i in np.flatnonzero(kept))


def test_binning_and_tile_sort_are_stable_depth_order():
    scene = random_scene(2, 3000)
    # many exact depth ties: snap the means to a coarse grid along the viewing direction
    scene["means"] = np.round(scene["means"] * 4) / 4
    W, H = 64, 48
    vm, K, near = (a[0] for a in camera_arrays(cameras(W, H, 1)))
    rec, trect, counts = _project(scene, vm, K, W, H, near[()])
    ntiles = counts.shape[1]
    tile_start = np.empty(ntiles + 1, np.int64)
    thread_off = np.empty(counts.shape, np.int64)
    total = bin_offsets(counts, tile_start, thread_off)
    lst = np.empty(total, np.int32)
    bin_fill(trect, (W + 15) // 16, thread_off, lst)
    order = np.empty(ntiles, np.int32)
    max_len = plan_tiles(tile_start, order)
    assert sorted(order.tolist()) == list(range(ntiles))
    lengths = np.diff(tile_start)
    assert np.all(np.diff(lengths[order]) <= 0) and max_len == lengths.max()
    keys = np.empty(max_len, np.uint64)
    idx = np.empty(max_len, np.int32)
    hist = np.empty(256, np.int64)
    z = rec[:, _jit.R_Z]
    assert len(np.unique(z[trect[1] >= trect[0]])) < 0.5 * (trect[1] >= trect[0]).sum()   # ties exist
    for t in range(ntiles):
        seg = lst[tile_start[t]:tile_start[t + 1]]
        assert np.all(np.diff(seg) > 0)                        # binning keeps index order
        sort_segment(lst, tile_start[t], len(seg), rec, keys, keys.copy(), idx, idx.copy(), hist)
        seg = lst[tile_start[t]:tile_start[t + 1]]
        # exactly the Gaussians whose rectangle covers the tile, in stable depth order
        expected = np.flatnonzero(trect[1] >= trect[0])
        expected = [i for i in expected if trect[0, i] <= t % ((W + 15) // 16) <= trect[1, i]
                    and trect[2, i] <= t // ((W + 15) // 16) <= trect[3, i]]
        expected = np.asarray(expected, np.int64)
        np.testing.assert_array_equal(seg, expected[np.argsort(z[expected], kind="stable")])


@pytest.mark.parametrize("ranges", [[(0, 3000)], [(0, 700), (900, 2500), (2600, 3000)]])
def test_sorted_fill_gives_the_lists_the_per_tile_sort_gives(ranges):
    # one depth sort of the visible Gaussians, then the fill: each tile's list as bin_fill +
    # sort_segment leave it, exact depth ties included (stable: index order), over index ranges
    scene = random_scene(2, 3000)
    scene["means"] = np.round(scene["means"] * 4) / 4
    W, H = 64, 48
    vm, K, near = (a[0] for a in camera_arrays(cameras(W, H, 1)))
    rec, trect, _ = _project(scene, vm, K, W, H, near[()])
    keep = np.zeros(3000, bool)
    for lo, hi in ranges:
        keep[lo:hi] = True
    trect[:, ~keep] = np.array([[0], [-1], [0], [-1]])                # outside the ranges: as if culled
    tiles_x, ntiles = (W + 15) // 16, ((W + 15) // 16) * ((H + 15) // 16)
    counts = np.zeros((1, ntiles), np.int32)
    for i in np.flatnonzero(trect[1] >= trect[0]):
        for ty in range(trect[2, i], trect[3, i] + 1):
            counts[0, ty * tiles_x + trect[0, i]:ty * tiles_x + trect[1, i] + 1] += 1
    tile_start = np.empty(ntiles + 1, np.int64)
    off = np.empty((1, ntiles), np.int64)
    total = bin_offsets(counts, tile_start, off)
    expected = np.empty(total, np.int32)
    bin_fill(trect, tiles_x, off.copy(), expected)
    keys, idx, hist = np.empty(total, np.uint64), np.empty(total, np.int32), np.empty(256, np.int64)
    for t in range(ntiles):
        sort_segment(expected, tile_start[t], tile_start[t + 1] - tile_start[t], rec, keys, keys.copy(), idx,
                     idx.copy(), hist)
    got = np.full(total, -1, np.int32)
    sorted_fill(np.array(ranges, np.int64), trect, rec, tiles_x, tile_start, got)
    np.testing.assert_array_equal(got, expected)


def test_argsort_int_is_stable():
    rng = np.random.default_rng(0)
    for n, hi in ((0, 5), (1, 5), (300, 7), (1000, 70000)):
        keys = rng.integers(0, hi, n).astype(np.int64)
        out = np.empty(n, np.int64)
        argsort_int(keys, out)
        np.testing.assert_array_equal(out, np.argsort(keys, kind="stable"))


def test_projection_backward_matches_autograd():
    scene = random_scene(3, 400, log_scale=(-3.0, -1.0))
    W, H = 48, 40
    vm, K, near = (a[0] for a in camera_arrays(cameras(W, H, 4)[3:]))
    rec, trect, _ = _project(scene, vm, K, W, H, near[()])
    kept = trect[1] >= trect[0]
    n = rec.shape[0]
    rng = np.random.default_rng(9)
    grad2d = rng.normal(size=(n, NGRAD))
    ps = {k: torch.tensor(scene[k], dtype=torch.float64, requires_grad=True)
          for k in ("means", "quats", "scales", "opacities", "colors")}
    ref = project_torch(ps["means"], ps["quats"], ps["scales"], ps["opacities"], torch.as_tensor(vm),
                        torch.as_tensor(K), W, H, float(near))
    g = torch.as_tensor(grad2d) * torch.as_tensor(kept, dtype=torch.float64)[:, None]
    loss = ((ref["xy"] * g[:, 0:2]).sum() + (ref["conic"] * g[:, 2:5]).sum() + (ps["opacities"] * g[:, 5]).sum()
            + (ref["depth"] * g[:, 6]).sum() + (ps["colors"] * g[:, 7:10]).sum())
    loss.backward()
    out = [np.zeros((n, 3)), np.zeros((n, 4)), np.zeros((n, 3)), np.zeros(n), np.zeros((n, 3)), np.zeros((n, 0))]
    f = lambda k: np.ascontiguousarray(scene[k], np.float64)  # noqa: E731
    project_backward(2, f("means"), f("quats"), f("scales"), vm, K, W, H, rec, grad2d, np.zeros((n, 0)), *out)
    for name, got in zip(("means", "quats", "scales", "opacities", "colors"), out):
        want = ps[name].grad.numpy()
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max(), err_msg=name)
