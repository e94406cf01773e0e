"""Camera axes mid-episode: a field-of-view or camera-height edit scheduled at step k moves the task's
camera from that step on, in every task and in a suite (`axis: camera_fov, at: k`); before step k,
and for edits that leave the camera alone, everything stays bit-identical to the unedited run."""

import numpy as np
import pytest

from morphosim_gym.envs import LanguagePerturbation

from .conftest import PROMPT, make

AT = 3
WIDEN, RAISE = "widen the field of view", "raise the camera by 0.5 metres"
TASK_CAMERA = {"MorphoSim/Track-v0": "eye", "MorphoSim/Find-v0": "eye", "MorphoSim/Reach-v0": "scene"}


def _pose(info, name):
    """(camera-to-world [4, 4], fy) of an info's camera."""
    cam = info["cameras"][name]
    return np.linalg.inv(np.asarray(cam["world_to_camera"])), float(np.asarray(cam["K"])[1, 1])


def _run(env_id, schedule, steps=AT + 2):
    """(observations, infos) of a zero-action episode with the edits of `schedule`."""
    env = LanguagePerturbation(make(env_id, prompt=PROMPT), schedule=schedule)
    obs, info = env.reset(seed=0)
    out = [(obs, info)]
    zero = np.zeros(env.action_space.shape, np.float32)
    for _ in range(steps):
        obs, _, _, _, info = env.step(zero)
        out.append((obs, info))
    env.close()
    return out


@pytest.fixture(scope="module")
def track_runs():
    return {name: _run("MorphoSim/Track-v0", sched) for name, sched in
            (("plain", {}), ("wide", {AT: WIDEN}), ("high", {AT: RAISE}), ("dim", {AT: "dim the lights"}))}


def test_track_field_of_view_widens_at_step_k(track_runs):
    plain, wide = track_runs["plain"], track_runs["wide"]
    for k, ((o0, i0), (o1, i1)) in enumerate(zip(plain, wide)):
        same = k < AT
        assert np.array_equal(o0["rgb"], o1["rgb"]) == same, k
        want = i0["fov_y_deg"] * (1.0 if same else 1.3)
        assert i1["fov_y_deg"] == pytest.approx(want, rel=1e-9), k
    assert wide[-1][1]["perturbations"] == ((AT, WIDEN, True),)


def test_track_camera_rises_at_step_k_keeping_its_direction(track_runs):
    plain, high = track_runs["plain"], track_runs["high"]
    for k, ((_, i0), (_, i1)) in enumerate(zip(plain, high)):
        (c0, f0), (c1, f1) = _pose(i0, "eye"), _pose(i1, "eye")
        dz = 0.0 if k < AT else 0.5
        np.testing.assert_allclose(c1[:3, 3], c0[:3, 3] + [0.0, 0.0, dz], atol=1e-6, err_msg=str(k))
        np.testing.assert_allclose(c1[:3, :3], c0[:3, :3], atol=1e-9, err_msg=str(k))   # pan and tilt kept
        assert f1 == f0
    assert not np.array_equal(plain[-1][0]["rgb"], high[-1][0]["rgb"])


def test_an_edit_that_leaves_the_camera_keeps_the_rig_bit_identical(track_runs):
    plain, dim = track_runs["plain"], track_runs["dim"]
    for (o0, i0), (o1, i1) in zip(plain, dim):
        np.testing.assert_array_equal(o0["proprio"], o1["proprio"])
        np.testing.assert_array_equal(i0["cameras"]["eye"]["world_to_camera"], i1["cameras"]["eye"]["world_to_camera"])
        assert i0["fov_y_deg"] == i1["fov_y_deg"]


@pytest.mark.parametrize("env_id", ["MorphoSim/Find-v0", "MorphoSim/Reach-v0"])
def test_other_tasks_follow_camera_edits_mid_episode(env_id):
    name = TASK_CAMERA[env_id]
    plain = _run(env_id, {}, AT + 1)
    edited = _run(env_id, {AT: [WIDEN, RAISE]}, AT + 1)
    for k, ((_, i0), (_, i1)) in enumerate(zip(plain, edited)):
        (c0, f0), (c1, f1) = _pose(i0, name), _pose(i1, name)
        if k < AT:
            np.testing.assert_array_equal(c1, c0)
            assert f1 == f0
        else:                                           # wider: a shorter focal length; 0.5 m higher
            assert f1 < f0
            assert c1[2, 3] == pytest.approx(c0[2, 3] + 0.5, abs=1e-6)


