"""Cloning episodes: envs pickle and deep-copy mid-episode, and `snapshot()` / `restore()` branch
an episode; every copy and branch continues byte-exactly like a fresh run of the same actions."""

import copy
import pickle

import numpy as np
import pytest

from morphosim_gym.edit.select import Selector
from morphosim_gym.rig import RIGS

from .conftest import PROMPT, make

EDIT = "make the ball blue"
K = 2                 # the step the episodes branch at
STEPS = 3             # steps per branch


def actions(env, n, seed=0):
    """`n` fixed actions in the env's action space."""
    rng = np.random.default_rng(seed)
    return [rng.uniform(-1, 1, env.action_space.shape).astype(np.float32) for _ in range(n)]


def run(env, acts, edit=None):
    """Step `acts` (after `perturb(edit)`, if given) and record every output, copied."""
    if edit is not None:
        assert env.unwrapped.perturb(edit)
    return [copy.deepcopy(env.step(a)) for a in acts] + [env.unwrapped.np_random.integers(2 ** 62, size=4)]


def assert_same(a, b, where="out"):
    """Exactly equal: arrays by dtype, shape and bytes; mappings and sequences item by item."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        assert isinstance(a, np.ndarray) and isinstance(b, np.ndarray), where
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), where
    elif isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), where
        for k in a:
            assert_same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, (list, tuple)):
        assert type(a) is type(b) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    else:
        assert type(a) is type(b) and a == b, f"{where}: {a!r} != {b!r}"


def started(env_id, seed=3, **kwargs):
    """An env reset with `seed` and stepped K times, and the actions that follow."""
    env = make(env_id, prompt=PROMPT, **kwargs)
    env.reset(seed=seed)
    acts = actions(env, K + STEPS, seed)
    for a in acts[:K]:
        env.step(a)
    return env, acts[K:]


# ------------------------------------------------------------------ pickle and deepcopy
@pytest.mark.parametrize("clone", [lambda e: pickle.loads(pickle.dumps(e)), copy.deepcopy], ids=["pickle", "deepcopy"])
@pytest.mark.parametrize("wrapped", [True, False], ids=["gym.make", "raw"])
def test_env_clones_mid_episode_after_an_edit(clone, wrapped):
    env, acts = started("MorphoSim/Track-v0")
    assert env.unwrapped.perturb(EDIT)
    target = env if wrapped else env.unwrapped
    twin = clone(target)
    assert twin is not target and twin.unwrapped.scene is not env.unwrapped.scene
    assert twin.unwrapped.world.t == env.unwrapped.world.t
    assert_same(run(twin, acts), run(target, acts))


def test_every_env_pickles_mid_episode(env_id):
    env, acts = started(env_id)
    twin = pickle.loads(pickle.dumps(env))
    assert_same(run(twin, acts, EDIT), run(env, acts, EDIT))


def test_rigs_and_the_selector_pickle():
    for name, cls in RIGS.items():
        rig = cls()
        twin = pickle.loads(pickle.dumps(rig))
        assert twin.camera_names == rig.camera_names, name
        assert np.array_equal(twin.camera(twin.camera_name, 16, 16).world_to_camera,
                              rig.camera(rig.camera_name, 16, 16).world_to_camera), name
    sel = pickle.loads(pickle.dumps(Selector(times=2)))
    assert sel.times == 2
    with sel._lock:                                   # a fresh lock, and an empty cache
        assert sel._cache == {}


# ------------------------------------------------------------------ snapshot / restore
def test_snapshot_branches_match_fresh_runs(env_id):
    """Snapshot at step K, run branch A (an edit) and B (none), restore and run A again: each
    branch equals a fresh env that did the same from step 0 (observations, rewards, infos, RNG)."""
    env, acts = started(env_id)
    snap = env.unwrapped.snapshot()
    branch_a = run(env, acts, EDIT)
    env.unwrapped.restore(snap)
    branch_b = run(env, acts)
    env.unwrapped.restore(snap)
    assert_same(run(env, acts, EDIT), branch_a)
    fresh_a, acts_a = started(env_id)
    assert_same(run(fresh_a, acts_a, EDIT), branch_a)
    fresh_b, acts_b = started(env_id)
    assert_same(run(fresh_b, acts_b), branch_b)
    assert branch_a[0][4]["edits"] == (EDIT,) and branch_b[0][4]["edits"] == ()        # the branches differ
    assert branch_a[0][4]["scene_id"] != branch_b[0][4]["scene_id"]


def test_snapshot_shares_the_scene_and_pickles():
    env, acts = started("MorphoSim/Track-v0")
    from morphosim_gym.envs.snapshot import EnvSnapshot

    u = env.unwrapped
    snap = u.snapshot()
    assert isinstance(snap, EnvSnapshot) and snap.step == K and snap.t == u.world.t
    assert snap.world.scene is u.scene                           # scenes are values: shared, never copied
    expected = run(env, acts, EDIT)
    u.restore(pickle.loads(pickle.dumps(snap)))
    assert_same(run(env, acts, EDIT), expected)
    other = copy.deepcopy(env)                                   # a snapshot restores into a copy too
    other.unwrapped.restore(snap)
    assert_same(run(other, acts, EDIT), expected)


def test_restore_after_the_episode_ended_and_reset():
    env, acts = started("MorphoSim/Track-v0")
    snap = env.unwrapped.snapshot()
    expected = run(env, acts)
    env.reset(seed=99)
    env.unwrapped.restore(snap)
    assert_same(run(env, acts), expected)


def test_snapshot_and_restore_errors():
    env = make("MorphoSim/Track-v0", prompt=PROMPT)
    with pytest.raises(RuntimeError, match="reset"):
        env.unwrapped.snapshot()
    env.reset(seed=0)
    with pytest.raises(TypeError, match="EnvSnapshot"):
        env.unwrapped.restore({"step": 1})
    reach = make("MorphoSim/Reach-v0", prompt=PROMPT)
    reach.reset(seed=0)
    with pytest.raises(ValueError, match="TrackEnv"):
        env.unwrapped.restore(reach.unwrapped.snapshot())
