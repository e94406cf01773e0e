"""Vector envs in every Gymnasium mode after the parent process has stepped an env, and envs
stepped from several Python threads (numba's threading layer: `morphosim_gym.parallel`)."""

import subprocess
import sys
import textwrap
from pathlib import Path

import gymnasium as gym
import numba
import numpy as np
import pytest

import morphosim_gym as ms

from .conftest import FAST, PROMPT, make

TRACK = "MorphoSim/Track-v0"
ROOT = Path(__file__).resolve().parents[2]
KW = dict(FAST, prompt=PROMPT, scene_seed=0)


@pytest.fixture(scope="module")
def parent_obs():
    """The parent steps an env first (numba's threads are running here), and keeps its reset view."""
    env = make(TRACK, **KW)
    obs, _ = env.reset(seed=0)
    env.step(env.action_space.sample())
    yield obs
    env.close()


def check(venv, parent_obs):
    """The vector env resets and steps; its first env sees what the parent's env saw."""
    try:
        obs, _ = venv.reset(seed=0)
        assert obs["rgb"].shape == (2, 32, 32, 3)
        assert np.array_equal(obs["rgb"][0], parent_obs["rgb"])
        for _ in range(2):
            obs, r, term, trunc, _ = venv.step(venv.action_space.sample())
        assert np.all(np.isfinite(r))
    finally:
        venv.close()


def test_numba_uses_a_fork_safe_threading_layer(parent_obs):
    assert numba.threading_layer() in ("tbb", "workqueue")


def test_the_tbb_wheel_is_used_when_installed(parent_obs):
    """pip's `tbb` puts libtbb.so.12 in <venv>/lib, off the loader's path; `parallel` preloads it,
    so numba runs TBB (thread- and fork-safe, as fast as OpenMP) rather than falling back."""
    import os
    import sys

    if not any(os.path.exists(os.path.join(p, "lib", "libtbb.so.12")) for p in (sys.prefix, sys.base_prefix)):
        pytest.skip("the tbb wheel is not installed (numba falls back to workqueue)")
    assert numba.threading_layer() == "tbb"


def test_sync_vector_env(parent_obs):
    check(gym.make_vec(TRACK, 2, vectorization_mode="sync", **KW), parent_obs)


def test_async_vector_env_with_the_default_start_method(parent_obs):
    """gym's default (fork on Linux): numba's OpenMP layer used to terminate every forked child."""
    check(gym.make_vec(TRACK, 2, vectorization_mode="async", **KW), parent_obs)


@pytest.mark.parametrize("context", ["fork", "forkserver"])
def test_async_vector_env_forks(parent_obs, context):
    check(gym.make_vec(TRACK, 2, vectorization_mode="async", vector_kwargs={"context": context}, **KW), parent_obs)


def test_async_vector_env_spawns(parent_obs):
    check(gym.make_vec(TRACK, 2, vectorization_mode="async", vector_kwargs={"context": "spawn"}, **KW), parent_obs)


def test_our_make_vec(parent_obs):
    """(spawns by default; ~10 s like the spawn test above)"""
    check(ms.envs.make_vec(TRACK, 2, **KW), parent_obs)


def run_script(code: str, timeout: float = 240) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT)


def test_envs_step_from_several_threads():
    """workqueue terminates the process when two threads launch kernels at once; envs, `render`
    and posing take turns (a viewer steps its env while its frame thread renders)."""
    out = run_script(f"""
        import threading
        import gymnasium as gym, numpy as np, morphosim_gym as ms
        from morphosim_gym.scene import Camera
        from morphosim_gym.scene.motion import skin
        from tests.envs.conftest import FAST, PROMPT
        envs = [gym.make("{TRACK}", prompt=PROMPT, render_threads=2, **FAST) for _ in range(2)]
        for e in envs:
            e.reset(seed=0)
        scene = envs[0].unwrapped.scene
        n = 20000                                      # enough Gaussians to skin in parallel
        means, quats = np.random.rand(n, 3).astype(np.float32), np.tile(np.float32([1, 0, 0, 0]), (n, 1))
        nodes, weights = np.zeros((n, 1), np.int32), np.ones((n, 1), np.float32)
        cam = Camera.look_at((0, -4, 2), (0, 0, 0.5), 32, 32)
        def steps(e):
            for _ in range(25):
                e.step(e.action_space.sample())
        def renders():
            for _ in range(25):
                ms.render(scene, cam, 0.0)
        def poses():
            for i in range(25):
                skin(means, quats, nodes, weights, np.tile([1.0, 0, 0, 0], (2, 1)), np.full((2, 3), 0.1 * i))
        threads = [threading.Thread(target=steps, args=(e,)) for e in envs]
        threads += [threading.Thread(target=renders), threading.Thread(target=poses)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        print("done")
    """)
    assert out.returncode == 0 and out.stdout.split()[-1:] == ["done"], out.stderr[-2000:]


def test_a_forked_child_runs_torch_after_the_parent_did():
    """GNU OpenMP in torch hangs a forked child's parallel ops once the parent ran one; children
    of a process that imported morphosim_gym run torch on one thread instead."""
    pytest.importorskip("torch")
    out = run_script("""
        import multiprocessing as mp
        import morphosim_gym, torch
        torch.set_num_threads(2)
        x = torch.randn(2_000_000)
        (x * 2).sum()
        def child(q):
            y = torch.randn(2_000_000)
            q.put(float((y * 0).sum()))
        ctx = mp.get_context("fork")
        q = ctx.Queue()
        p = ctx.Process(target=child, args=(q,))
        p.start()
        p.join(60)
        alive = p.is_alive()
        if alive:
            p.kill()
        print("hung" if alive else q.get(timeout=5))
    """, timeout=120)
    assert out.returncode == 0 and out.stdout.split()[-1:] == ["0.0"], (out.stdout, out.stderr[-2000:])


def test_a_threading_layer_the_user_chose_is_kept():
    out = run_script("""
        import os
        os.environ["NUMBA_THREADING_LAYER"] = "omp"
        import morphosim_gym, numba
        print(os.environ["NUMBA_THREADING_LAYER"], numba.config.THREADING_LAYER)
    """)
    assert out.returncode == 0 and out.stdout.split() == ["omp", "omp"], out.stderr[-2000:]
