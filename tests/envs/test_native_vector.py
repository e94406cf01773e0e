"""The native vector env (`MorphoSimVectorEnv`): N worlds in one process, one batched render per
step, env i identical to a single env seeded s + i (autoreset NEXT_STEP)."""

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

from morphosim_gym.envs import ENV_IDS, LanguagePerturbation, MorphoSimVectorEnv, make_vec
from morphosim_gym.envs.vector_infos import InfoBatch, batch_infos
from tests.envs.conftest import FAST, PROMPT, make

N = 2


def _same(a, b) -> bool:
    if isinstance(b, dict):
        return isinstance(a, dict) and all(_same(a[k], v) for k, v in b.items())
    if isinstance(b, np.ndarray) or isinstance(a, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)
    if isinstance(a, np.generic):            # vector infos store scalars in numpy arrays
        a = a.item()
    return type(a) is type(b) and a == b


def _entry(vinfo: dict, i: int):
    """Env i's info out of a vector info dict (values where its `_key` mask is set)."""
    out = {}
    for key, value in vinfo.items():
        if isinstance(key, str) and key.startswith("_"):
            continue
        if isinstance(value, dict):
            out[key] = _entry(value, i)
        elif vinfo[f"_{key}"][i]:
            out[key] = value[i]
    return out


def _check_info(vinfo: dict, i: int, single: dict) -> None:
    got = _entry(vinfo, i)
    assert set(got) == set(single)
    for key, value in single.items():
        assert _same(got[key], value), key


def _check_obs(vobs: dict, i: int, single: dict) -> None:
    assert set(vobs) == set(single)
    for key, value in single.items():
        assert vobs[key][i].dtype == value.dtype and np.array_equal(vobs[key][i], value), key


def _rollout_compare(venv, singles, seed: int, max_steps: int = 90, extra_steps: int = 3) -> int:
    vobs, vinfo = venv.reset(seed=seed)
    for i, env in enumerate(singles):
        obs, info = env.reset(seed=seed + i)
        _check_obs(vobs, i, obs)
        _check_info(vinfo, i, info)
    rng = np.random.default_rng(seed)
    done_prev = np.zeros(N, bool)
    resets, after = 0, None
    for step in range(max_steps):
        actions = rng.uniform(-1, 1, venv.action_space.shape).astype(np.float32)
        vobs, vrew, vterm, vtrunc, vinfo = venv.step(actions)
        for i, env in enumerate(singles):
            if done_prev[i]:
                obs, info = env.reset()
                rew, term, trunc = 0.0, False, False
                resets += 1
            else:
                obs, rew, term, trunc, info = env.step(actions[i])
            _check_obs(vobs, i, obs)
            _check_info(vinfo, i, info)
            assert vrew[i] == rew and vterm[i] == term and vtrunc[i] == trunc, (step, i)
        done_prev = vterm | vtrunc
        if resets >= N and after is None:
            after = step
        if after is not None and step >= after + extra_steps:
            break
    return resets


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_each_env_matches_a_single_env_over_episodes_with_autoreset(env_id):
    kw = dict(FAST, scene_pool=2)
    venv = gym.make_vec(env_id, N, vectorization_mode="vector_entry_point", **kw)
    assert isinstance(venv, MorphoSimVectorEnv)
    assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
    singles = [make(env_id, **kw) for _ in range(N)]
    assert _rollout_compare(venv, singles, seed=7) >= N       # every env went through an autoreset
    venv.close()


def test_make_vec_vector_mode_and_errors():
    venv = make_vec("MorphoSim/Track-v0", 2, vectorization_mode="vector", **FAST)
    assert isinstance(venv, MorphoSimVectorEnv) and venv.num_envs == 2
    obs, _ = venv.reset(seed=0)
    assert obs["rgb"].shape == (2, 32, 32, 3)
    with pytest.raises(ValueError, match="wrappers"):
        make_vec("MorphoSim/Track-v0", 2, vectorization_mode="vector", wrappers=[lambda e: e], **FAST)
    with pytest.raises(ValueError, match="'vector', 'async' or 'sync'"):
        make_vec("MorphoSim/Track-v0", 2, vectorization_mode="gpu")
    with pytest.raises(ValueError, match="num_envs"):
        MorphoSimVectorEnv(0)
    with pytest.raises(ValueError, match="kind"):
        MorphoSimVectorEnv(1, kind="swim")
    with pytest.raises(ValueError, match="actions for 2 envs"):
        venv.step(np.zeros((3, 3), np.float32))
    # a bad action of one env is refused before any env moves
    steps = [env._step_count for env in venv.envs]
    times = [env.world.t for env in venv.envs]
    with pytest.raises(ValueError, match=r"env 1: .*NaN.*no env was stepped"):
        venv.step(np.array([[0.5, 0, 0], [0, np.nan, 0]], np.float32))
    assert [env._step_count for env in venv.envs] == steps and [env.world.t for env in venv.envs] == times
    venv.step(np.zeros((2, 3), np.float32))                   # and the batch steps on
    assert [env._step_count for env in venv.envs] == [k + 1 for k in steps]
    with pytest.raises(ValueError, match="env index"):
        venv.perturb(5, "make the ball blue")
    with pytest.raises(ValueError, match="seeds"):
        venv.reset(seed=[1, 2, 3])
    venv.close()


