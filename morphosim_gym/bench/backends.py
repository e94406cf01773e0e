"""Where episodes run: this process, a local process pool, or a Ray cluster.

Each backend has two phases with the same shape: `prepare` generates every distinct scene of
the sweep once into the shared on-disk `MorphoSim` cache, then `run` executes the episodes
and yields their results as they finish (in any order; the runner sorts). Workers pin numba
to one thread, and an episode depends only on its key, so every backend gives the same
records.
"""

from __future__ import annotations

import warnings
from typing import Any, Iterable, Iterator, Optional

from .episode import EpisodeKey, EpisodeResult, EpisodeRunner
from .suite import Suite

__all__ = ["BACKENDS", "run_backend", "Job"]

BACKENDS = ("local", "ray")

Job = tuple[EpisodeKey, int] | tuple[EpisodeKey, int, bool]   # an episode, frames to keep[, keep_steps]


def _single_thread() -> None:
    """Pin numba's kernels to one thread in this worker (bitwise-reproducible, no oversubscription)."""
    import numba

    numba.set_num_threads(1)


# ---------------------------------------------------------------------- local
_RUNNERS: dict[tuple[str, Optional[str], bool], EpisodeRunner] = {}


def _runner(suite: Suite, cache_dir: Optional[str], grounding: Optional[str]) -> EpisodeRunner:
    key = (suite.digest(), cache_dir, grounding)
    if key not in _RUNNERS:
        _RUNNERS[key] = EpisodeRunner(suite, cache_dir, grounding)
    return _RUNNERS[key]


def _prepare_one(suite: Suite, cache_dir: Optional[str], grounding: Optional[str], seed: int) -> str:
    return _runner(suite, cache_dir, grounding).prepare(seed)


def _run_one(suite: Suite, cache_dir: Optional[str], grounding: Optional[str], job: Job) -> EpisodeResult:
    return _runner(suite, cache_dir, grounding).run(*job)


def _local(suite: Suite, seeds: list[int], jobs: list[Job], cache_dir: Optional[str], workers: int,
           grounding: Optional[str]) -> Iterator[EpisodeResult]:
    if workers <= 1:
        import numba

        threads = numba.get_num_threads()
        _single_thread()
        try:
            for seed in seeds:
                _prepare_one(suite, cache_dir, grounding, seed)
            for job in jobs:
                yield _run_one(suite, cache_dir, grounding, job)
        finally:
            numba.set_num_threads(threads)
        return
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"),
                             initializer=_single_thread) as pool:
        for fut in as_completed([pool.submit(_prepare_one, suite, cache_dir, grounding, s) for s in seeds]):
            fut.result()
        futures = [pool.submit(_run_one, suite, cache_dir, grounding, job) for job in jobs]
        for fut in as_completed(futures):
            yield fut.result()


# ------------------------------------------------------------------------ ray
def _ray() -> Any:
    """The ray module, once the extra's packages it needs here (ray, psutil) are found installed."""
    from morphosim_gym.extras import require_extra

    require_extra("bench", "ray", "psutil", needed_for="--backend ray")
    import ray

    return ray


RAY_START_TRIES = 3
_RAY_START_TIMEOUT = "timed out during startup"     # Ray's words when its raylet misses its fixed 30 s wait


def _start_ray(ray: Any, tries: int = RAY_START_TRIES, **kw: Any) -> None:
    """`ray.init(**kw)`, tried again when Ray's node times out during startup (a busy machine: its
    raylet must register within a fixed 30 s). The processes a failed try started are ended before
    the next; other errors are raised at once; the last timeout is raised naming the tries."""
    import psutil

    for attempt in range(1, tries + 1):
        before = {p.pid for p in psutil.Process().children(recursive=True)}
        try:
            ray.init(**kw)
            return
        except Exception as err:
            if _RAY_START_TIMEOUT not in str(err):
                raise
            _end_new_children(psutil, before)
            if attempt == tries:
                raise RuntimeError(f"Ray's local node timed out during startup {tries} times (a machine too "
                                   "busy to start its raylet within 30 s); try again with fewer jobs running, "
                                   "or use --backend local") from err
            warnings.warn(f"Ray's local node timed out during startup (try {attempt} of {tries}); "
                          "trying again", RuntimeWarning, stacklevel=2)


def _end_new_children(psutil: Any, before: set[int]) -> None:
    """Terminate (then kill) the child processes of this process that are not in `before`."""
    new = [p for p in psutil.Process().children(recursive=True) if p.pid not in before]
    for p in new:
        try:
            p.terminate()
        except psutil.NoSuchProcess:
            pass
    _, alive = psutil.wait_procs(new, timeout=5)
    for p in alive:
        try:
            p.kill()
        except psutil.NoSuchProcess:
            pass
    psutil.wait_procs(alive, timeout=5)


def _ray_episodes(suite: Suite, seeds: list[int], jobs: list[Job], cache_dir: Optional[str], workers: int,
                  address: Optional[str], grounding: Optional[str]) -> Iterator[EpisodeResult]:
    ray = _ray()
    started = False
    if not ray.is_initialized():
        # "local": our own cluster, even where RAY_ADDRESS or a stale `ray start` file names another.
        kw: dict[str, Any] = {"address": address} if address else {"address": "local", "num_cpus": max(workers, 1)}
        _start_ray(ray, include_dashboard=False, log_to_driver=False, configure_logging=False, **kw)
        started = True
    try:
        yield from _ray_run(ray, suite, seeds, jobs, cache_dir, workers, grounding)
    finally:
        if started:
            ray.shutdown()


def _ray_run(ray: Any, suite: Suite, seeds: list[int], jobs: list[Job], cache_dir: Optional[str], workers: int,
             grounding: Optional[str]) -> Iterator[EpisodeResult]:
    @ray.remote(num_cpus=1)
    class Worker:
        def __init__(self, suite: Suite, cache_dir: Optional[str], grounding: Optional[str]) -> None:
            _single_thread()
            self.runner = EpisodeRunner(suite, cache_dir, grounding)

        def prepare(self, seeds: list[int]) -> list[str]:
            return [self.runner.prepare(s) for s in seeds]

        def run(self, job: Job) -> EpisodeResult:
            return self.runner.run(*job)

    n = max(1, min(workers, len(jobs) or 1))
    suite_ref = ray.put(suite)
    actors = [Worker.remote(suite_ref, cache_dir, grounding) for _ in range(n)]
    ray.get([a.prepare.remote(seeds[i::n]) for i, a in enumerate(actors)])      # each scene generated once
    from ray.util import ActorPool

    pool = ActorPool(actors)
    yield from pool.map_unordered(lambda a, job: a.run.remote(job), jobs)
    for a in actors:
        ray.kill(a)


def run_backend(backend: str, suite: Suite, seeds: Iterable[int], jobs: Iterable[Job], cache_dir: Optional[str],
                workers: int = 1, address: Optional[str] = None,
                grounding: Optional[str] = None) -> Iterator[EpisodeResult]:
    """Generate the scenes of `seeds` once, then run `jobs`, yielding results as they finish.
    `grounding`: the level of the scene prompts (see `EpisodeRunner`); None: the one in force here,
    resolved once in this process and handed to every worker (local or Ray) as it is."""
    from morphosim_gym.language.grounding import grounding_level

    seeds, jobs, grounding = list(seeds), list(jobs), grounding_level(grounding)
    if backend == "local":
        return _local(suite, seeds, jobs, cache_dir, workers, grounding)
    if backend == "ray":
        return _ray_episodes(suite, seeds, jobs, cache_dir, workers, address, grounding)
    raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")
