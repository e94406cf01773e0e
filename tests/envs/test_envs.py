"""The Gymnasium envs: API conformance, determinism, rewards, options, actions, edits, ecosystem."""

import ast
import dataclasses
import inspect
import re
import subprocess
import sys

import cv2
import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import morphosim_gym as ms
from morphosim_gym.envs import ENV_IDS, LanguagePerturbation, RGBObservation
from morphosim_gym.envs.config import DEFAULT_SIM_CONFIG, EnvConfig
from morphosim_gym.envs.find import FindEnv
from morphosim_gym.envs.scenes import SceneSource
from morphosim_gym.tasks import Task
from morphosim_gym.envs.reach import ReachEnv
from morphosim_gym.envs.track import TrackEnv

from .conftest import FAST, FAST_SIM, PROMPT, make

ENV_CLASSES = (TrackEnv, ReachEnv, FindEnv)


# ------------------------------------------------------------------ registration and API
def test_every_id_is_registered_with_a_string_entry_point():
    for env_id in ENV_IDS:
        spec = gym.spec(env_id)
        assert isinstance(spec.entry_point, str) and spec.entry_point.startswith("morphosim_gym.envs.")


def test_import_registers_without_compiling_or_generating():
    code = ("import sys, morphosim_gym, gymnasium; "
            "print('mujoco' in sys.modules, 'morphosim_gym.envs.core' in sys.modules, "
            "'MorphoSim/Track-v0' in gymnasium.registry)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False", "True"]


def test_check_env_passes(env_id):
    env = make(env_id, render_mode="rgb_array")
    check_env(env.unwrapped, skip_render_check=False)
    env.close()


def test_spaces(env_id):
    env = make(env_id, depth=True, segmentation=True)
    obs, info = env.reset(seed=0)
    assert set(obs) == {"rgb", "depth", "segmentation", "proprio"}
    assert obs["rgb"].shape == (32, 32, 3) and obs["rgb"].dtype == np.uint8
    assert obs["depth"].dtype == np.float32 and obs["segmentation"].dtype == np.int32
    assert env.observation_space.contains(obs)
    assert env.action_space.dtype == np.float32 and np.all(env.action_space.low == -1)
    # the target shows in the instance map under the id info gives
    assert info["id_to_name"][info["target_id"]] == info["target"]


def test_default_observation_is_84px_rgb_and_proprio():
    env = gym.make("MorphoSim/Track-v0", sim=FAST_SIM)
    obs, _ = env.reset(seed=0)
    assert set(obs) == {"rgb", "proprio"} and obs["rgb"].shape == (84, 84, 3)


def test_several_cameras_add_suffixed_keys():
    env = make("MorphoSim/Reach-v0", cameras=("scene", "wrist"), segmentation=True)
    obs, info = env.reset(seed=0)
    assert {"rgb", "rgb_wrist", "segmentation", "segmentation_wrist", "proprio"} == set(obs)
    assert set(info["cameras"]) == {"scene", "wrist"}
    assert not np.array_equal(obs["rgb"], obs["rgb_wrist"])
    with pytest.raises(ValueError, match="cameras of the rig"):
        make("MorphoSim/Reach-v0", cameras=("nope",))


def test_info_contents(env_id):
    env = make(env_id)
    obs, info = env.reset(seed=1)
    for key in ("success", "target", "target_id", "instruction", "prompt", "scene_id", "edits", "cameras",
                "id_to_name", "t", "scene_seed"):
        assert key in info
    assert info["success"] is False and info["t"] == 0.0
    assert len(info["scene_id"]) == 64 and info["scene_id"] == env.unwrapped.scene.content_hash()
    cam = next(iter(info["cameras"].values()))
    assert cam["K"].shape == (3, 3) and cam["world_to_camera"].shape == (4, 4)
    assert info["target"].split("_")[0] in info["prompt"]
    obs, r, term, trunc, info = env.step(env.action_space.sample())
    assert info["t"] == pytest.approx(0.1) and info["step"] == 1


