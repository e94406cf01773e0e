"""`scene=`: one fixed world from a scene file (e.g. a reconstructed video) in every env, with errors at make."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.envs import ENV_IDS

from .conftest import FAST, FAST_SIM, PROMPT


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    scene = ms.MorphoSim(FAST_SIM).generate(PROMPT, seed=0)
    path = tmp_path_factory.mktemp("scene") / "scene.msim"
    ms.save_scene(scene, path)
    return path


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_env_runs_on_a_scene_file(env_id, scene_file):
    env = gym.make(env_id, scene=str(scene_file), target="ball", **FAST)
    obs, info = env.reset(seed=0)
    assert info["target"] == "ball" and info["prompt"] == PROMPT and info["scene_seed"] is None
    obs2, *_ = env.step(env.action_space.sample())
    assert obs2["rgb"].shape == obs["rgb"].shape
    same = gym.make(env_id, scene=scene_file, target="ball", **FAST)
    np.testing.assert_array_equal(same.reset(seed=0)[0]["rgb"], obs["rgb"])   # a Path works too, same world
    env.close()


def test_the_scene_is_the_file_on_every_reset_and_edits_apply(scene_file):
    env = gym.make("MorphoSim/Track-v0", scene=scene_file, **FAST)
    ids = {env.reset(seed=s)[1]["scene_id"] for s in range(3)}
    assert len(ids) == 1
    _, info = env.reset(seed=0, options={"edits": ["make the ball blue"]})
    assert info["edits"] == ("make the ball blue",)


def test_a_file_that_is_not_a_scene_fails_at_make(tmp_path):
    bad = tmp_path / "scene.msim"
    bad.write_bytes(b"definitely not a scene")
    with pytest.raises(ValueError, match=r"scene\.msim"):
        gym.make("MorphoSim/Track-v0", scene=str(bad), **FAST)
    with pytest.raises(ValueError, match="no such file"):
        gym.make("MorphoSim/Track-v0", scene=str(tmp_path / "missing.msim"), **FAST)
    with pytest.raises(ValueError, match="Expected scene as a scene file path"):
        gym.make("MorphoSim/Track-v0", scene=3, **FAST)


def test_a_target_not_in_the_scene_fails_at_make_or_reset(scene_file):
    with pytest.raises(ValueError, match=r"target 'giraffe'.*scene\.msim.*ball"):
        gym.make("MorphoSim/Track-v0", scene=scene_file, target="giraffe", **FAST)
    env = gym.make("MorphoSim/Track-v0", scene=scene_file, **FAST)
    with pytest.raises(ValueError, match=r"target 'giraffe'.*scene\.msim"):
        env.reset(seed=0, options={"target": "giraffe"})


def test_scene_with_prompt_or_pool_is_refused(scene_file):
    with pytest.raises(ValueError, match="either scene"):
        gym.make("MorphoSim/Track-v0", scene=scene_file, prompt=PROMPT, **FAST)
    with pytest.raises(ValueError, match="either scene"):
        gym.make("MorphoSim/Track-v0", scene=scene_file, scene_pool=2, **FAST)