def test_per_env_seeds_options_edits_and_attributes():
    kw = dict(FAST, prompt=PROMPT)
    venv = make_vec("MorphoSim/Track-v0", 2, vectorization_mode="vector", **kw)
    obs, info = venv.reset(seed=[3, 4], options=[{"edits": ["make the ball blue"]}, None])
    assert info["edits"][0] == ("make the ball blue",) and info["edits"][1] == ()
    ref = make("MorphoSim/Track-v0", **kw)
    ref_obs, _ = ref.reset(seed=3, options={"edits": ["make the ball blue"]})
    assert np.array_equal(obs["rgb"][0], ref_obs["rgb"])
    assert venv.perturb(1, "make the ball green") is True
    a = np.zeros((2, 3), np.float32)
    _, _, _, _, info = venv.step(a)
    assert info["edits"][1] == ("make the ball green",) and info["edits"][0] == ("make the ball blue",)
    assert venv.call("perturb", "make the ball red") == (True, True)
    assert [s.history[-1] for s in venv.get_attr("scene")] == ["make the ball red"] * 2
    venv.set_attr("marker", [1, 2])
    assert venv.get_attr("marker") == (1, 2)
    _, info = venv.reset(options={"reset_mask": np.array([False, True])})
    assert list(info["_step"]) == [False, True]
    venv.close()


def test_language_perturbation_per_env_matches_the_wrapped_single_env():
    kw = dict(FAST, prompt=PROMPT)
    schedule = {2: "make the ball blue"}
    venv = make_vec("MorphoSim/Track-v0", N, vectorization_mode="vector",
                    perturbations=[{"schedule": schedule}, None], **kw)
    singles = [LanguagePerturbation(make("MorphoSim/Track-v0", **kw), schedule=schedule),
               make("MorphoSim/Track-v0", **kw)]
    vobs, vinfo = venv.reset(seed=1)
    for i, env in enumerate(singles):
        obs, info = env.reset(seed=1 + i)
        _check_obs(vobs, i, obs)
        _check_info(vinfo, i, info)
    for _ in range(4):
        a = np.full((N, 3), 0.3, np.float32)
        vobs, vrew, _, _, vinfo = venv.step(a)
        for i, env in enumerate(singles):
            obs, rew, _, _, info = env.step(a[i])
            _check_obs(vobs, i, obs)
            _check_info(vinfo, i, info)
            assert vrew[i] == rew
    assert vinfo["perturbations"][0] == ((2, "make the ball blue", True),)
    assert not vinfo["_perturbations"][1]
    venv.close()


def test_registered_task_ids_get_the_native_vector_env():
    from morphosim_gym.envs import register_task

    env_id = register_task("find", env_id="MorphoSim/FindNativeVectorTest-v0")
    venv = gym.make_vec(env_id, 2, vectorization_mode="vector_entry_point", **FAST)
    assert isinstance(venv, MorphoSimVectorEnv)
    obs, info = venv.reset(seed=0)
    single = make(env_id)
    ref, ref_info = single.reset(seed=1)
    assert np.array_equal(obs["rgb"][1], ref["rgb"]) and info["target"][1] == ref_info["target"]
    venv.close()


@pytest.mark.parametrize("scheduler,pipeline,threads", [("numba", 1, None), ("numba", 3, None), ("views", 1, 2),
                                                      ("views", 3, 2), ("views", 2, 1)])