# ------------------------------------------------------------------ docstrings
def _arguments_table(cls):
    doc = inspect.getdoc(cls)
    section = doc.split("## Arguments", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        if not line.startswith("| `"):
            continue
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        rows[cells[0].strip("`")] = (cells[1].strip("`").replace("\\|", "|"), cells[2].strip("`"))
    return rows


@pytest.mark.parametrize("cls", ENV_CLASSES)
def test_docstring_arguments_table_matches_the_config(cls):
    """Each env's Arguments table has one row per `EnvConfig` field, in field order, with the
    field's type and the env's default (`EnvConfig`'s, or the env's `config_defaults`)."""
    table = _arguments_table(cls)
    fields = {f.name: f for f in dataclasses.fields(EnvConfig)}
    assert list(table) == list(fields)
    assert set(cls.config_defaults) <= set(fields)
    for name, (type_text, default_text) in table.items():
        assert type_text == fields[name].type, name
        assert ast.literal_eval(default_text) == cls.config_defaults.get(name, fields[name].default), name
    assert ast.literal_eval(table["terminate_on_success"][1]) is (cls is not TrackEnv)


@pytest.mark.parametrize("cls", ENV_CLASSES)
def test_signature_shows_the_config_with_the_env_defaults(cls):
    table = _arguments_table(cls)
    params = inspect.signature(cls).parameters
    assert list(params) == list(table)
    for name, p in params.items():
        assert p.kind is inspect.Parameter.KEYWORD_ONLY
        assert p.default == ast.literal_eval(table[name][1]), name


@pytest.mark.parametrize("cls", ENV_CLASSES)
def test_docstring_sections_in_order(cls):
    doc = inspect.getdoc(cls)
    heads = re.findall(r"^## (.+)$", doc, flags=re.M)
    assert heads == ["Description", "Action Space", "Observation Space", "Rewards", "Starting State",
                     "Episode End", "Arguments", "Version History"]


# ------------------------------------------------------------------ determinism and rewards
def _rollout(env_id, seed, steps=8, **kw):
    env = make(env_id, **kw)
    rng = np.random.default_rng(seed)
    obs, info = env.reset(seed=seed)
    out = [(obs, 0.0, info)]
    for _ in range(steps):
        obs, r, term, trunc, info = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        out.append((obs, r, info))
        if term or trunc:
            break
    return env, out


def test_suite_determinism_memory_and_reward_bounds(env_id):
    """dm_control-style suite check: same seed and actions -> identical observations and rewards;
    observations never share memory across steps and are not constant; rewards within bounds."""
    env, a = _rollout(env_id, 7)
    _, b = _rollout(env_id, 7)
    assert len(a) == len(b)
    for (oa, ra, ia), (ob, rb, ib) in zip(a, b):
        assert oa.keys() == ob.keys()
        for k in oa:
            assert np.array_equal(oa[k], ob[k]), k
        assert ra == rb and ia["success"] == ib["success"] and ia["scene_id"] == ib["scene_id"]
    for (o1, _, _), (o2, _, _) in zip(a, a[1:]):
        for k in o1:
            assert not np.shares_memory(o1[k], o2[k]), k
    assert any(not np.array_equal(a[0][0]["rgb"], o["rgb"]) for o, _, _ in a[1:])
    lo, hi = env.unwrapped.task.reward_range()
    assert all(lo - 1e-9 <= r <= hi + 1e-9 for _, r, _ in a[1:])
    _, c = _rollout(env_id, 8)
    assert any(not np.array_equal(x[0]["rgb"], y[0]["rgb"]) for x, y in zip(a, c))


def test_reward_is_the_sum_of_its_terms(env_id):
    _, steps = _rollout(env_id, 3, steps=6)
    for _, r, info in steps[1:]:
        terms = {k: v for k, v in info.items() if k.startswith("reward_")}
        assert len(terms) >= 2
        assert r == pytest.approx(sum(terms.values()), abs=1e-12)
        assert all(v >= 0 for k, v in terms.items() if k != "reward_ctrl")


def test_seeding_through_np_random_only(env_id):
    env = make(env_id)
    o1, i1 = env.reset(seed=5)
    o2, i2 = env.reset(seed=6)
    o3, i3 = env.reset(seed=5)
    assert np.array_equal(o1["rgb"], o3["rgb"]) and i1["prompt"] == i3["prompt"]
    assert i1["prompt"] != i2["prompt"] or not np.array_equal(o1["rgb"], o2["rgb"])


# ------------------------------------------------------------------ time and episode end
def test_scene_time_follows_the_control_rate_and_the_clip_ends_the_episode():
    env = make("MorphoSim/Track-v0", control_hz=5.0)
    env.reset(seed=0)
    n = 0
    while True:
        _, _, term, trunc, info = env.step(np.zeros(3, np.float32))
        n += 1
        assert info["t"] == pytest.approx(min(n / 5.0, 6.0))
        assert not term
        if trunc:
            break
    assert n == 30 and info["t"] == pytest.approx(6.0)


def test_track_episode_is_60_steps_at_the_default_rate():
    env = make("MorphoSim/Track-v0", scene_pool=1)
    env.reset(seed=0)
    for n in range(1, 61):
        _, _, term, trunc, _ = env.step(np.zeros(3, np.float32))
        assert trunc == (n == 60) and not term


# ------------------------------------------------------------------ actions
def test_nan_actions_are_rejected_and_never_reach_the_rig(env_id):
    env = make(env_id)
    env.reset(seed=0)
    rig = env.unwrapped.rig
    q = rig.data.qpos.copy()
    bad = np.zeros(env.action_space.shape, np.float32)
    bad[0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        env.step(bad)
    bad[0] = np.inf
    with pytest.raises(ValueError, match="finite"):
        env.step(bad)
    assert np.array_equal(rig.data.qpos, q) and env.unwrapped._step_count == 0
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros(env.action_space.shape[0] + 1, np.float32))


def test_out_of_bounds_actions_are_clipped(env_id):
    e1, e2 = make(env_id), make(env_id)
    big = np.full(e1.action_space.shape, 5.0, np.float32)
    big[0] = -7.0
    e1.reset(seed=2)
    e2.reset(seed=2)
    o1, r1, *_ = e1.step(big)
    o2, r2, *_ = e2.step(np.clip(big, -1, 1))
    assert np.array_equal(o1["rgb"], o2["rgb"]) and np.array_equal(o1["proprio"], o2["proprio"]) and r1 == r2


# ------------------------------------------------------------------ reset options
def test_unknown_option_keys_are_rejected():
    env = make("MorphoSim/Track-v0")
    with pytest.raises(ValueError, match="unknown"):
        env.reset(seed=0, options={"prompt": PROMPT, "colour": "red"})
    with pytest.raises(ValueError, match="camera"):
        env.reset(seed=0, options={"camera": {"zoom": 2}})
    with pytest.raises(ValueError, match="edits"):
        env.reset(seed=0, options={"edits": [3]})


def test_prompt_scene_seed_and_target_options():
    env = make("MorphoSim/Track-v0")
    obs, info = env.reset(seed=0, options={"prompt": "a blue cube moves in a circle", "scene_seed": 4})
    assert info["prompt"] == "a blue cube moves in a circle" and info["scene_seed"] == 4
    assert info["target"] == "cube" and info["instruction"] == "keep the blue cube in the centre of the view"
    _, info2 = env.reset(seed=1, options={"prompt": "a blue cube moves in a circle", "scene_seed": 4})
    assert info2["scene_id"] == info["scene_id"]
    _, info3 = env.reset(seed=0, options={"prompt": "a red ball moves from left to right next to a green mug",
                                          "target": "mug"})
    assert info3["target"] == "mug"


def test_a_prompt_without_the_target_is_an_error():
    env = make("MorphoSim/Track-v0")
    with pytest.raises(ValueError, match="Expected the prompt to name the target 'dog'"):
        env.reset(seed=0, options={"prompt": PROMPT, "target": "dog"})
    with pytest.raises(ValueError, match="Expected the prompt to name the target"):
        make("MorphoSim/Find-v0", prompt=PROMPT, target="cube").reset(seed=0)
    with pytest.raises(ms.CommandError):
        env.reset(seed=0, options={"prompt": "make the ball blue"})      # an edit, not a scene


def test_camera_override_sets_the_start_view():
    env = make("MorphoSim/Track-v0", prompt=PROMPT)
    _, info = env.reset(seed=0)
    target = info["target_position"]
    eye = target + np.array([0.3, -1.5, 0.6])
    obs, info = env.reset(seed=0, options={"camera": {"position": eye, "look_at": target, "fov_y_deg": 20.0}})
    assert info["fov_y_deg"] == pytest.approx(20.0)
    cam = env.unwrapped.rig.camera("eye", 32, 32)
    np.testing.assert_allclose(cam.position, eye, atol=1e-9)
    assert info["target_offset"] < 1e-6 and info["centred"]


# ------------------------------------------------------------------ scene sources and pools
def test_oracle_fast_path_gives_the_same_scene_as_generate():
    sim = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=0.25))
    src = SceneSource(sim)
    a = src.get(PROMPT, 3)
    b = sim.generate(PROMPT, seed=3)
    assert a.content_hash() == b.content_hash()
    assert src.get(PROMPT, 3) is a                       # cached


