"""Gaussians validation, Motion skinning and interpolation, Scene4D.at and edit history."""

import numpy as np
import pytest

from morphosim_gym.scene import Gaussians, Motion, Scene4D
from morphosim_gym.scene.rotations import (axis_angle_to_quat, matrix_to_quat, quat_multiply, quat_slerp,
                                           quat_to_matrix)
from tests.conftest import make_tiny_scene


def _g(n=4, **over):
    rng = np.random.default_rng(1)
    args = dict(means=rng.normal(size=(n, 3)), quats=rng.normal(size=(n, 4)), scales=np.full((n, 3), 0.1),
                opacities=np.full(n, 0.5), colors=np.full((n, 3), 0.5))
    args.update(over)
    return Gaussians(**args)


@pytest.mark.parametrize("field,value,msg", [
    ("means", np.zeros((4, 2)), "means of shape"),
    ("quats", np.zeros((4, 4)), "norm 0"),
    ("scales", np.zeros((4, 3)), "scales > 0"),
    ("scales", -np.ones((4, 3)), "scales > 0"),
    ("opacities", np.full(4, 1.5), "opacities in"),
    ("colors", np.full((4, 3), -0.1), "colors in"),
    ("means", np.full((4, 3), np.nan), "finite means"),
    ("features", np.zeros((3, 2)), "features of shape"),
    ("object_ids", np.zeros(5, dtype=int), "object_ids of shape"),
    ("object_ids", np.zeros(4) + 0.5, "integer object_ids"),
])
def test_gaussians_bad_input_names_field(field, value, msg):
    with pytest.raises(ValueError, match=msg):
        _g(**{field: value})


def test_gaussians_concat_and_subset():
    a, b = _g(3), _g(2, object_ids=np.array([4, 5]))
    c = Gaussians.concat([a, b])
    assert len(c) == 5 and c.object_ids.tolist() == [-1, -1, -1, 4, 5]
    assert len(c.subset(c.object_ids >= 0)) == 2
    assert len(Gaussians.empty()) == 0


def test_rotation_helpers_roundtrip():
    rng = np.random.default_rng(0)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[q[:, 0] < 0] *= -1
    np.testing.assert_allclose(matrix_to_quat(quat_to_matrix(q)), q, atol=1e-10)
    # slerp endpoints and midpoint angle
    a = axis_angle_to_quat(np.array([0, 0, 1.0]), 0.0)
    b = axis_angle_to_quat(np.array([0, 0, 1.0]), 1.0)
    np.testing.assert_allclose(quat_slerp(a, b, 0.5), axis_angle_to_quat(np.array([0, 0, 1.0]), 0.5), atol=1e-12)
    np.testing.assert_allclose(quat_multiply(b, a), b, atol=1e-12)


def test_scene_at_moves_rigid_objects_and_keeps_static(tiny_scene):
    s = tiny_scene
    g0, g1 = s.at(0.0), s.at(s.duration)
    ids = s.gaussians.object_ids
    np.testing.assert_array_equal(g0.means[ids == 0], g1.means[ids == 0])            # ground static
    np.testing.assert_allclose(g1.means[ids == 1] - g0.means[ids == 1], np.tile([2.0, 0, 0], ((ids == 1).sum(), 1)),
                               atol=1e-5)                                                 # ball moved 2 m along x
    # rigid: pairwise distances inside the cube are preserved under rotation
    c0, c1 = g0.means[ids == 2][:20], g1.means[ids == 2][:20]
    d0 = np.linalg.norm(c0[:, None] - c0[None], axis=-1)
    d1 = np.linalg.norm(c1[:, None] - c1[None], axis=-1)
    np.testing.assert_allclose(d0, d1, atol=1e-5)


def test_scene_at_interpolates_between_frames(tiny_scene):
    s = tiny_scene
    ids = s.gaussians.object_ids
    mid = s.at(0.5 / s.fps)                       # half-way between frame 0 and 1
    a, b = s.at(0.0), s.at(1.0 / s.fps)
    np.testing.assert_allclose(mid.means[ids == 1], 0.5 * (a.means[ids == 1] + b.means[ids == 1]), atol=1e-5)
    # cube centre rotates at constant angular rate: slerp half-way angle
    rot_mid = s.motion.node_poses(0.5)[0][1]
    expected = axis_angle_to_quat(np.array([0, 0, 1.0]), 0.5 * (np.pi / 2) / (s.num_frames - 1))
    np.testing.assert_allclose(rot_mid, expected, atol=1e-9)


@pytest.mark.parametrize("t", [-0.1, 100.0, float("nan"), "soon"])
def test_scene_at_rejects_time_outside_clip(tiny_scene, t):
    with pytest.raises(ValueError, match="Expected t"):
        tiny_scene.at(t)


def test_scene_is_immutable_and_at_returns_read_only_arrays(tiny_scene):
    with pytest.raises(ValueError):
        tiny_scene.gaussians.colors[0, 0] = 1.0
    g = tiny_scene.at(0.0)
    for name in ("means", "quats", "scales", "opacities", "colors", "object_ids"):
        with pytest.raises(ValueError):            # shared with the cache: a caller cannot corrupt it
            getattr(g, name)[:] = 0
    own = g.numpy()
    own.means[:] = 0.0                             # a copy is the caller's own
    assert not np.allclose(tiny_scene.at(0.0).means, 0.0)


