"""Tasks: YAML specs, scene distributions, reward shapes, registering user tasks."""

import math

import gymnasium as gym
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.colors import color_rgb
from morphosim_gym.envs import register_task
from morphosim_gym.tasks import (TASK_CLASSES, FindTask, ReachTask, TaskSpec, TrackTask, builtin_task_names,
                                 load_task_spec, make_task, tolerance)
from morphosim_gym.tasks.rewards import SIGMOIDS

from .conftest import FAST

USER_YAML = """
name: track-balls
kind: track
scenes:
  prompt: "a {color} {object} {motion}"
  target: object
  fields:
    color: [red, blue]
    object: [ball]
    motion: ["moves from left to right", "bounces from right to left"]
instruction: "follow the {target}"
params:
  success_fraction: 0.5
"""


def test_tolerance_shapes():
    assert tolerance(0.5, (0, 1)) == 1.0
    assert tolerance(1.5, (0, 1)) == 0.0                    # margin 0: an indicator
    for s in SIGMOIDS:
        assert tolerance(2.0, (0, 1), margin=1.0, sigmoid=s) == pytest.approx(0.1)
        assert tolerance(-1.0, (0, 1), margin=1.0, sigmoid=s) == pytest.approx(0.1)
        xs = np.linspace(1, 3, 9)
        v = tolerance(xs, (0, 1), margin=1.0, sigmoid=s)
        assert np.all(np.diff(v) <= 1e-12) and np.all((v >= 0) & (v <= 1))
    with pytest.raises(ValueError, match="bounds"):
        tolerance(0, (1, 0))
    with pytest.raises(ValueError, match="sigmoid"):
        tolerance(2, (0, 1), margin=1, sigmoid="cubic")


@pytest.mark.parametrize("sigmoid", SIGMOIDS)
def test_tolerance_of_a_number_is_the_array_value_to_the_bit(sigmoid):
    # the per-step reward path takes numbers through a float fast path: same value, same type
    xs = np.concatenate([np.random.default_rng(0).normal(0.3, 1.5, 200), [0.0, 0.15, 0.6, -np.inf, np.inf, np.nan]])
    for bounds, margin in [((0.0, 0.15), 0.5), ((0.12, 0.6), 0.15), ((0.0, 0.0), 1.0), ((0.0, 1.0), 0.0)]:
        ref = tolerance(xs, bounds, margin, sigmoid=sigmoid, value_at_margin=0.3)
        got = [tolerance(float(x), bounds, margin, sigmoid=sigmoid, value_at_margin=0.3) for x in xs]
        assert all(type(g) is float for g in got)
        np.testing.assert_array_equal(np.array(got), ref)


def test_ctrl_term_is_numpys_mean_to_the_bit():
    rng = np.random.default_rng(1)
    for n in range(1, 12):
        for _ in range(50):
            a = rng.uniform(-1, 1, n)
            assert TrackTask.ctrl_term(a, 0.013) == -0.013 * float(np.mean(a * a))


def test_builtin_tasks_load_and_match_their_kinds():
    assert builtin_task_names() == ["find", "reach", "track"]
    for name in builtin_task_names():
        task = make_task(name)
        assert isinstance(task, TASK_CLASSES[name]) and task.kind == name


def test_task_params_overrides_and_errors():
    task = TrackTask("track", success_fraction=0.5)
    assert task.params["success_fraction"] == 0.5
    with pytest.raises(ValueError, match="unknown"):
        TrackTask("track", nonsense=1.0)
    with pytest.raises(ValueError, match="kind 'reach'"):
        ReachTask("track")
    with pytest.raises(ValueError, match="weights"):
        FindTask("find", facing_weight=0.9)


