"""`build_scenes`: many (prompt, seed) scenes at once, in this process, a process pool or Ray.

    scenes = build_scenes(sim, [("a red ball moves from left to right", 0), ...], workers=4)

What a worker builds is `sim.generate(prompt, seed=seed)`, with the same `MorphoSim` the env
uses (its on-disk caches included: with `reconstruction="fit"` the reconstruction cache of
`reconstruct.pipeline`, and with `SimConfig(cache=True)` the clip and scene caches), so a
second build of the same pool loads instead of fitting. Every scene is built with one numba
thread and one torch thread, in this process and in the workers alike, so a serial build and
a parallel one give bit-identical scenes (`Scene4D.content_hash`).

Workers are forked where that is safe (Linux, and numba's threading layer is a fork-safe one:
`morphosim_gym.parallel`), which also spares user scripts the `if __name__ == "__main__"`
guard; otherwise spawned. A forked worker first runs a numba kernel with the scenes' thread
settings and reports ready: forking a process whose other threads are inside a native thread
pool (TBB, OpenMP, a tqdm lock) can leave the child stuck, and then the build starts again with
spawned workers (`PoolStartWarning`; those need the guard and a picklable sim). Every wait is bounded: a scene that takes longer than `timeout_s`
stops the build with a `ScenePoolError`, as does a worker that dies (killed, out of memory);
an error raised while building a scene (a prompt the parser rejects, a clip that cannot be
reconstructed) is raised again here as it was.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import sys
import time
from contextlib import AbstractContextManager, contextmanager, nullcontext
from typing import Any, Callable, Iterator, Optional, Sequence

import numba
import numpy as np

from morphosim_gym.scene import Scene4D

__all__ = ["build_scenes", "ScenePoolError", "PoolStartWarning", "POOL_BACKENDS", "DEFAULT_SCENE_TIMEOUT_S",
           "DEFAULT_START_TIMEOUT_S", "single_threaded", "start_method"]

POOL_BACKENDS = ("process", "ray")
DEFAULT_SCENE_TIMEOUT_S = 3600.0
"""Seconds one scene may take before the build gives up (a full-size fit on a loaded laptop
takes a few minutes)."""

Key = tuple[str, int]
_DISABLE = {True: False, False: True, None: None}     # progress -> tqdm's disable (None: only on a terminal)


class ScenePoolError(RuntimeError):
    """A pool build that could not finish: a worker died or a scene took longer than its timeout."""


# ------------------------------------------------------------------ one scene
def _uses_torch(sim: Any) -> bool:
    return getattr(getattr(sim, "config", None), "reconstruction", None) == "fit"


@contextmanager
def single_threaded(torch_too: bool = True) -> Iterator[None]:
    """Run the enclosed code with one numba thread (and one torch thread when `torch_too`), then
    restore the previous counts."""
    import numba

    from morphosim_gym.parallel import kernel_lock

    torch = None
    if torch_too:
        import torch
    with kernel_lock():
        old_numba = numba.get_num_threads()
        old_torch = torch.get_num_threads() if torch is not None else None
        numba.set_num_threads(1)
        if torch is not None:
            torch.set_num_threads(1)
        try:
            with _one_blas_thread():       # numpy's BLAS too: its idle threads spin on a busy machine
                yield
        finally:
            numba.set_num_threads(old_numba)
            if torch is not None:
                torch.set_num_threads(old_torch)


def _one_blas_thread() -> AbstractContextManager:
    """Limit numpy's BLAS to one thread (threadpoolctl, installed with scikit-learn); a no-op without it."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


def build_one(sim: Any, prompt: str, seed: int) -> Scene4D:
    """`sim.generate(prompt, seed=seed)` with one numba and one torch thread (what every worker runs)."""
    with single_threaded(_uses_torch(sim)):
        return sim.generate(prompt, seed=int(seed))