def test_at_caches_recent_times_and_interleaves(tiny_scene, monkeypatch):
    from morphosim_gym.scene import scene4d
    from morphosim_gym.scene.scene4d import POSE_CACHE_SIZE

    monkeypatch.setattr(scene4d, "POSE_CACHE_BYTES", 0)      # only the count limit

    times = [i / tiny_scene.fps for i in range(min(tiny_scene.num_frames, POSE_CACHE_SIZE))]
    first = [tiny_scene.at(t) for t in times]
    again = [tiny_scene.at(t) for t in reversed(times)][::-1]
    assert all(a is b for a, b in zip(first, again))          # interleaved times hit the cache
    fresh = Scene4D(tiny_scene.gaussians, tiny_scene.motion, tiny_scene.objects, tiny_scene.fps, tiny_scene.cameras)
    for t, g in zip(times, first):
        np.testing.assert_array_equal(g.means, fresh.at(t).means)
        np.testing.assert_array_equal(g.quats, fresh.at(t).quats)
    tiny_scene.at(0.5 / tiny_scene.fps)                       # a new time evicts the least recently used
    assert len(tiny_scene._poses) <= POSE_CACHE_SIZE


def test_at_keeps_more_times_within_the_byte_budget(tiny_scene, monkeypatch):
    from morphosim_gym.scene import scene4d
    from morphosim_gym.scene.scene4d import POSE_CACHE_SIZE

    per_time = tiny_scene.gaussians.means.nbytes * 28 // 12     # posed means (12 B) and quats (16 B)
    keep = POSE_CACHE_SIZE + 3
    monkeypatch.setattr(scene4d, "POSE_CACHE_BYTES", keep * per_time)
    times = [i * tiny_scene.duration / (keep + 2) for i in range(keep + 2)]
    calls = []
    apply = tiny_scene.motion.apply
    monkeypatch.setattr(tiny_scene.motion, "apply", lambda *a: calls.append(1) or apply(*a), raising=False)
    first = [tiny_scene.at(t) for t in times[:keep]]
    assert len(calls) == keep and len(tiny_scene._poses) == keep
    assert all(tiny_scene.at(t) is g for t, g in zip(times[:keep], first)) and len(calls) == keep   # no re-skinning
    tiny_scene.at(times[keep])                                 # over the budget: the oldest goes
    assert len(tiny_scene._poses) == keep and tiny_scene._pose_bytes == keep * per_time
    assert float(tiny_scene.frame_index(times[0])) not in tiny_scene._poses


def test_centre_is_on_the_generation_cameras_axis(tiny_scene):
    c = tiny_scene.centre(0.0)
    cam = tiny_scene.camera
    off_axis = (c - cam.position) - ((c - cam.position) @ cam.forward) * cam.forward
    assert np.linalg.norm(off_axis) < 1e-9 and (c - cam.position) @ cam.forward > 0


def test_derive_and_undo_bit_exact(tiny_scene):
    colors = tiny_scene.gaussians.colors.copy()
    colors[tiny_scene.gaussians.object_ids == 1] = [0, 0, 1]
    edited = tiny_scene.derive("make the ball blue", gaussians=tiny_scene.gaussians.replace(colors=colors))
    assert edited.history == ("make the ball blue",)
    assert edited.undo() is tiny_scene
    assert edited.content_hash() != tiny_scene.content_hash()
    with pytest.raises(ValueError, match="undo"):
        tiny_scene.undo()


def test_scene_validation_names_problem(tiny_scene):
    g = tiny_scene.gaussians.replace(object_ids=np.full(len(tiny_scene.gaussians), 7, dtype=np.int32))
    with pytest.raises(ValueError, match="unknown ids"):
        tiny_scene.derive(gaussians=g)
    with pytest.raises(ValueError, match="fps"):
        tiny_scene.derive(fps=0)
    with pytest.raises(ValueError, match="skin"):
        Motion(np.ones((2, 1, 4)), np.zeros((2, 1, 3)), np.array([[0], [3]]), np.ones((2, 1)), np.zeros(1))


def test_object_lookup(tiny_scene):
    assert tiny_scene.object("ball").id == 1
    assert tiny_scene.object(2).name == "cube"
    with pytest.raises(ValueError, match="ground"):
        tiny_scene.object("giraffe")
    c0, c1 = tiny_scene.object_center("ball", 0.0), tiny_scene.object_center("ball", tiny_scene.duration)
    np.testing.assert_allclose(c1 - c0, [2, 0, 0], atol=1e-5)


def test_blend_skinning_two_nodes():
    # a Gaussian half bound to a still node and half to a node translated by (2, 0, 0) moves by (1, 0, 0)
    rot = np.tile([1.0, 0, 0, 0], (2, 2, 1))
    trans = np.zeros((2, 2, 3))
    trans[1, 1] = [2, 0, 0]
    m = Motion(rot, trans, np.array([[0, 1]]), np.array([[0.5, 0.5]]), np.array([0, 0]))
    means, quats = m.apply(np.zeros((1, 3), np.float32), np.array([[1, 0, 0, 0]], np.float32), 1.0)
    np.testing.assert_allclose(means, [[1, 0, 0]], atol=1e-6)
    np.testing.assert_allclose(quats, [[1, 0, 0, 0]], atol=1e-6)


def test_single_frame_scene_has_zero_duration():
    s = make_tiny_scene(frames=1)
    assert s.duration == 0.0 and len(s.at(0.0)) == len(s.gaussians)
    assert isinstance(s, Scene4D)


def test_scene_pickles_without_its_pose_cache(tiny_scene):
    import pickle

    tiny_scene.at(0.0)
    back = pickle.loads(pickle.dumps(tiny_scene))
    assert back.content_hash() == tiny_scene.content_hash() and len(back._poses) == 0
    np.testing.assert_array_equal(back.at(1.0 / tiny_scene.fps).means, tiny_scene.at(1.0 / tiny_scene.fps).means)