def test_scene_pool_prebuilds_and_resets_do_not_generate():
    env = make("MorphoSim/Track-v0", scene_pool=3, pool_seed=2)
    src = env.unwrapped._source

    def fail(*a, **k):
        raise AssertionError("a reset generated a scene")

    src._generate = fail
    seen = {env.reset(seed=s)[1]["scene_id"] for s in range(12)}
    assert 1 <= len(seen) <= 3
    env2 = make("MorphoSim/Track-v0", scene_pool=3, pool_seed=2)
    assert {env2.reset(seed=s)[1]["scene_id"] for s in range(12)} == seen


# ------------------------------------------------------------------ edits
def _dilate(mask, r=3):
    return cv2.dilate(mask.astype(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)).astype(bool)


def test_reset_edits_show_in_the_observation_only():
    env = make("MorphoSim/Track-v0", prompt=PROMPT, width=64, height=64, segmentation=True)
    o0, i0 = env.reset(seed=0)
    o1, i1 = env.reset(seed=0, options={"edits": ["make the ball blue"]})
    assert i1["edits"] == ("make the ball blue",) and i0["edits"] == ()
    assert i1["scene_id"] != i0["scene_id"]
    target = o0["segmentation"] == i0["target_id"]
    diff = np.any(o0["rgb"] != o1["rgb"], axis=-1)
    assert diff[target].mean() > 0.9                      # the ball's pixels changed...
    assert not np.any(diff & ~_dilate(target))            # ...and nothing away from it
    assert o1["rgb"][target][:, 2].mean() > o1["rgb"][target][:, 0].mean()    # blue now
    assert np.array_equal(o0["segmentation"], o1["segmentation"]) and np.array_equal(o0["proprio"], o1["proprio"])
    for k in ("target", "target_offset", "prompt"):
        assert i0[k] == i1[k]