def test_pipelined_chunks_match_single_envs(scheduler, pipeline, threads):
    # pipeline=3 over 2 envs: one env per chunk (chunk c renders while the other is prepared or
    # finished); "numba": a worker thread renders a chunk when pipeline > 1; "views": helper
    # threads (render_threads - 1 of them) claim whole views beside this thread
    kw = dict(FAST, scene_pool=2)
    venv = make_vec("MorphoSim/Track-v0", N, vectorization_mode="vector", pipeline=pipeline, scheduler=scheduler,
                    render_threads=threads, **kw)
    singles = [make("MorphoSim/Track-v0", **kw) for _ in range(N)]
    assert _rollout_compare(venv, singles, seed=11) >= N
    assert (venv._worker is not None) == (scheduler == "numba" and pipeline > 1)
    assert (venv._helpers is not None) == (scheduler == "views")
    if scheduler == "views":
        assert venv._helpers.helpers == threads - 1
    venv.close()
    assert venv._worker is None and venv._helpers is None


def test_scheduler_and_render_threads_are_checked():
    for bad in ("tiles", None, 1):
        with pytest.raises(ValueError, match="scheduler"):
            MorphoSimVectorEnv(1, scheduler=bad)
    for bad in (0, -2, 1.5, True):
        with pytest.raises(ValueError, match="render_threads"):
            MorphoSimVectorEnv(1, render_threads=bad)


def test_pipeline_argument_is_checked():
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ValueError, match="pipeline"):
            MorphoSimVectorEnv(1, pipeline=bad)


def test_a_pipelined_vector_env_deep_copies_and_both_copies_step_alike():
    import copy

    venv = make_vec("MorphoSim/Track-v0", N, vectorization_mode="vector", pipeline=2, **FAST)
    venv.reset(seed=3)
    a = np.full((N, 3), 0.2, np.float32)
    venv.step(a)
    twin = copy.deepcopy(venv)
    assert twin._worker is None and twin._helpers is None
    obs, rew, _, _, _ = venv.step(a)
    obs2, rew2, _, _, _ = twin.step(a)
    assert np.array_equal(obs["rgb"], obs2["rgb"]) and np.array_equal(rew, rew2)
    venv.close()
    twin.close()


def test_envs_with_one_sim_share_one_scene_source_and_build_the_pool_once(monkeypatch):
    from morphosim_gym.envs import scenes

    built = []
    real = scenes.build_scenes
    monkeypatch.setattr(scenes, "build_scenes", lambda sim, keys, *a: built.extend(keys) or real(sim, keys, *a))
    other_sim = dataclasses.replace(FAST["sim"])                      # equal, but another object
    venv = make_vec("MorphoSim/Track-v0", 3, vectorization_mode="vector", scene_pool=2,
                    env_kwargs=[None, None, {"sim": other_sim}], **FAST)
    sources = [env._source for env in venv.envs]
    assert sources[0] is sources[1] and sources[2] is not sources[0]   # a different sim: its own source
    keys = {(r.prompt, seed) for r, seed in venv.envs[0]._scenes.pool}
    assert len(built) == 2 * len(keys)                                 # env 0's pool (shared by env 1), env 2's
    venv.reset(seed=0)
    pooled = {id(s) for s in sources[0]._cache.values()}
    assert {id(env.world.scene) for env in venv.envs[:2]} <= pooled    # the pool's own scene objects
    venv.close()


def test_a_shared_scene_source_grows_to_hold_every_pool_built_into_it(monkeypatch):
    from morphosim_gym.envs import scenes

    monkeypatch.setattr(scenes, "build_scenes", lambda sim, keys, *a: [object() for _ in keys])
    monkeypatch.setattr(scenes, "build_one", lambda sim, prompt, seed: object())
    source = scenes.SceneSource(sim=None, cache_size=1)
    source.build_many([("a", 0), ("b", 1)])
    source.build_many([("c", 2)])                          # another env's pool in the same source
    assert source.cache_size == 3
    source.get("d", 3)                                     # a miss evicts only the least recent
    assert list(source._cache) == [("b", 1), ("c", 2), ("d", 3)]


