"""`render_batch`: many views of different scenes in one batched pass, bit-identical to `render`."""

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.render import backend_available
from morphosim_gym.render.api import render_batch
from tests.conftest import make_tiny_scene
from tests.render.helpers import cameras, random_scene

_FIELDS = ("rgb", "depth", "alpha", "instance")

# (seed, Gaussians, width, height): different scenes, counts and image sizes; n = 0 is an empty view
_SPECS = [(0, 3000, 84, 84), (1, 400, 64, 48), (2, 0, 32, 32), (3, 6000, 100, 70), (4, 1500, 17, 90),
          (5, 50, 16, 16), (6, 2500, 84, 84), (7, 900, 48, 64)]


def _gaussians(seed: int, n: int, d: int = 0) -> ms.Gaussians:
    s = random_scene(seed, n, d=d)
    return ms.Gaussians(means=s["means"], quats=s["quats"], scales=s["scales"], opacities=s["opacities"],
                        colors=s["colors"], object_ids=s["object_ids"], features=s.get("features"))


def _views(specs, d: int = 0) -> list:
    views = []
    for k, (seed, n, w, h) in enumerate(specs):
        cam = cameras(w, h, 4)[k % 4]
        bg = (0.1 * (k % 3), 0.2, 0.05 * k)
        views.append((_gaussians(seed, n, d), cam, bg))
    return views