def test_perturb_mid_episode_shows_from_the_next_step():
    kw = dict(prompt=PROMPT, width=64, height=64, segmentation=True)
    ref, pert = make("MorphoSim/Track-v0", **kw), make("MorphoSim/Track-v0", **kw)
    a = np.array([0.2, -0.1, 0.0], np.float32)
    ref.reset(seed=0)
    pert.reset(seed=0)
    for _ in range(3):
        oa, ra, *_ = ref.step(a)
        ob, rb, *_ = pert.step(a)
        assert np.array_equal(oa["rgb"], ob["rgb"])
    assert pert.unwrapped.perturb("make the ball green") is True
    oa, ra, _, _, ia = ref.step(a)
    ob, rb, _, _, ib = pert.step(a)
    target = oa["segmentation"] == ia["target_id"]
    diff = np.any(oa["rgb"] != ob["rgb"], axis=-1)
    assert diff[target].mean() > 0.9 and not np.any(diff & ~_dilate(target))
    assert ra == rb and ib["edits"] == ("make the ball green",)


def test_failed_edits_raise_by_default_and_skip_when_asked():
    env = make("MorphoSim/Track-v0", prompt=PROMPT)
    # "reverse the ground" fails inside the editor without loading the text-embedding model
    with pytest.raises(ms.EditError, match="ground"):
        env.reset(seed=0, options={"edits": ["reverse the ground"]})
    with pytest.raises(ms.CommandError):
        env.reset(seed=0, options={"edits": ["make the ball move -2 times faster"]})
    o_skip, info = env.reset(seed=0, options={"edits": ["reverse the ground"], "on_edit_error": "skip"})
    o_plain, _ = env.reset(seed=0)
    assert info["edits"] == () and "ground" in info["edit_errors"][0]
    assert np.array_equal(o_skip["rgb"], o_plain["rgb"])
    env.reset(seed=0)
    with pytest.raises(ms.EditError):
        env.unwrapped.perturb("reverse the ground")
    skip = make("MorphoSim/Track-v0", prompt=PROMPT, on_edit_error="skip")
    skip.reset(seed=0)
    assert skip.unwrapped.perturb("reverse the ground") is False


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_removing_the_target_keeps_the_episode_running(env_id):
    env = make(env_id, prompt=PROMPT)
    env.reset(seed=0, options={"edits": ["remove the ball"]})
    _, r, _, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
    assert info["target_position"] is None and not info["success"]
    assert info.get("target_pixels", info.get("target_visible_pixels")) == 0