def quiet(sim: Any) -> Any:
    """`sim` with the reconstruction's own progress bars off (a worker's bars would interleave with
    the pool's); the same sim when it is not a `MorphoSim` or has none to turn off. Progress is not
    part of the reconstruction's cache key, so the scenes are the same."""
    from dataclasses import replace

    from morphosim_gym.pipeline import MorphoSim

    if not isinstance(sim, MorphoSim) or sim.config.reconstruction != "fit":
        return sim
    from morphosim_gym.reconstruct.presets import resolve_reconstruction_config

    cfg = resolve_reconstruction_config(sim.config.reconstruction_config)
    if not cfg.progress and not cfg.fit.progress and not cfg.features.progress:
        return sim
    cfg = replace(cfg, progress=False, fit=replace(cfg.fit, progress=False),
                  features=replace(cfg.features, progress=False))
    out = MorphoSim(replace(sim.config, reconstruction_config=cfg))
    out.editor = sim.editor
    return out


# ------------------------------------------------------------------ worker side (process pool)
_WORKER_SIM: Any = None
DEFAULT_START_TIMEOUT_S = 60.0
"""Seconds forked workers may take to report ready before the pool is rebuilt with spawned ones."""


class PoolStartWarning(RuntimeWarning):
    """Forked scene workers did not start; the build goes on with spawned ones."""


@numba.njit(parallel=True, cache=True)
def _probe_kernel(x: np.ndarray) -> float:       # pragma: no cover - compiled
    total = 0.0
    for i in numba.prange(x.shape[0]):
        total += x[i]
    return total


def _own_tqdm_lock() -> None:
    """Give this (forked) worker a tqdm write lock of its own. tqdm's default lock is a
    multiprocessing lock shared with the parent plus a thread lock copied from it: a child that
    takes the shared one and then waits on a copied thread lock another parent thread held at
    fork time never lets go of it, and a child killed while holding it freezes the parent's next
    bar. Workers' bars are off (`quiet`), so they need no lock shared with anyone."""
    import threading

    from tqdm import tqdm

    tqdm.set_lock(threading.RLock())


def _init_worker(sim: Any, ready: Any = None) -> None:
    """Worker start: keep the sim, take a tqdm lock of its own, and, in a forked worker, run a
    numba kernel with the thread settings every scene uses and report ready (a fork that left a
    native thread pool broken hangs here, where the parent can see it, not in a scene)."""
    global _WORKER_SIM
    import faulthandler
    import signal

    _WORKER_SIM = sim
    _own_tqdm_lock()
    faulthandler.register(signal.SIGUSR1, all_threads=True)     # the parent asks for stacks before it kills
    if ready is not None:
        with single_threaded(_uses_torch(sim)):
            _probe_kernel(np.ones(64, np.float32))
        ready.put(os.getpid())


def _worker_build(index: int, prompt: str, seed: int) -> tuple[int, Scene4D]:
    return index, build_one(_WORKER_SIM, prompt, seed)


def start_method() -> str:
    """"fork" where forking this process is safe for numba and torch (Linux; a fork-safe numba
    threading layer or none launched yet), else "spawn"."""
    if not sys.platform.startswith("linux") or "fork" not in mp.get_all_start_methods():
        return "spawn"
    from morphosim_gym.parallel import threading_layer

    return "spawn" if threading_layer() == "omp" else "fork"


# ------------------------------------------------------------------ backends
def _serial(sim: Any, keys: Sequence[Key], timeout_s: float, tick: Callable[[], None]) -> list[Scene4D]:
    out = []
    for prompt, seed in keys:
        out.append(build_one(sim, prompt, seed))
        tick()
    return out


def _kill(pool: Any) -> None:
    """Stop a process pool's workers now (a timed-out build must not leave them fitting); each is
    first asked for its threads' stacks (on its stderr), so a hang says where it was."""
    import signal

    procs = list(getattr(pool, "_processes", {}).values())
    for proc in procs:
        try:
            os.kill(proc.pid, signal.SIGUSR1)
        except Exception:  # pragma: no cover - already gone
            pass
    if procs:
        time.sleep(0.5)
    for proc in procs:
        try:
            proc.kill()
        except Exception:  # pragma: no cover - already gone
            pass
    pool.shutdown(wait=False, cancel_futures=True)