def test_a_suite_schedules_the_camera_axes_mid_episode(tmp_path):
    from morphosim_gym.bench.episode import EpisodeKey, EpisodeRunner
    from morphosim_gym.bench.suite import load_suite

    suite = load_suite({
        "name": "cam_mid", "env": "MorphoSim/Track-v0", "env_kwargs": {"width": 32, "height": 32}, "episodes": 1,
        "frames": 0, "world": {"generation": {"num_frames": 9, "width": 32, "height": 32}},
        "scenes": {"prompt": "a red {object} moves from left to right", "fields": {"object": ["ball"]},
                   "target": "object", "target_color": None},
        "perturbations": [{"axis": "camera_fov", "at": AT}, {"axis": "camera_height", "at": AT}]})
    runner = EpisodeRunner(suite, str(tmp_path))
    rec = {p: runner.run(EpisodeKey("zero", p, 0)).record for p in ("base", "camera_fov", "camera_height")}
    assert all(r["status"] == "ok" for r in rec.values()), rec
    assert rec["camera_fov"]["at"] == AT and rec["camera_fov"]["perturbed"]
    assert rec["camera_fov"]["metrics"]["fov_y_deg"] == pytest.approx(1.3 * rec["base"]["metrics"]["fov_y_deg"])
    assert rec["camera_height"]["metrics"] != rec["base"]["metrics"]       # the target moves in the raised view


def _zero_steps(env, n):
    zero = np.zeros(env.action_space.shape, np.float32)
    return [env.step(zero)[4] for _ in range(n)]


def test_move_camera_mid_episode_matches_a_view_edit_of_the_same_offset():
    plain = make("MorphoSim/Track-v0", prompt=PROMPT)
    moved = make("MorphoSim/Track-v0", prompt=PROMPT)
    for env in (plain, moved):
        env.reset(seed=0)
        _zero_steps(env, AT - 1)
    generation = np.asarray(moved.unwrapped.world.scene.camera.position, dtype=np.float64)
    moved.unwrapped.move_camera({"position": (generation + [0.0, 0.0, 0.5]).tolist()})
    i0, i1 = _zero_steps(plain, 1)[0], _zero_steps(moved, 1)[0]
    (c0, f0), (c1, f1) = _pose(i0, "eye"), _pose(i1, "eye")
    np.testing.assert_allclose(c1[:3, 3], c0[:3, 3] + [0.0, 0.0, 0.5], atol=1e-6)
    np.testing.assert_allclose(c1[:3, :3], c0[:3, :3], atol=1e-9)
    assert f1 == f0
    plain.close()
    moved.close()


def test_move_camera_refuses_bad_moves_and_leaves_the_rig_as_it_was():
    env = make("MorphoSim/Track-v0", prompt=PROMPT)
    env.reset(seed=0)
    before = env.unwrapped.rig.qpos.copy()
    for bad in ({}, {"look_at": [0, 0, 0]}, {"position": [0, float("nan"), 1]}, {"fov_y_deg": 0}, {"zoom": 2}):
        with pytest.raises(ValueError, match="camera"):
            env.unwrapped.move_camera(bad)
    np.testing.assert_array_equal(env.unwrapped.rig.qpos, before)
    env.close()


def test_a_suite_camera_shift_at_step_k_moves_the_view_from_that_step(tmp_path):
    from morphosim_gym.bench.episode import EpisodeKey, EpisodeRunner
    from morphosim_gym.bench.suite import load_suite

    spec = {"name": "orbit_mid", "env": "MorphoSim/Track-v0", "env_kwargs": {"width": 32, "height": 32},
            "episodes": 1, "frames": 0, "world": {"generation": {"num_frames": 9, "width": 32, "height": 32}},
            "scenes": {"prompt": "a red {object} moves from left to right", "fields": {"object": ["ball"]},
                       "target": "object", "target_color": None},
            "perturbations": [{"name": "orbit_mid", "camera": {"orbit_deg": 25}, "at": AT}]}
    runner = EpisodeRunner(load_suite(spec), str(tmp_path))
    base, mid = (runner.run(EpisodeKey("zero", p, 0), frames=100) for p in ("base", "orbit_mid"))   # every step
    assert mid.record["status"] == "ok" and mid.record["at"] == AT and mid.record["perturbed"]
    assert mid.record["camera"] and "position" in mid.record["camera"]
    assert len(base.frames) == len(mid.frames) > AT + 1           # frame k: the observation after k steps
    for k, (f0, f1) in enumerate(zip(base.frames, mid.frames)):
        assert np.array_equal(f0, f1) == (k < AT), k