def test_language_perturbation_wrapper_schedule_and_probability():
    kw = dict(prompt=PROMPT, width=48, height=48)
    env = LanguagePerturbation(make("MorphoSim/Track-v0", **kw), schedule={2: "make the ball blue"})
    ref = make("MorphoSim/Track-v0", **kw)
    a = np.zeros(3, np.float32)
    _, info = env.reset(seed=0)
    ref.reset(seed=0)
    assert info["perturbations"] == ()
    o1, *_ = env.step(a)
    r1, *_ = ref.step(a)
    assert np.array_equal(o1["rgb"], r1["rgb"])
    o2, _, _, _, info = env.step(a)
    r2, *_ = ref.step(a)
    assert not np.array_equal(o2["rgb"], r2["rgb"])
    assert info["perturbations"] == ((2, "make the ball blue", True),) and info["edits"] == ("make the ball blue",)
    at_reset = LanguagePerturbation(make("MorphoSim/Track-v0", **kw), schedule={0: "make the ball blue"})
    _, info = at_reset.reset(seed=0)
    assert info["edits"] == ("make the ball blue",)

    def logs(seed):
        w = LanguagePerturbation(make("MorphoSim/Track-v0", **kw), edits=["make the ball blue",
                                 "make the ball green"], probability=0.3, max_random_edits=2)
        w.reset(seed=seed)
        for _ in range(12):
            *_, info = w.step(a)
        return info["perturbations"]

    assert logs(1) == logs(1) and 1 <= len(logs(1)) <= 2
    with pytest.raises(ValueError, match="probability"):
        LanguagePerturbation(make("MorphoSim/Track-v0", **kw), edits=["make the ball blue"], probability=2.0)


# ------------------------------------------------------------------ tasks reachable
def test_track_camera_override_and_centring_success():
    env = make("MorphoSim/Track-v0", prompt=PROMPT, width=48, height=48)
    env.reset(seed=0)
    u = env.unwrapped
    for _ in range(60):
        cam = u.rig.camera(u.task.task_camera, 48, 48)     # the task camera as the last step rendered it
        uv, _ = cam.project(u.world.target_position())
        d = (uv - [cam.cx, cam.cy]) / [cam.cx, cam.cy]
        *_, trunc, info = env.step(np.array([-2 * d[0], -2 * d[1], 0.0], np.float32).clip(-1, 1))
        if trunc:
            break
    assert info["success"] and info["centred_fraction"] >= 0.7


def test_reach_path_is_reachable_and_a_jacobian_controller_intercepts():
    import mujoco

    env = make("MorphoSim/Reach-v0")
    hits = 0
    for seed in range(3):
        _, info = env.reset(seed=seed)
        u = env.unwrapped
        rig = u.rig
        path = u.world.target_path(25)
        assert np.linalg.norm(path - rig.shoulder, axis=1).max() <= rig.reach
        jac = np.zeros((3, rig.model.nv))
        while True:
            err = u.world.target_position(min(u.world.t + u.dt, u.world.duration)) - rig.end_effector()
            mujoco.mj_comPos(rig.model, rig.data)           # the Jacobian reads com-based dofs
            mujoco.mj_jacSite(rig.model, rig.data, jac, None, rig._site)
            dq = np.linalg.pinv(jac) @ err / u.dt
            _, _, term, trunc, info = env.step((dq / rig.max_joint_rate).clip(-1, 1).astype(np.float32))
            if term or trunc:
                break
        hits += int(info["success"] and term)
    assert hits >= 2


def test_find_success_when_looking_at_the_target():
    env = make("MorphoSim/Find-v0", width=48, height=48)
    _, info = env.reset(seed=0)
    assert info["target_pixels"] == 0 or not info["success"]
    target = info["target_position"]
    back = env.unwrapped.world.generation_camera.position - target
    eye = target + 0.6 * back
    _, info = env.reset(seed=0, options={"camera": {"position": eye, "look_at": target}})
    assert info["found_now"]
    _, _, term, _, info = env.step(np.zeros(6, np.float32))
    assert not info["success"]                            # held 1 step of 2
    _, _, term, _, info = env.step(np.zeros(6, np.float32))
    assert info["success"] and term


