"""The public render layer: contracts, scene rendering, bad input, optional backends."""

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.render import backend_available
from tests.conftest import make_tiny_scene


def test_render_scene_torch_backend_contract():
    scene = make_tiny_scene(n_per_object=60)
    cam = scene.camera.resized(32, 32)
    out = ms.render(scene, cam, t=1.0, backend="torch")
    assert out.rgb.shape == (32, 32, 3) and out.rgb.dtype == np.float32
    assert out.depth.shape == out.alpha.shape == (32, 32)
    assert out.instance.dtype == np.int32
    assert set(np.unique(out.instance)) <= {-1, 0, 1, 2}
    assert out.features is None
    assert np.all((out.rgb >= 0) & (out.rgb <= 1))


def test_render_batched_cameras_match_single():
    scene = make_tiny_scene(n_per_object=40)
    cams = [scene.camera.resized(24, 24), scene.camera.resized(24, 24).orbit(20, center=(0, 0.5, 0.3))]
    both = ms.render(scene, cams, backend="torch")
    assert both.rgb.shape == (2, 24, 24, 3)
    one = ms.render(scene, cams[1], backend="torch")
    np.testing.assert_allclose(both.rgb[1], one.rgb, atol=1e-6)


@pytest.mark.parametrize("kwargs,msg", [
    (dict(backend="vulkan"), "backend"),
    (dict(background=(2, 0, 0)), "background"),
    (dict(t=99.0), "Expected t"),
    (dict(features=True), "features"),
])
def test_render_bad_input(kwargs, msg):
    scene = make_tiny_scene(n_per_object=10)
    with pytest.raises(ValueError, match=msg):
        ms.render(scene, scene.camera, **kwargs)


def test_render_rejects_mixed_resolutions_and_non_sources():
    scene = make_tiny_scene(n_per_object=10)
    with pytest.raises(ValueError, match="all cameras"):
        ms.render(scene, [scene.camera, scene.camera.resized(10, 10)], backend="torch")
    with pytest.raises(ValueError, match="Scene4D or Gaussians"):
        ms.render("scene.msim", scene.camera)


def test_empty_scene_renders_background():
    cam = ms.Camera.look_at((0, -3, 1), (0, 0, 0), 16, 16)
    out = ms.render(ms.Gaussians.empty(), cam, backend="torch", background=(0.2, 0.4, 0.6))
    np.testing.assert_allclose(out.rgb, np.broadcast_to([0.2, 0.4, 0.6], (16, 16, 3)), atol=1e-7)
    assert np.all(out.alpha == 0) and np.all(out.depth == 0) and np.all(out.instance == -1)


@pytest.mark.skipif(backend_available("gsplat"), reason="gsplat and CUDA are present")
def test_gsplat_unavailable_is_a_clear_error():
    scene = make_tiny_scene(n_per_object=10)
    with pytest.raises(ms.BackendUnavailableError, match="gsplat"):
        ms.render(scene, scene.camera, backend="gsplat")
