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
guard; otherwise spawned. Every wait is bounded: a scene that takes longer than `timeout_s`
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

from morphosim_gym.scene import Scene4D

__all__ = ["build_scenes", "ScenePoolError", "POOL_BACKENDS", "DEFAULT_SCENE_TIMEOUT_S", "single_threaded",
           "start_method"]

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


def _init_worker(sim: Any) -> None:
    global _WORKER_SIM
    _WORKER_SIM = sim


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
    """Stop a process pool's workers now (a timed-out build must not leave them fitting)."""
    for proc in list(getattr(pool, "_processes", {}).values()):
        try:
            proc.kill()
        except Exception:  # pragma: no cover - already gone
            pass
    pool.shutdown(wait=False, cancel_futures=True)


def _process(sim: Any, keys: Sequence[Key], workers: int, timeout_s: float, tick: Callable[[], None]
             ) -> list[Scene4D]:
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    method = start_method()
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context(method), initializer=_init_worker,
                               initargs=(sim,))
    results: dict[int, Scene4D] = {}
    try:
        pending = {pool.submit(_worker_build, i, p, s) for i, (p, s) in enumerate(keys)}
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
                 progress: Optional[bool] = None, timeout_s: Optional[float] = None) -> list[Scene4D]:
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
    """
    if backend not in POOL_BACKENDS:
        raise ValueError(f"Expected pool backend in {POOL_BACKENDS}, found {backend!r}")
    timeout = DEFAULT_SCENE_TIMEOUT_S if timeout_s is None else float(timeout_s)
    if not timeout > 0:
        raise ValueError(f"Expected timeout_s > 0, found {timeout_s!r}")
    keys = [(str(p), int(s)) for p, s in keys]
    if not keys:
        return []
    n = min((os.cpu_count() or 1) if workers is None else int(workers), len(keys))
    from tqdm import tqdm

    bar = tqdm(total=len(keys), desc=f"building {len(keys)} scenes", unit="scene", disable=_DISABLE[progress], dynamic_ncols=True, leave=False)
    try:
        if n <= 1 and backend == "process":
            return _serial(sim, keys, timeout, bar.update)
        run = _process if backend == "process" else _ray
        return run(quiet(sim), keys, max(n, 1), timeout, bar.update)
    finally:
        bar.close()
