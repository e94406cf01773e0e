"""Bad or extreme (but finite, valid) input never crashes a kernel nor yields NaN.

Documented behaviour: Gaussians whose centre is at or behind the near plane are culled (as in
the reference), so a camera behind or inside everything renders the background; so does an
empty scene or one entirely off-screen. Degenerate footprints (zero scales, overflowing
covariances) are either drawn like the reference or culled, never NaN.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from morphosim_gym.render.cpu import rasterize_cpu, rasterize_numpy
from morphosim_gym.render.reference import rasterize_torch

from .helpers import camera_arrays, cameras, random_scene

W, H = 33, 20
BG = np.array([0.1, 0.2, 0.3], np.float32)
CAM = cameras(W, H, 1)[0]                       # at (0, -3, 1.5), looking at the origin
EYE = np.array([0.0, -3.0, 1.5], np.float32)


def _case(name):
    s = random_scene(0, 300)
    rng = np.random.default_rng(1)
    if name == "empty":
        s = {k: v[:0] for k, v in s.items()}
    elif name == "behind_camera":
        s["means"] = s["means"] - np.array([0.0, 8.0, 0.0], np.float32)
    elif name == "all_off_screen":
        s["means"] = s["means"] + np.array([60.0, 0.0, 0.0], np.float32)
    elif name == "camera_inside_gaussians":
        # centres within 5 mm of the eye (closer than the 1 cm near plane), the camera deep inside them
        s["means"] = EYE + (rng.uniform(-1.0, 1.0, (300, 3)) * 0.0025).astype(np.float32)
        s["scales"] = np.exp(rng.uniform(-1.0, 1.0, (300, 3))).astype(np.float32)
    elif name == "straddling_near_plane":
        s["means"] = EYE + (rng.normal(size=(300, 3)) * 0.02).astype(np.float32)
        s["scales"] = np.exp(rng.uniform(-1.0, 0.5, (300, 3))).astype(np.float32)
    elif name == "huge_scales":
        s["scales"] = np.exp(rng.uniform(3.0, 5.0, (300, 3))).astype(np.float32)
    elif name == "overflowing_scales":
        s["scales"] = np.exp(rng.uniform(20.0, 30.0, (300, 3))).astype(np.float32)
    elif name == "tiny_scales":
        s["scales"] = np.exp(rng.uniform(-25.0, -15.0, (300, 3))).astype(np.float32)
    elif name == "zero_scales":
        s["scales"][:, :2] = 0.0
    elif name == "flat_discs":
        s["scales"][:, 2] = 0.0
    elif name == "tiny_quaternions":
        s["quats"] = s["quats"] * np.float32(1e-18)
    elif name == "opacity_at_cut":
        s["opacities"][:] = np.float32(1.0 / 255.0)
    elif name == "opaque":
        s["opacities"][:] = 1.0
    elif name == "far_away":
        s["means"] = (s["means"] * 1e3 + np.array([0.0, 1e5, 0.0])).astype(np.float32)
    return s


CASES = ["empty", "behind_camera", "all_off_screen", "camera_inside_gaussians", "straddling_near_plane",
         "huge_scales", "overflowing_scales", "tiny_scales", "zero_scales", "flat_discs", "tiny_quaternions",
         "opacity_at_cut", "opaque", "far_away"]
BACKGROUND_ONLY = {"empty", "behind_camera", "all_off_screen", "camera_inside_gaussians"}


@pytest.mark.parametrize("name", CASES)
def test_forward_is_finite_and_matches_reference(name):
    s = _case(name)
    vm, K, near = camera_arrays([CAM])
    out = rasterize_numpy(**s, viewmats=vm, Ks=K, width=W, height=H, background=BG)
    for k in ("rgb", "depth", "alpha"):
        assert np.all(np.isfinite(out[k])), k
    assert np.all((out["alpha"] >= 0) & (out["alpha"] <= 1))
    if name in BACKGROUND_ONLY:
        np.testing.assert_array_equal(out["rgb"][0], np.broadcast_to(BG, (H, W, 3)))
        assert np.all(out["alpha"] == 0) and np.all(out["depth"] == 0) and np.all(out["instance"] == -1)
    T = lambda x: torch.as_tensor(np.asarray(x, np.float32))  # noqa: E731
    ref = rasterize_torch(*(T(s[k]) for k in ("means", "quats", "scales", "opacities", "colors")), T(vm), T(K),
                          W, H, object_ids=torch.as_tensor(s["object_ids"]), background=T(BG))
    np.testing.assert_allclose(out["rgb"], ref["rgb"].numpy(), atol=1e-5)
    np.testing.assert_allclose(out["alpha"], ref["alpha"].numpy(), atol=1e-5)


@pytest.mark.parametrize("name", ["empty", "behind_camera", "straddling_near_plane", "huge_scales",
                                  "zero_scales", "opaque", "tiny_scales"])
def test_backward_is_finite(name):
    s = _case(name)
    vm, K, near = camera_arrays([CAM])
    ps = [torch.tensor(s[k], requires_grad=True) for k in ("means", "quats", "scales", "opacities", "colors")]
    out = rasterize_cpu(*ps, torch.as_tensor(vm), torch.as_tensor(K), W, H)
    (out["rgb"].sum() + out["depth"].sum() + out["alpha"].sum()).backward()
    for p in ps:
        assert p.grad is not None and torch.isfinite(p.grad).all()


def test_zero_feature_channels_and_no_object_ids():
    s = random_scene(2, 100)
    vm, K, near = camera_arrays([CAM])
    out = rasterize_numpy(s["means"], s["quats"], s["scales"], s["opacities"], s["colors"], vm, K, W, H,
                          features=np.zeros((100, 0), np.float32))
    assert out["features"].shape == (1, H, W, 0)
    assert np.all(out["instance"] == -1)        # no object ids: nothing to report
    g = [torch.tensor(s[k], requires_grad=True) for k in ("means", "quats", "scales", "opacities", "colors")]
    feats = torch.zeros((100, 0), requires_grad=True)
    o = rasterize_cpu(*g, torch.as_tensor(vm), torch.as_tensor(K), W, H, features=feats)
    o["rgb"].sum().backward()
    assert feats.grad is not None and feats.grad.shape == (100, 0)


def test_one_pixel_and_odd_sizes():
    s = random_scene(3, 200)
    for w, h in ((1, 1), (1, 17), (17, 1), (31, 33)):
        cam = cameras(w, h, 1)[0]
        vm, K, near = camera_arrays([cam])
        out = rasterize_numpy(**s, viewmats=vm, Ks=K, width=w, height=h)
        T = lambda x: torch.as_tensor(np.asarray(x, np.float32))  # noqa: E731
        ref = rasterize_torch(*(T(s[k]) for k in ("means", "quats", "scales", "opacities", "colors")), T(vm),
                              T(K), w, h, object_ids=torch.as_tensor(s["object_ids"]))
        assert out["rgb"].shape == (1, h, w, 3)
        np.testing.assert_allclose(out["rgb"], ref["rgb"].numpy(), atol=1e-5)


def test_non_finite_colour_or_feature_is_culled_not_nan():
    s = random_scene(4, 200, d=2)
    s["colors"][::7] = np.nan
    s["colors"][1::7, 1] = np.inf
    s["features"][2::7, 0] = np.nan
    vm, K, near = camera_arrays([CAM])
    out = rasterize_numpy(**s, viewmats=vm, Ks=K, width=W, height=H)
    for k in ("rgb", "depth", "alpha", "features"):
        assert np.all(np.isfinite(out[k])), k
    bad = np.zeros(200, bool)
    bad[::7] = bad[1::7] = bad[2::7] = True
    clean = {k: (v[~bad] if k != "features" else v[~bad]) for k, v in s.items()}
    ref = rasterize_numpy(**clean, viewmats=vm, Ks=K, width=W, height=H)
    np.testing.assert_array_equal(out["rgb"], ref["rgb"])


def test_mis_shaped_arguments_raise_value_error():
    s = random_scene(5, 10)
    vm, K, near = camera_arrays([CAM])
    with pytest.raises(ValueError, match="Expected quats of shape"):
        rasterize_numpy(s["means"], s["quats"][:, :3], s["scales"], s["opacities"], s["colors"], vm, K, W, H)
    with pytest.raises(ValueError, match="Expected Ks of shape"):
        rasterize_numpy(s["means"], s["quats"], s["scales"], s["opacities"], s["colors"], vm, K[:, :2], W, H)
    with pytest.raises(ValueError, match="Expected a positive image size"):
        rasterize_numpy(s["means"], s["quats"], s["scales"], s["opacities"], s["colors"], vm, K, 0, H)
