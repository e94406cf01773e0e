"""`SB3VecEnv`: the native vector env behind Stable-Baselines3's VecEnv interface, env for env what
SB3's DummyVecEnv of single envs gives (same-step autoreset, terminal observations, seeds)."""

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3.common.vec_env import DummyVecEnv, VecFrameStack  # noqa: E402

from morphosim_gym.envs import RGBObservation, make_vec  # noqa: E402
from morphosim_gym.envs.sb3_vec import SB3VecEnv, split_infos  # noqa: E402
from tests.envs.conftest import FAST, make  # noqa: E402

N = 2
KW = dict(FAST, scene_pool=2)


def _same_info(a: dict, b: dict) -> None:
    assert set(a) == set(b)
    for key, value in b.items():
        got = a[key]
        if isinstance(value, dict):
            _same_info(got, value)
        elif isinstance(value, np.ndarray):
            assert isinstance(got, np.ndarray) and got.dtype == value.dtype and np.array_equal(got, value), key
        else:
            assert got == value, key


def test_sb3_adapter_matches_dummy_vec_env_over_episodes():
    ours = SB3VecEnv(make_vec("MorphoSim/Track-v0", N, vectorization_mode="vector", **KW), obs_key="rgb")
    ref = DummyVecEnv([lambda: RGBObservation(make("MorphoSim/Track-v0", **KW)) for _ in range(N)])
    assert ours.observation_space == ref.observation_space and ours.action_space == ref.action_space
    ours.seed(5)
    ref.seed(5)
    np.testing.assert_array_equal(ours.reset(), ref.reset())
    rng = np.random.default_rng(0)
    dones_seen = 0
    for step in range(90):
        a = rng.uniform(-1, 1, (N, 3)).astype(np.float32)
        obs, rew, done, infos = ours.step(a)
        robs, rrew, rdone, rinfos = ref.step(a)
        np.testing.assert_array_equal(obs, robs)
        np.testing.assert_array_equal(rew, rrew)
        np.testing.assert_array_equal(done, rdone)
        for i in range(N):
            if done[i]:
                np.testing.assert_array_equal(infos[i].pop("terminal_observation"),
                                              rinfos[i].pop("terminal_observation"))
            rinfos[i].pop("episode", None)
            _same_info(infos[i], rinfos[i])
        dones_seen += int(done.sum())
        if dones_seen >= N and step >= 62:
            break
    assert dones_seen >= N
    assert ours.get_attr("dt") == ref.get_attr("dt")
    assert len(ours.env_method("snapshot", indices=[1])) == 1
    ours.set_attr("marker", 3, indices=0)
    assert ours.get_attr("marker", indices=[0]) == [3] and ours.env_is_wrapped(RGBObservation) == [False] * N
    ours.close()
    ref.close()


def test_sb3_adapter_with_frame_stack_and_errors():
    venv = make_vec("MorphoSim/Track-v0", N, vectorization_mode="vector", **KW)
    with pytest.raises(ValueError, match="obs_key"):
        SB3VecEnv(venv, obs_key="nope")
    with pytest.raises(ValueError, match="MorphoSimVectorEnv"):
        SB3VecEnv(object())
    stacked = VecFrameStack(SB3VecEnv(venv, obs_key="rgb"), 3)
    assert stacked.reset().shape == (N, 32, 32, 9)
    obs, _, _, infos = stacked.step(np.zeros((N, 3), np.float32))
    assert obs.shape == (N, 32, 32, 9) and len(infos) == N and "success" in infos[0]
    with pytest.raises(RuntimeError, match="step_async"):
        stacked.venv.step_wait()
    stacked.close()


def test_split_infos_follows_the_masks_and_nesting():
    infos = {"a": np.array([1, 2]), "_a": np.array([True, False]),
             "d": {"x": np.array([0.5, 0.25]), "_x": np.array([True, True])}, "_d": np.array([True, True])}
    assert split_infos(infos, 2) == [{"a": 1, "d": {"x": 0.5}}, {"d": {"x": 0.25}}]
