"""Scene pools built in parallel (`envs.pool.build_scenes`): the same scenes as a serial build, bounded
waits, clear errors for dead workers, timeouts and bad scenes, and the on-disk cache."""

import os
import time
import warnings

import gymnasium as gym
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.envs.pool import ScenePoolError, build_scenes, start_method
from morphosim_gym.scene.diskcache import DamagedCacheEntryWarning

PROMPTS = [("a red ball moves from left to right", 1), ("a blue cube moves from right to left", 2),
           ("a yellow car bounces from left to right", 3)]


def _oracle(**kw):
    return ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=0.2), **kw)


class _Dies:
    """A sim whose worker process dies while building."""

    def generate(self, prompt, seed=0):
        os._exit(3)


class _Hangs:
    """A sim that takes far longer than the pool allows."""

    def generate(self, prompt, seed=0):
        time.sleep(120)


class _Refuses:
    """A sim that rejects one prompt."""

    def generate(self, prompt, seed=0):
        if "cube" in prompt:
            raise ms.CommandError(f"Expected a prompt this test accepts, found {prompt!r}")
        return _oracle().generate(prompt, seed=seed)


def test_parallel_build_gives_the_serial_scenes_in_order():
    sim = _oracle()
    serial = build_scenes(sim, PROMPTS, workers=1, progress=False)
    parallel = build_scenes(sim, PROMPTS, workers=2, progress=False)
    assert [s.content_hash() for s in serial] == [s.content_hash() for s in parallel]
    assert [s.provenance.prompt for s in parallel] == [p for p, _ in PROMPTS]


def test_pool_workers_do_not_change_the_env_pool():
    a = gym.make("MorphoSim/Track-v0", scene_pool=3, pool_seed=2, width=32, height=32)
    b = gym.make("MorphoSim/Track-v0", scene_pool=3, pool_seed=2, width=32, height=32, pool_workers=2)
    ids_a = [a.reset(seed=s)[1]["scene_id"] for s in range(6)]
    ids_b = [b.reset(seed=s)[1]["scene_id"] for s in range(6)]
    assert ids_a == ids_b


def test_fork_where_numba_allows_it():
    assert start_method() in ("fork", "spawn")
    from morphosim_gym.parallel import threading_layer

    if threading_layer() in ("tbb", "workqueue") and os.name == "posix":
        assert start_method() == "fork"


def test_a_worker_that_dies_is_a_clear_error_not_a_hang():
    with pytest.raises(ScenePoolError, match="worker process died"):
        build_scenes(_Dies(), PROMPTS[:2], workers=2, progress=False, timeout_s=60)


def test_a_scene_slower_than_the_timeout_stops_the_build():
    start = time.monotonic()
    with pytest.raises(ScenePoolError, match="within 1 s each"):
        build_scenes(_Hangs(), PROMPTS[:2], workers=2, progress=False, timeout_s=1.0)
    assert time.monotonic() - start < 60           # bounded (the workers were killed, not waited for)


def test_a_scene_error_in_a_worker_is_raised_as_it_was():
    with pytest.raises(ms.CommandError, match="this test accepts"):
        build_scenes(_Refuses(), PROMPTS, workers=2, progress=False, timeout_s=300)


def test_bad_pool_arguments_fail_at_make():
    with pytest.raises(ValueError, match="pool_backend"):
        gym.make("MorphoSim/Track-v0", scene_pool=2, pool_backend="threads")
    with pytest.raises(ValueError, match="pool_workers"):
        gym.make("MorphoSim/Track-v0", scene_pool=2, pool_workers=0)
    with pytest.raises(ValueError, match="pool_timeout_s"):
        gym.make("MorphoSim/Track-v0", scene_pool=2, pool_timeout_s=-1)
    with pytest.raises(ValueError, match="timeout_s"):
        build_scenes(_oracle(), PROMPTS, timeout_s=0)


def test_a_pooled_scene_without_the_target_fails_at_make():
    with pytest.raises(ValueError, match="Scene pool.*no target.*'dog'"):
        gym.make("MorphoSim/Track-v0", prompt=PROMPTS[0][0], target="dog", scene_pool=2, width=32, height=32)