class _NotStarted(Exception):
    """Forked workers that did not report ready in time."""


def _wait_ready(ready: Any, workers: int, timeout_s: float, pending: set) -> None:
    """Wait for `workers` ready reports on `ready`, or for a scene future to finish first (a result,
    an error or a dead pool: the build loop takes it from there); `_NotStarted` when neither comes."""
    import queue

    deadline = time.monotonic() + timeout_s
    seen = 0
    while seen < workers:
        left = deadline - time.monotonic()
        if left <= 0:
            raise _NotStarted(f"{seen} of {workers}")
        try:
            ready.get(timeout=min(left, 0.2))
            seen += 1
        except queue.Empty:
            if any(f.done() for f in pending):
                return


def _process(sim: Any, keys: Sequence[Key], workers: int, timeout_s: float, tick: Callable[[], None],
             start_timeout_s: float = DEFAULT_START_TIMEOUT_S) -> list[Scene4D]:
    method = start_method()
    if method == "fork":
        _probe_kernel(np.ones(64, np.float32))       # compiled here, before the fork: workers inherit it
        try:
            return _pool_build(sim, keys, workers, timeout_s, tick, "fork", start_timeout_s)
        except _NotStarted as exc:
            import warnings

            warnings.warn(f"Forked scene-building workers did not start within {start_timeout_s:.0f} s ({exc} "
                          f"ready; a thread of this process was probably inside a native thread pool when it "
                          f"forked): building with spawned workers instead", PoolStartWarning, stacklevel=3)
    return _pool_build(sim, keys, workers, timeout_s, tick, "spawn", None)


def _pool_build(sim: Any, keys: Sequence[Key], workers: int, timeout_s: float, tick: Callable[[], None],
                method: str, start_timeout_s: Optional[float]) -> list[Scene4D]:
    """One process-pool build; with `start_timeout_s`, the workers must report ready first."""
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    ctx = mp.get_context(method)
    ready = ctx.Queue() if start_timeout_s is not None else None
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_worker,
                               initargs=(sim, ready))
    results: dict[int, Scene4D] = {}
    try:
        pending = {pool.submit(_worker_build, i, p, s) for i, (p, s) in enumerate(keys)}
        if ready is not None:
            _wait_ready(ready, min(workers, len(keys)), start_timeout_s, pending)
        rounds = -(-len(keys) // workers)
        deadline = time.monotonic() + timeout_s * rounds
        while pending:
            left = deadline - time.monotonic()
            done, pending = wait(pending, timeout=max(left, 0.0), return_when=FIRST_COMPLETED)
            if not done:
                raise ScenePoolError(f"Expected {len(keys)} scenes within {timeout_s:.0f} s each ({rounds} rounds "
                                     f"on {workers} workers), found {len(results)} after {timeout_s * rounds:.0f} s; "
                                     f"pass a larger pool_timeout_s for slow fits")
            for fut in done:
                try:
                    i, scene = fut.result(timeout=0)
                except BrokenProcessPool as exc:
                    raise ScenePoolError(f"A scene-building worker process died ({method} pool of {workers}) after "
                                         f"{len(results)} of {len(keys)} scenes: {exc}; killed or out of memory? "
                                         f"Try fewer pool_workers") from None
                results[i] = scene
                tick()
    except BaseException:
        _kill(pool)
        raise
    pool.shutdown(wait=True)
    return [results[i] for i in range(len(keys))]


def _ray_build(ray: Any, sim: Any, keys: Sequence[Key], workers: int, timeout_s: float,
               tick: Callable[[], None]) -> list[Scene4D]:
    started = not ray.is_initialized()
    if started:
        ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False, configure_logging=False)
    try:
        remote = ray.remote(num_cpus=1, max_retries=0)(build_one)
        sim_ref = ray.put(sim)
        refs = {remote.remote(sim_ref, p, s): i for i, (p, s) in enumerate(keys)}
        results: dict[int, Scene4D] = {}
        rounds = -(-len(keys) // workers)
        deadline = time.monotonic() + timeout_s * rounds
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1, timeout=max(deadline - time.monotonic(), 0.0))
            if not done:
                for ref in pending:
                    ray.cancel(ref, force=True)
                raise ScenePoolError(f"Expected {len(keys)} scenes within {timeout_s:.0f} s each on Ray, found "
                                     f"{len(results)}; pass a larger pool_timeout_s for slow fits")
            try:
                results[refs[done[0]]] = ray.get(done[0], timeout=timeout_s)
            except ray.exceptions.RayTaskError as exc:            # the scene's own error, raised as it was
                raise exc.as_instanceof_cause() from None
            except (ray.exceptions.WorkerCrashedError, ray.exceptions.RayActorError) as exc:
                raise ScenePoolError(f"A Ray worker died while building a scene: {exc}") from None
            tick()
        return [results[i] for i in range(len(keys))]
    finally:
        if started:
            ray.shutdown()