# ------------------------------------------------------------------ ecosystem
def test_sync_vector_env_and_episode_statistics():
    venv = gym.vector.SyncVectorEnv([lambda: gym.wrappers.RecordEpisodeStatistics(
        make("MorphoSim/Track-v0", control_hz=2.0, scene_pool=2)) for _ in range(2)])
    obs, infos = venv.reset(seed=[0, 1])
    assert obs["rgb"].shape == (2, 32, 32, 3)
    done = np.zeros(2, bool)
    for _ in range(12):
        obs, r, term, trunc, infos = venv.step(venv.action_space.sample())
        done |= term | trunc
    assert done.all() and "episode" in infos
    venv.close()


@pytest.mark.slow
def test_async_vector_env():
    venv = ms.envs.make_vec("MorphoSim/Track-v0", 2, **FAST, scene_pool=2)
    obs, _ = venv.reset(seed=0)
    assert obs["rgb"].shape == (2, 32, 32, 3)
    for _ in range(3):
        obs, r, term, trunc, infos = venv.step(venv.action_space.sample())
    assert np.all(np.isfinite(r))
    venv.close()


def test_render_mode_and_record_video(tmp_path):
    pytest.importorskip("moviepy")
    env = make("MorphoSim/Track-v0", render_mode="rgb_array", render_width=64, render_height=48, control_hz=2.0)
    videos = tmp_path / "videos"                      # a new folder: the wrapper warns on an existing one
    env = gym.wrappers.RecordVideo(env, str(videos), episode_trigger=lambda e: True, disable_logger=True)
    env.reset(seed=0)
    frame = env.render()
    assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8
    while True:
        *_, term, trunc, _ = env.step(env.action_space.sample())
        if term or trunc:
            break
    env.close()
    assert list(videos.glob("*.mp4"))


def test_rgb_observation_wrapper():
    env = RGBObservation(make("MorphoSim/Track-v0"))
    obs, _ = env.reset(seed=0)
    assert obs.shape == (32, 32, 3) and env.observation_space.contains(obs)


def test_sim_is_a_morphosim_a_simconfig_or_the_default():
    sim = ms.MorphoSim(FAST_SIM)
    shared = make("MorphoSim/Track-v0", sim=sim)
    assert shared.unwrapped._sim is sim
    built = make("MorphoSim/Track-v0").unwrapped._sim
    assert isinstance(built, ms.MorphoSim) and built.config == FAST_SIM
    default = gym.make("MorphoSim/Track-v0").unwrapped._sim.config
    assert default == DEFAULT_SIM_CONFIG
    assert default == ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=0.35)).config
    _, a = shared.reset(seed=0, options={"prompt": PROMPT, "scene_seed": 1})
    assert a["scene_id"] == sim.generate(PROMPT, seed=1).content_hash()
    with pytest.raises(ValueError, match="Expected sim as a MorphoSim, a SimConfig or None, found int"):
        make("MorphoSim/Track-v0", sim=3)


@pytest.mark.parametrize("name", ["detail", "reconstruction"])
def test_world_settings_are_no_env_arguments(name):
    with pytest.raises(TypeError, match=rf"found {name}=.*sim=SimConfig\("):
        gym.make("MorphoSim/Track-v0", **{name: 0.25 if name == "detail" else "oracle"})
    with pytest.raises(TypeError, match=r"found unknown \['colour'\]"):
        TrackEnv(colour="red")


def test_config_is_frozen_and_keyword_calls_work():
    env = TrackEnv(prompt=PROMPT, width=16, height=24, cameras=["eye"], sim=FAST_SIM)
    cfg = env.config
    assert (cfg.width, cfg.height, cfg.cameras, cfg.terminate_on_success) == (16, 24, ("eye",), False)
    assert ReachEnv(sim=FAST_SIM).config.terminate_on_success is True
    assert ReachEnv(sim=FAST_SIM, terminate_on_success=False).config.terminate_on_success is False
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.width = 32
    seed = EnvConfig(scene_seed=np.int64(3)).scene_seed
    assert seed == 3 and type(seed) is int
    for bad, text in ((dict(render_mode="human"), "render_mode"), (dict(scene_pool=0), "scene_pool as an integer >= 1"),
                      (dict(pool_seed=-1), "pool_seed"), (dict(render_threads=True), "render_threads"),
                      (dict(prompt=" "), "prompt"), (dict(scene_seed=1.5), "scene_seed")):
        with pytest.raises(ValueError, match=text):
            EnvConfig(**bad)


