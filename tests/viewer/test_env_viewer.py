"""`morphosim view --env`: the episode runner and its page, on a small stand-in env (always) and on
MorphoSim/Track-v0 (where the envs are installed)."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import morphosim_gym  # noqa: F401  (registers the envs, where present)
from morphosim_gym.policies import random_policy, resolve_policy
from morphosim_gym.viewer.env_app import EnvRunner, EnvViewer

HAVE_TRACK = "MorphoSim/Track-v0" in gym.registry


class CountingEnv(gym.Env):
    """Five steps; reward 1 - mean |action|; success from the third step; the image shows the step."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(self, render_mode="rgb_array"):
        self.observation_space = spaces.Dict({"rgb": spaces.Box(0, 255, (16, 16, 3), np.uint8)})
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.render_mode = render_mode
        self.n = 0

    def _obs(self):
        return {"rgb": np.full((16, 16, 3), 40 * self.n, np.uint8)}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.n = 0
        return self._obs(), {"success": False, "seed": seed}

    def step(self, action):
        self.n += 1
        reward = 1.0 - float(np.abs(action).mean())
        return self._obs(), reward, self.n >= 5, False, {"success": self.n >= 3, "reward_main": reward}

    def render(self):
        return np.full((24, 32, 3), 40 * self.n, np.uint8)


def forward_policy(env, seed):
    """A policy factory importable as 'tests.viewer.test_env_viewer:forward_policy'."""
    return lambda obs, info: np.array([0.5, 0.0], dtype=np.float32)


class FactoryLog:
    """A factory that records its calls and the (obs, info) its policy sees."""

    def __init__(self):
        self.calls, self.seen = [], []

    def __call__(self, env, seed):
        self.calls.append((env, seed))
        return lambda obs, info: (self.seen.append((int(obs["rgb"][0, 0, 0]), dict(info))),
                                  np.zeros(2, np.float32))[1]


def test_episodes_run_with_a_policy_and_restart():
    runner = EnvRunner(CountingEnv(), policy="zero", seed=7)
    rec = runner.record
    assert (rec.episode, rec.step, rec.info["seed"]) == (1, 0, 7)
    for _ in range(5):
        rec = runner.step()
    assert rec.terminated and rec.done and rec.step == 5 and rec.success
    assert rec.episode_return == pytest.approx(5.0) and runner.rewards == [1.0] * 5
    rec = runner.step()                                     # a finished episode is followed by a reset
    assert (rec.episode, rec.step, rec.info["seed"]) == (2, 0, 8)
    assert runner.observation_image.shape == (16, 16, 3)
    assert not runner.has_world
    ok, msg = runner.perturb("make the ball blue")
    assert not ok and "does not take language edits" in msg


def test_random_policy_is_seeded():
    def actions(seed):
        runner = EnvRunner(CountingEnv(), policy="random", seed=seed)
        rec = runner.record
        return [runner.act(rec.obs, rec.info) for _ in range(4)]

    np.testing.assert_array_equal(actions(3), actions(3))
    assert not np.array_equal(actions(3), actions(4))
    # the bench's random policy, from the episode's reset seed
    env = CountingEnv()
    bench = random_policy(env, 3)
    np.testing.assert_array_equal(actions(3), [bench(None, {}) for _ in range(4)])


def test_the_factory_is_called_once_per_episode_with_its_reset_seed():
    log = FactoryLog()
    runner = EnvRunner(CountingEnv(), policy=log, seed=7)
    assert runner.factory is log and [s for _, s in log.calls] == [7] and log.calls[0][0] is runner.env
    for _ in range(6):                                      # five steps, then the reset of episode 2
        runner.step()
    assert [s for _, s in log.calls] == [7, 8]
    assert [n for n, _ in log.seen] == [0, 40, 80, 120, 160]       # each step's act saw the latest obs
    assert log.seen[0][1]["seed"] == 7 and log.seen[1][1]["reward_main"] == 1.0   # and info (reset's, then step's)


def test_policies_by_name():
    env = CountingEnv()
    assert np.all(EnvRunner(env, policy="zero").act(None, {}) == 0)
    assert env.action_space.contains(EnvRunner(CountingEnv(), policy="random").act(None, {}))
    runner = EnvRunner(CountingEnv(), policy="tests.viewer.test_env_viewer:forward_policy")
    assert runner.factory is forward_policy
    np.testing.assert_array_equal(runner.act(None, {}), [0.5, 0.0])
    assert resolve_policy("zero") is EnvRunner(CountingEnv(), policy="zero").factory
    for bad in ("", "best", "tests.viewer.test_env_viewer:nothing", "no_such_module:f"):
        with pytest.raises(ValueError, match="policy"):
            EnvRunner(CountingEnv(), policy=bad)
    with pytest.raises(ValueError, match="to be a factory"):        # the viewer's old fn(obs, action_space)
        EnvRunner(CountingEnv(), policy=lambda obs, action_space: np.zeros(2, np.float32))