def test_a_cached_file_that_is_not_a_scene_is_rebuilt(tmp_path):
    sim = _oracle(cache=True, cache_dir=str(tmp_path))
    first = build_scenes(sim, PROMPTS[:2], workers=2, progress=False)
    files = sorted((tmp_path / "scene").glob("*.msim"))
    assert len(files) == 2
    files[0].write_bytes(b"this is not a scene file")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        again = build_scenes(sim, PROMPTS[:2], workers=1, progress=False)
    assert any(issubclass(w.category, DamagedCacheEntryWarning) for w in caught)
    assert [s.content_hash() for s in again] == [s.content_hash() for s in first]


def test_serial_build_restores_the_thread_counts():
    import numba

    before = numba.get_num_threads()
    build_scenes(_oracle(), PROMPTS[:1], workers=1, progress=False)
    assert numba.get_num_threads() == before


@pytest.mark.slow
def test_ray_backend_gives_the_same_scenes():
    pytest.importorskip("ray")
    sim = _oracle()
    serial = build_scenes(sim, PROMPTS[:2], workers=1, progress=False)
    remote = build_scenes(sim, PROMPTS[:2], workers=2, backend="ray", progress=False, timeout_s=600)
    assert [s.content_hash() for s in serial] == [s.content_hash() for s in remote]
    assert np.array_equal(serial[0].gaussians.means, remote[0].gaussians.means)


def test_builds_run_numba_torch_and_blas_on_one_thread():
    threadpoolctl = pytest.importorskip("threadpoolctl")
    import numba
    import torch

    from morphosim_gym.envs.pool import single_threaded

    def blas_threads():
        return [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]

    before = (numba.get_num_threads(), torch.get_num_threads(), blas_threads())
    with single_threaded():
        assert numba.get_num_threads() == 1 and torch.get_num_threads() == 1
        assert blas_threads() and all(n == 1 for n in blas_threads())
    assert (numba.get_num_threads(), torch.get_num_threads(), blas_threads()) == before


class _UsesTqdm:
    """A sim that draws a (hidden) tqdm bar while it builds, as reconstruction does."""

    def generate(self, prompt, seed=0):
        from tqdm import tqdm

        for _ in tqdm(range(2), disable=True):
            pass
        return _oracle().generate(prompt, seed=seed)


def test_workers_do_not_share_the_parents_tqdm_lock():
    # tqdm's default lock is a multiprocessing lock shared across fork: held here (or by a child
    # killed while holding it) it would stop every worker's bar
    from tqdm import tqdm

    if start_method() != "fork":
        pytest.skip("workers are spawned here: they share no lock with this process")
    with tqdm.get_lock():
        scenes = build_scenes(_UsesTqdm(), PROMPTS[:2], workers=2, progress=False, timeout_s=30)
    assert [s.provenance.prompt for s in scenes] == [p for p, _ in PROMPTS[:2]]


_STUCK_FORK = """
import os, time, warnings
import morphosim_gym as ms
from morphosim_gym.envs.pool import PoolStartWarning, build_scenes, start_method

if __name__ == "__main__":
    assert start_method() == "fork"
    sim = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=0.2))
    keys = [("a red ball moves from left to right", 1), ("a blue cube moves from right to left", 2)]
    serial = build_scenes(sim, keys, workers=1, progress=False)
    os.register_at_fork(after_in_child=lambda: time.sleep(3600))      # every forked child is stuck
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        built = build_scenes(sim, keys, workers=2, progress=False, timeout_s=60, start_timeout_s=3)
    print("WARNED", any(issubclass(w.category, PoolStartWarning) for w in caught))
    print("SAME", [s.content_hash() for s in built] == [s.content_hash() for s in serial])
"""


def test_stuck_forked_workers_are_replaced_by_spawned_ones(tmp_path):
    import subprocess
    import sys

    if start_method() != "fork":
        pytest.skip("workers are spawned here")
    script = tmp_path / "stuck_fork.py"
    script.write_text(_STUCK_FORK)
    start = time.monotonic()
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "WARNED True" in out.stdout and "SAME True" in out.stdout, out.stdout + out.stderr[-2000:]
    assert time.monotonic() - start < 200