def _deep_equal(a, b) -> bool:
    """Equal structure, key order, types, dtypes and values (NaN equal to NaN)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return list(a) == list(b) and all(_deep_equal(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        if a.dtype != b.dtype or a.shape != b.shape:
            return False
        if a.dtype == object:
            return all(_deep_equal(x, y) for x, y in zip(a.ravel(), b.ravel()))
        return bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    return bool(a == b)


def test_the_vector_info_batching_equals_gymnasiums():
    fast = object.__new__(MorphoSimVectorEnv)            # only num_envs and the method are used
    fast.num_envs = 3
    infos = [{"success": True, "t": 0.1, "step": 3, "target": "ball", "edits": (), "reward_ctrl": np.float32(-0.01),
              "cameras": {"eye": {"K": np.eye(3), "width": 84}}, "id_to_name": {0: "ground", 1: "ball"}},
             {"final_obs": {"rgb": np.zeros(2)}, "t": 1, "target_position": np.arange(3.0), "edits": ("x",),
              "cameras": {"eye": {"K": 2 * np.eye(3), "width": 84}}, "id_to_name": {1: "cube"}},
             {"success": False, "step": np.int64(9), "target_position": None, "target": "cube", "final_obs": 7}]
    plain = object.__new__(type("Plain", (gym.vector.VectorEnv,), {}))   # gymnasium's own, nested calls too
    plain.num_envs = 3
    ours, theirs = {}, {}
    for i, info in enumerate(infos):
        ours = fast._add_info(ours, info, i)
        theirs = plain._add_info(theirs, info, i)
    assert _deep_equal(ours, theirs)
    # the step's key-by-key batching (`batch_infos`) and the env-by-env `InfoBatch` give the same,
    # in any env order; with values of mixed types in a key (int and float "t", np.int64 and int
    # "step") and arrays
    order = [2, 0, 1]

    def both(given: list, added: list = None) -> list:
        batch = InfoBatch(3)
        for i in added or order:
            batch.add(i, given[i])
        return [batch_infos([(i, given[i]) for i in order], 3), batch.result(order=order)]

    theirs = {}
    for i in order:
        theirs = plain._add_info(theirs, infos[i], i)
    assert all(_deep_equal(ours, theirs) for ours in both(infos))
    same_type = [{"t": 0.5 * i, "pos": np.arange(3.0) + i, "ok": bool(i % 2), "k": np.float32(i), "s": f"x{i}",
                  "cameras": {"eye": {"K": np.eye(3) * i, "width": 84}}, "final_obs": [i] * i,
                  "id_to_name": {0: "ground", i: "ball"}} for i in range(3)]
    theirs = {}
    for i in order:
        theirs = plain._add_info(theirs, same_type[i], i)
    for added in ([2, 0, 1], [0, 1, 2], [1, 2, 0]):             # filled as added, batched in `order`'s
        assert all(_deep_equal(ours, theirs) for ours in both(same_type, added))
    # a value of another type (an int "t", a float32 "pos") in the env batched first but added last:
    # the same (its type makes the array, as in Gymnasium), batched at the end
    for key, value in (("t", 3), ("pos", np.zeros(3, np.float32)), ("k", 1.0),
                       ("cameras", {"eye": {"K": np.eye(3), "width": 8.0}})):
        odd = [dict(info) for info in same_type]
        odd[2][key] = value
        theirs = {}
        for i in order:
            theirs = plain._add_info(theirs, odd[i], i)
        assert all(_deep_equal(ours, theirs) for ours in both(odd, [0, 1, 2]))
    mixed = [{"x": {"a": 1}}, {"x": 2}]                       # a dict, then not: env by env
    sequential = fast._add_info(fast._add_info({}, mixed[0], 0), mixed[1], 1)
    assert _deep_equal(batch_infos(list(enumerate(mixed)), 3), sequential)
    batch = InfoBatch(3)
    batch.add(0, mixed[0])
    batch.add(1, mixed[1])
    assert _deep_equal(batch.result(), sequential)


def test_autoresets_join_the_batched_render(monkeypatch):
    from morphosim_gym.envs import core

    calls = []
    real = core.render_scene
    monkeypatch.setattr(core, "render_scene", lambda *a, **k: calls.append(1) or real(*a, **k))
    venv = make_vec("MorphoSim/Track-v0", N, vectorization_mode="vector", scene_pool=1, **FAST)
    singles = [make("MorphoSim/Track-v0", scene_pool=1) for _ in range(N)]
    venv.reset(seed=3)
    for i, env in enumerate(singles):
        env.reset(seed=3 + i)
    a = np.zeros((N, 3), np.float32)
    done = np.zeros(N, bool)
    resets = 0
    while resets < N:                                        # Track truncates at the clip's end: all reset
        before = len(calls)
        vobs, _, vterm, vtrunc, vinfo = venv.step(a)
        assert len(calls) == before                          # no env rendered on its own, resets included
        for i, env in enumerate(singles):
            if done[i]:
                obs, info = env.reset()
                resets += 1
            else:
                obs, *_, info = env.step(a[i])
            _check_obs(vobs, i, obs)
            _check_info(vinfo, i, info)
        done = vterm | vtrunc
    venv.close()