def test_task_policies_on_an_env_without_a_task_say_so():
    for name, who in (("oracle", "oracle"), ("color", "colour")):
        with pytest.raises(ValueError, match=f"MorphoSim env with a task .* for the {who} policy"):
            EnvRunner(CountingEnv(), policy=name)


def test_unknown_env_id_lists_the_known_ones():
    with pytest.raises(ValueError, match="registered env id"):
        EnvRunner("MorphoSim/Nothing-v0")


def test_viewer_panel_and_playback_on_a_plain_env():
    from morphosim_gym.viewer.testing import wait_for

    with EnvViewer(CountingEnv(), policy="tests.viewer.test_env_viewer:forward_policy", episodes=2, port=0,
                   verbose=False, steps_per_second=30, autoplay=True) as viewer:
        wait_for(lambda: not viewer._play.value, 10, message="playback to stop after 2 episodes")
        rec = viewer.runner.record
        assert rec.episode == 2 and rec.done
        text = viewer.panel_text
        assert "Episode 2" in text and "success: yes" in text and "return: 3.750" in text
        assert "reward\\_main 0.750" in text
        viewer._buttons.value = "New episode"               # the buttons work without a page too
        assert viewer.runner.record.episode == 3


# ----------------------------------------------------------------------------- MorphoSim/Track-v0
@pytest.fixture(scope="module")
def track_runner():
    if not HAVE_TRACK:
        pytest.skip("MorphoSim/Track-v0 is not registered in this build")
    runner = EnvRunner("MorphoSim/Track-v0", policy="random", seed=0)
    yield runner
    runner.close()


def test_track_third_person_view_shows_world_and_agent(track_runner):
    import morphosim_gym as ms

    runner = track_runner
    rec = runner.step()
    assert runner.has_world and runner.observation_image.shape == runner.env.observation_space["rgb"].shape
    g, bg = runner.world_gaussians()
    world = runner.env.unwrapped.world
    assert len(g) > len(world.gaussians())                 # the agent's own Gaussians are in the view
    cam = runner.default_camera(96, 64)
    out = ms.render(g, cam, background=bg)
    target = rec.info["target_id"]
    assert (out.instance == target).sum() > 5               # the target is in the third-person view
    assert (~np.isin(out.instance, [-1] + [o.id for o in world.scene.objects])).sum() > 5   # and the agent
    # the agent's camera from info is the camera the observation was rendered from
    eye = next(iter(runner.agent_cameras().values()))
    obs = ms.render(world.gaussians(), eye, background=bg).rgb_uint8()
    assert np.abs(obs.astype(int) - runner.observation_image.astype(int)).mean() < 3


@pytest.fixture(scope="module")
def track_env():
    if not HAVE_TRACK:
        pytest.skip("MorphoSim/Track-v0 is not registered in this build")
    env = gym.make("MorphoSim/Track-v0", prompt="a red ball bounces from right to left", render_mode="rgb_array")
    yield env
    env.close()


@pytest.mark.parametrize("name", ["oracle", "color"])
def test_track_runs_the_bench_builtins(track_env, name):
    """The viewer runs every built-in the bench has, including the task-aware ones."""
    from morphosim_gym.policies import BUILTIN_POLICIES

    runner = EnvRunner(track_env, policy=name, seed=0)
    assert runner.factory is BUILTIN_POLICIES[name]
    recs = [runner.step() for _ in range(8)]
    assert [r.step for r in recs] == list(range(1, 9)) and not any(r.done for r in recs)
    assert all(r.info["target_pixels"] > 0 for r in recs)            # both keep the target in view
    assert sum(r.info["centred"] for r in recs[-4:]) >= 3, [r.info["target_offset"] for r in recs]
    assert recs[-1].episode_return > 0.5 * len(recs)                 # reward_centred is 0.8 when centred


def test_track_language_edit_during_an_episode(track_runner):
    runner = track_runner
    target = runner.record.info["target"]
    before = runner.env.unwrapped.scene.content_hash()
    ok, msg = runner.perturb(f"make the {target} blue")
    assert ok, msg
    assert runner.env.unwrapped.scene.content_hash() != before
    ok, msg = runner.perturb("delete the giraffe")
    assert not ok and "giraffe" in msg


def test_cli_checks_the_policy_before_making_the_env(capsys):
    from morphosim_gym.cli import main

    assert main(["view", "--env", "MorphoSim/Nothing-v0", "--policy", "nope"]) == 2
    err = capsys.readouterr().err
    assert "Expected a policy in ['color', 'oracle', 'random', 'zero'] or 'module:callable', found 'nope'" in err