def _assert_same(batched, single, features: bool = False) -> None:
    for name in _FIELDS + (("features",) if features else ()):
        a, b = getattr(batched, name), getattr(single, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        assert np.array_equal(a, b), f"{name} differs"


@pytest.mark.parametrize("count", [1, 3, 8])
@pytest.mark.parametrize("parallel_projection", [False, True])
def test_batch_is_bit_identical_to_single_renders(count, parallel_projection, monkeypatch):
    from morphosim_gym.render.cpu import batch

    if parallel_projection:        # small batches project on the calling thread; force the prange path
        monkeypatch.setattr(batch, "SERIAL_BELOW", 0)
    views = _views(_SPECS[:count])
    outs = render_batch(views)
    assert len(outs) == count
    for (g, cam, bg), out in zip(views, outs):
        _assert_same(out, ms.render(g, cam, background=bg))


def test_batch_with_an_empty_view_and_all_empty():
    views = _views([(2, 0, 32, 32), (0, 2000, 40, 40)])
    outs = render_batch(views)
    assert np.all(outs[0].alpha == 0) and np.all(outs[0].instance == -1)
    np.testing.assert_array_equal(outs[0].rgb, np.broadcast_to(np.float32([0.0, 0.2, 0.0]), (32, 32, 3)))
    _assert_same(outs[1], ms.render(views[1][0], views[1][1], background=views[1][2]))
    empty = render_batch(_views([(2, 0, 16, 24), (3, 0, 8, 8)]))
    assert [o.rgb.shape for o in empty] == [(24, 16, 3), (8, 8, 3)]
    assert render_batch([]) == []


def test_batch_of_scenes_and_composited_parts_at_a_time():
    scene = make_tiny_scene(n_per_object=80)
    agent = _gaussians(9, 300)
    cam = scene.camera.resized(40, 32)
    views = [(scene, cam), ([scene, agent], cam.orbit(25, center=(0, 0.5, 0.3))), (agent, cam, (1, 1, 1))]
    outs = render_batch(views, t=1.0)
    for (src, c, *bg), out in zip(views, outs):
        _assert_same(out, ms.render(src, c, t=1.0, background=bg[0] if bg else None))


def test_batch_features():
    views = _views(_SPECS[:3], d=4)
    outs = render_batch(views, features=True)
    for (g, cam, bg), out in zip(views, outs):
        _assert_same(out, ms.render(g, cam, background=bg, features=True), features=True)


def test_batch_same_views_many_times_is_stable():
    views = _views(_SPECS[:4])
    first = render_batch(views)
    again = render_batch(views[::-1])[::-1]
    for a, b in zip(first, again):
        _assert_same(a, b)


def test_torch_backend_batch_matches_torch_render():
    views = _views([(0, 300, 24, 24), (1, 200, 16, 20)])
    for (g, cam, bg), out in zip(views, render_batch(views, backend="torch")):
        np.testing.assert_array_equal(out.rgb, ms.render(g, cam, background=bg, backend="torch").rgb)


@pytest.mark.parametrize("views,msg", [
    ([("nope", None)], "Camera"),
    ([(ms.Gaussians.empty(),)], "view 0"),
    ([(ms.Gaussians.empty(), cameras(8, 8)[0], (2, 0, 0))], "background"),
    ([("scene.msim", cameras(8, 8)[0])], "Scene4D or Gaussians"),
])
def test_batch_bad_input(views, msg):
    with pytest.raises(ValueError, match=msg):
        render_batch(views)


def test_batch_bad_backend_and_missing_features():
    with pytest.raises(ValueError, match="backend"):
        render_batch(_views(_SPECS[:1]), backend="vulkan")
    with pytest.raises(ValueError, match="features"):
        render_batch(_views(_SPECS[:1]), features=True)


@pytest.mark.skipif(backend_available("gsplat"), reason="gsplat and CUDA are present")
def test_gsplat_batch_unavailable_is_a_clear_error():
    with pytest.raises(ms.BackendUnavailableError, match="gsplat"):
        render_batch(_views(_SPECS[:2]), backend="gsplat")


def _clusters(seed: int, centres, n_each: int = 400, spread: float = 0.15) -> ms.Gaussians:
    """Objects as contiguous clusters of Gaussians (object id = cluster index) around `centres`."""
    rng = np.random.default_rng(seed)
    k = len(centres)
    means = (np.repeat(np.asarray(centres, np.float32), n_each, axis=0)
             + rng.normal(size=(k * n_each, 3)).astype(np.float32) * spread)
    return ms.Gaussians(means=means, quats=rng.normal(size=(k * n_each, 4)).astype(np.float32),
                        scales=np.exp(rng.uniform(-5.0, -2.5, size=(k * n_each, 3))).astype(np.float32),
                        opacities=rng.uniform(0.05, 1.0, size=k * n_each).astype(np.float32),
                        colors=rng.uniform(0, 1, size=(k * n_each, 3)).astype(np.float32),
                        object_ids=np.repeat(np.arange(k), n_each).astype(np.int32))


def test_object_culling_is_exact_and_drops_objects_outside_the_view():
    from morphosim_gym.render.cpu import batch

    # around the camera's view: in front, just off each edge (so footprints reach in), far off
    # each side, behind the camera, and straddling the near plane
    centres = [(0, 0, 0), (1.9, 0, 0), (-1.9, 0, 0.2), (0, 0, 1.6), (6, 0, 0), (-6, 1, 0), (0, 0, 7),
               (0, 0, -6), (0, -6, 1.5), (0, -3.0, 1.5), (0.5, 1.0, -0.3)]
    g = _clusters(0, centres)
    cams = cameras(48, 40, 4) + [cameras(96, 96, 1)[0].orbit(40, center=(0, 0, 0))]
    views = [(g, cam, (0.3, 0.2, 0.1)) for cam in cams]
    culled = render_batch(views, cull=True)
    plain = render_batch(views)
    for (src, cam, bg), a, b in zip(views, culled, plain):
        _assert_same(a, b)
        _assert_same(a, ms.render(src, cam, background=bg))
    bv = [batch.batch_view([g], c.world_to_camera, c.K, c.near, c.width, c.height) for c in cams]
    f32 = np.float32
    kept = batch._kept_ranges(np.array([0, len(g)]), np.ascontiguousarray(g.means, f32), g.scales, g.opacities,
                              g.object_ids, np.stack([v.viewmat for v in bv])[:1], np.stack([v.K for v in bv])[:1],
                              np.array([[48, 40, 3]]), np.array([cams[0].near], f32), True)
    n_kept = int((kept[0][:, 1] - kept[0][:, 0]).sum())
    assert 0 < n_kept <= len(g) - 4 * 400      # the 4 objects wholly outside the first view are dropped