def _ray(sim: Any, keys: Sequence[Key], workers: int, timeout_s: float, tick: Callable[[], None]) -> list[Scene4D]:
    try:
        import ray
    except ImportError:
        raise ValueError("Expected the ray package for pool_backend='ray', found it missing; "
                         "pip install -e '.[bench]'") from None
    return _ray_build(ray, sim, keys, workers, timeout_s, tick)


# ------------------------------------------------------------------ api
def build_scenes(sim: Any, keys: Sequence[Key], workers: Optional[int] = 1, backend: str = "process",
                 progress: Optional[bool] = None, timeout_s: Optional[float] = None,
                 start_timeout_s: float = DEFAULT_START_TIMEOUT_S) -> list[Scene4D]:
    """The scenes of `keys` ((prompt, seed) pairs), in order (see the module docstring).

    Args:
        sim: the `MorphoSim` (or any object with `generate(prompt, seed=...)`; a process pool
            pickles it when it spawns).
        workers: processes (or Ray tasks at a time); 1 builds here; None = one per CPU.
        backend: "process" (a local process pool) or "ray" (a Ray cluster: the running one, or a
            local one of `workers` CPUs started and stopped here).
        progress: a tqdm bar; None = only on a terminal.
        timeout_s: seconds one scene may take (default `DEFAULT_SCENE_TIMEOUT_S`); the build's
            limit is that times the rounds of `workers` it needs.
        start_timeout_s: seconds forked workers may take to report ready; past it they are killed
            and the build starts again with spawned workers (a `PoolStartWarning` says so).
    """
    if backend not in POOL_BACKENDS:
        raise ValueError(f"Expected pool backend in {POOL_BACKENDS}, found {backend!r}")
    timeout = DEFAULT_SCENE_TIMEOUT_S if timeout_s is None else float(timeout_s)
    if not timeout > 0:
        raise ValueError(f"Expected timeout_s > 0, found {timeout_s!r}")
    if not float(start_timeout_s) > 0:
        raise ValueError(f"Expected start_timeout_s > 0, found {start_timeout_s!r}")
    keys = [(str(p), int(s)) for p, s in keys]
    if not keys:
        return []
    n = min((os.cpu_count() or 1) if workers is None else int(workers), len(keys))
    from tqdm import tqdm

    bar = tqdm(total=len(keys), desc=f"building {len(keys)} scenes", unit="scene", disable=_DISABLE[progress], dynamic_ncols=True, leave=False)
    try:
        if n <= 1 and backend == "process":
            return _serial(sim, keys, timeout, bar.update)
        if backend == "process":
            return _process(quiet(sim), keys, max(n, 1), timeout, bar.update, float(start_timeout_s))
        return _ray(quiet(sim), keys, max(n, 1), timeout, bar.update)
    finally:
        bar.close()