def test_one_entry_point_table_for_ids_and_registered_tasks():
    from morphosim_gym.envs import ENTRY_POINTS, register_task

    assert ENV_IDS == tuple(f"MorphoSim/{k.capitalize()}-v0" for k in ENTRY_POINTS)
    for kind, entry in ENTRY_POINTS.items():
        assert gym.spec(f"MorphoSim/{kind.capitalize()}-v0").entry_point == entry
        env_id = register_task(kind, env_id=f"MorphoSim/TestTable{kind}-v0")
        assert gym.spec(env_id).entry_point == entry


def test_make_vec_is_gym_make_vec_with_our_defaults(monkeypatch):
    calls = []
    monkeypatch.setattr(gym, "make_vec", lambda *a, **k: calls.append((a, k)) or "venv")
    assert ms.envs.make_vec("MorphoSim/Track-v0", 3, render_threads=2, width=32) == "venv"
    assert ms.envs.make_vec("MorphoSim/Track-v0", 2, "sync", context="fork") == "venv"
    (a1, k1), (a2, k2) = calls
    assert a1 == ("MorphoSim/Track-v0", 3) and k1["vectorization_mode"] == "async"
    assert k1["vector_kwargs"] == {"context": "spawn"} and k1["render_threads"] == 2 and k1["width"] == 32
    assert k2["vectorization_mode"] == "sync" and k2["vector_kwargs"] == {}
    with pytest.raises(ValueError, match="num_envs"):
        ms.envs.make_vec("MorphoSim/Track-v0", 0)
    with pytest.raises(ValueError, match="vectorization_mode"):
        ms.envs.make_vec("MorphoSim/Track-v0", 2, "threads")


def test_sync_make_vec_with_wrappers():
    venv = ms.envs.make_vec("MorphoSim/Track-v0", 2, "sync", wrappers=[RGBObservation], **FAST, scene_pool=1)
    obs, _ = venv.reset(seed=0)
    assert obs.shape == (2, 32, 32, 3)
    venv.close()


def test_the_task_gets_the_rendered_view_as_an_argument():
    env = make("MorphoSim/Track-v0", prompt=PROMPT)
    u = env.unwrapped
    seen = []
    measure, evaluate = u.task.measure, u.task.evaluate
    u.task.measure = lambda world, rig, view: seen.append(view) or measure(world, rig, view)
    u.task.evaluate = lambda world, rig, view, a: seen.append(view) or evaluate(world, rig, view, a)
    env.reset(seed=0)
    env.step(np.zeros(3, np.float32))
    assert seen[0].t == 0.0 and seen[1].t == pytest.approx(0.1) and not hasattr(u, "_last_view")
    assert all(v is seen[1] for v in seen[1:])             # evaluate measures the same view
    assert seen[1].instance.shape == (32, 32) and seen[1].camera.width == 32
    assert Task.reset_metrics(u.task) == {}


def test_wrapper_failed_names_the_edit_that_raised():
    env = LanguagePerturbation(make("MorphoSim/Track-v0", prompt=PROMPT), schedule={2: "reverse the ground"})
    env.reset(seed=0)
    env.step(np.zeros(3, np.float32))
    assert env.failed is None
    with pytest.raises(ms.EditError, match="ground"):
        env.step(np.zeros(3, np.float32))
    assert env.failed == (2, "reverse the ground") and env.unwrapped._step_count == 1


def test_constructor_errors():
    with pytest.raises(ValueError, match="control_hz"):
        make("MorphoSim/Track-v0", control_hz=0)
    with pytest.raises(ValueError, match="width"):
        make("MorphoSim/Track-v0", width=3)
    with pytest.raises(ValueError, match="on_edit_error"):
        make("MorphoSim/Track-v0", on_edit_error="ignore")
    with pytest.raises(ValueError, match="kind 'track'"):
        make("MorphoSim/Track-v0", task="reach")
    with pytest.raises(ValueError, match="unknown"):
        make("MorphoSim/Track-v0", task_params={"nope": 1})
    with pytest.raises(RuntimeError, match="reset"):
        make("MorphoSim/Track-v0").unwrapped.perturb("make the ball blue")