def test_yaml_errors_name_the_key(tmp_path):
    base = {"name": "x", "kind": "track", "scenes": {"prompt": "a {color} {object}", "fields": {
        "color": ["red"], "object": ["ball"]}}}
    assert TaskSpec.from_dict(base).kind == "track"
    with pytest.raises(ValueError, match="colour"):
        TaskSpec.from_dict({**base, "colour": 1})
    with pytest.raises(ValueError, match="kind"):
        TaskSpec.from_dict({**base, "kind": "juggle"})
    with pytest.raises(ValueError, match="speed"):
        TaskSpec.from_dict({**base, "scenes": {"prompt": "a {speed} {object}", "fields": {"object": ["ball"]},
                                                 "target_color": None}})
    with pytest.raises(ValueError, match="scenes.target"):
        TaskSpec.from_dict({**base, "scenes": {**base["scenes"], "target": "thing"}})
    with pytest.raises(ValueError, match="distractors"):
        TaskSpec.from_dict({**base, "scenes": {**base["scenes"], "prompt": "a {object} next to {distractors}"}})
    with pytest.raises(ValueError, match="built-in task name"):
        load_task_spec(str(tmp_path / "missing.yaml"))


def test_sampling_is_seeded_and_articles_agree():
    spec = load_task_spec("find")
    a = [spec.scenes.sample(np.random.default_rng(3)).prompt for _ in range(2)]
    assert a[0] == a[1]
    prompts = [spec.scenes.sample(np.random.default_rng(s)).prompt for s in range(200)]
    assert not any(" a orange" in p or " a apple" in p or p.startswith("a orange") for p in prompts)
    assert any(" an " in p or p.startswith("an ") for p in prompts)


@pytest.mark.parametrize("name", ["track", "reach", "find"])
def test_scene_distribution_prompts_generate_with_their_target(name):
    """Every sampled prompt parses and generates, and the target is the named object (with its colour)."""
    spec = load_task_spec(name)
    sim = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=0.2))
    from morphosim_gym.envs.scenes import SceneSource

    src = SceneSource(sim)
    task = make_task(name)
    rng = np.random.default_rng(11)
    for i in range(6):
        req = spec.scenes.sample(rng)
        scene = src.get(req.prompt, i)
        target = task.resolve_target(scene, req.target)
        assert target.name == req.target
        if name != "find":
            assert target.dynamic
        color = req.fields.get("color")
        assert target.color == pytest.approx(color_rgb(color), abs=1e-3)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["track", "reach", "find"])
def test_scene_distribution_many_prompts(name):
    spec = load_task_spec(name)
    sim = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=0.2))
    from morphosim_gym.envs.scenes import SceneSource

    src = SceneSource(sim)
    task = make_task(name)
    rng = np.random.default_rng(5)
    for i in range(60):
        req = spec.scenes.sample(rng)
        assert task.resolve_target(src.get(req.prompt, i), req.target).name == req.target


def test_a_user_yaml_task_becomes_an_env_id(tmp_path):
    path = tmp_path / "track_balls.yaml"
    path.write_text(USER_YAML)
    env_id = register_task(path)
    assert env_id == "MorphoSim/TrackBalls-v0"
    env = gym.make(env_id, **FAST)
    _, info = env.reset(seed=0)
    assert info["target"] == "ball" and info["instruction"].startswith("follow the ")
    assert env.unwrapped.task.params["success_fraction"] == 0.5
    env2 = gym.make("MorphoSim/Track-v0", task=str(path), **FAST)
    assert env2.reset(seed=0)[1]["prompt"] == info["prompt"]


def test_track_reward_favours_the_centre():
    task = TrackTask("track")
    p = task.params
    env = gym.make("MorphoSim/Track-v0", prompt="a red ball moves from left to right", **FAST)
    env.reset(seed=0)
    u = env.unwrapped
    rewards = []
    for d in (0.0, 0.3, 0.8):                      # aim off the target by d half-images horizontally
        target = u.world.target_position()
        pan = np.arctan(d * np.tan(np.radians(u.rig.fov) / 2))
        u.rig.aim_at(target, (pan, 0.0))
        *_, info = env.step(np.zeros(3, np.float32))
        rewards.append(info["reward_centred"])
    assert rewards[0] > 0.75 and 0.2 < rewards[1] < 0.6 and 0.0 < rewards[2] < 0.1
    lo, hi = task.reward_range()
    assert lo == -p["ctrl_cost"] and hi == 1.0


def test_find_start_looks_away_from_the_scene_most_of_the_time():
    env = gym.make("MorphoSim/Find-v0", **FAST)
    angles = []
    for seed in range(8):
        _, info = env.reset(seed=seed)
        angles.append(info["target_angle"])
    assert np.mean(np.array(angles) > math.radians(30)) >= 0.75
