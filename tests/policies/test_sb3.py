"""`policies.sb3`: a saved SB3 model as a policy factory, with the training's frame stack rebuilt exactly
(a tiny randomly initialised PPO on a fake image env, no MorphoSim env needed)."""

import json
from types import SimpleNamespace

import numpy as np
import pytest
from gymnasium import spaces

pytest.importorskip("stable_baselines3")

from morphosim_gym.policies import policy_for_episode, resolve_policy  # noqa: E402
from morphosim_gym.policies.sb3 import ENV_VAR, SETTINGS_FORMAT, load_settings, sb3_policy  # noqa: E402

SIZE, STACK = 36, 3                                     # 36 px: the smallest image SB3's NatureCNN takes


class _ImageEnv:
    """The least a PPO needs to be built: stacked rgb observations and a 3-d action box."""

    def __init__(self):
        import gymnasium as gym

        class Env(gym.Env):
            observation_space = spaces.Box(0, 255, (SIZE, SIZE, 3 * STACK), np.uint8)
            action_space = spaces.Box(-1.0, 1.0, (3,), np.float32)

            def reset(self, *, seed=None, options=None):
                return self.observation_space.sample(), {}

            def step(self, action):
                return self.observation_space.sample(), 0.0, False, True, {}

        self.env = Env()


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(1)
    path = tmp_path_factory.mktemp("sb3") / "tiny_model.zip"
    model = PPO("CnnPolicy", _ImageEnv().env, n_steps=16, batch_size=16, seed=0, device="cpu",
                policy_kwargs={"features_extractor_kwargs": {"features_dim": 8}, "net_arch": []})
    model.save(path)
    settings = {"format": SETTINGS_FORMAT, "algo": "PPO", "env_id": "MorphoSim/Track-v0", "width": SIZE,
                "height": SIZE, "observation": "rgb", "frame_stack": STACK, "frame_stack_padding": "zero",
                "deterministic": True}
    path.with_suffix(".json").write_text(json.dumps(settings))
    return path, PPO.load(str(path), device="cpu")


def _env():
    return SimpleNamespace(action_space=spaces.Box(-1.0, 1.0, (3,), np.float32), unwrapped=SimpleNamespace())


def _frames(n, seed=0, size=SIZE):
    rng = np.random.default_rng(seed)
    return [{"rgb": rng.integers(0, 256, (size, size, 3), dtype=np.uint8), "proprio": np.zeros(6, np.float32)}
            for _ in range(n)]


def test_actions_equal_the_model_on_zero_padded_stacks_oldest_first(saved):
    path, model = saved
    act = policy_for_episode(sb3_policy(path), _env(), 7)
    frames = [f["rgb"] for f in _frames(5)]
    zero = np.zeros_like(frames[0])
    for t, obs in enumerate(_frames(5)):
        window = ([zero] * STACK + frames[:t + 1])[-STACK:]        # what VecFrameStack gives after a reset
        want = model.predict(np.concatenate(window, axis=-1), deterministic=True)[0]
        got = act(obs, {})
        assert got.shape == (3,)
        np.testing.assert_array_equal(got, want)


def test_the_stack_matters_and_each_episode_starts_fresh(saved):
    path, model = saved
    factory = sb3_policy(path)
    frames = _frames(4, seed=1)
    a = policy_for_episode(factory, _env(), 0)
    first = [a(o, {}) for o in frames]
    b = policy_for_episode(factory, _env(), 0)                      # a new episode: zero padding again
    np.testing.assert_array_equal(np.stack([b(o, {}) for o in frames]), np.stack(first))
    last_alone = model.predict(np.concatenate([np.zeros_like(frames[0]["rgb"])] * 2 + [frames[-1]["rgb"]], -1),
                               deterministic=True)[0]
    full = model.predict(np.concatenate([f["rgb"] for f in frames[1:]], -1), deterministic=True)[0]
    np.testing.assert_array_equal(first[-1], full)
    assert not np.array_equal(full, last_alone)       # the older frames change the action: the stack is used


def test_wrong_image_size_names_both_sizes(saved):
    path, _ = saved
    act = sb3_policy(path)(_env(), 0)
    with pytest.raises(ValueError, match=r"\(36, 36, 3\).*found \(48, 48, 3\).*width=36"):
        act(_frames(1, size=48)[0], {})


def test_missing_or_bad_settings_are_named(saved, tmp_path):
    path, _ = saved
    lone = tmp_path / "lone.zip"
    lone.write_bytes(path.read_bytes())
    with pytest.raises(ValueError, match="lone.json"):
        sb3_policy(lone)(_env(), 0)
    bad = json.loads(path.with_suffix(".json").read_text())
    bad["frame_stack"] = "3"
    lone.with_suffix(".json").write_text(json.dumps(bad))
    with pytest.raises(ValueError, match="'frame_stack' as int"):
        load_settings(lone)
    bad.update(frame_stack=3, format="other")
    lone.with_suffix(".json").write_text(json.dumps(bad))
    with pytest.raises(ValueError, match="format"):
        load_settings(lone)
    with pytest.raises(ValueError, match="no such file"):
        sb3_policy(tmp_path / "absent.zip")(_env(), 0)


def test_policy_from_env_resolves_as_a_module_spec(saved, monkeypatch):
    path, model = saved
    factory = resolve_policy("morphosim_gym.policies.sb3:policy_from_env")
    monkeypatch.delenv(ENV_VAR, raising=False)
    with pytest.raises(ValueError, match=ENV_VAR):
        factory(_env(), 0)
    monkeypatch.setenv(ENV_VAR, str(path))
    obs = _frames(1, seed=3)[0]
    stacked = np.concatenate([np.zeros_like(obs["rgb"])] * 2 + [obs["rgb"]], -1)
    np.testing.assert_array_equal(policy_for_episode(factory, _env(), 0)(obs, {}),
                                  model.predict(stacked, deterministic=True)[0])
