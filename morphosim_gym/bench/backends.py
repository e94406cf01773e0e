"""Where episodes run: this process, a local process pool, or a Ray cluster.

Each backend has two phases with the same shape: `prepare` generates every distinct scene of
the sweep once into the shared on-disk `MorphoSim` cache, then `run` executes the episodes
and yields their results as they finish (in any order; the runner sorts). Workers pin numba
to one thread, and an episode depends only on its key, so every backend gives the same
records.
"""

from __future__ import annotations

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


def _runner(suite: Suite, cache_dir: Optional[str], strict: bool) -> EpisodeRunner:
    key = (suite.digest(), cache_dir, strict)
    if key not in _RUNNERS:
        _RUNNERS[key] = EpisodeRunner(suite, cache_dir, strict)
    return _RUNNERS[key]


def _prepare_one(suite: Suite, cache_dir: Optional[str], strict: bool, seed: int) -> str:
    return _runner(suite, cache_dir, strict).prepare(seed)


def _run_one(suite: Suite, cache_dir: Optional[str], strict: bool, job: Job) -> EpisodeResult:
    return _runner(suite, cache_dir, strict).run(*job)


def _local(suite: Suite, seeds: list[int], jobs: list[Job], cache_dir: Optional[str], workers: int,
           strict: bool) -> Iterator[EpisodeResult]:
    if workers <= 1:
        import numba

        threads = numba.get_num_threads()
        _single_thread()
        try:
            for seed in seeds:
                _prepare_one(suite, cache_dir, strict, seed)
            for job in jobs:
                yield _run_one(suite, cache_dir, strict, job)
        finally:
            numba.set_num_threads(threads)
        return
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("spawn"),
                             initializer=_single_thread) as pool:
        for fut in as_completed([pool.submit(_prepare_one, suite, cache_dir, strict, s) for s in seeds]):
            fut.result()
        futures = [pool.submit(_run_one, suite, cache_dir, strict, job) for job in jobs]
        for fut in as_completed(futures):
            yield fut.result()


# ------------------------------------------------------------------------ ray
def _ray() -> Any:
    try:
        import ray
    except ImportError:
        raise ValueError("Expected the ray package for --backend ray, found it missing; "
                         "pip install -e '.[bench]'") from None
    return ray


def _ray_episodes(suite: Suite, seeds: list[int], jobs: list[Job], cache_dir: Optional[str], workers: int,
                  address: Optional[str], strict: bool) -> Iterator[EpisodeResult]:
    ray = _ray()
    started = False
    if not ray.is_initialized():
        # "local": our own cluster, even where RAY_ADDRESS or a stale `ray start` file names another.
        kw: dict[str, Any] = {"address": address} if address else {"address": "local", "num_cpus": max(workers, 1)}
        ray.init(include_dashboard=False, log_to_driver=False, configure_logging=False, **kw)
        started = True
    try:
        yield from _ray_run(ray, suite, seeds, jobs, cache_dir, workers, strict)
    finally:
        if started:
            ray.shutdown()


def _ray_run(ray: Any, suite: Suite, seeds: list[int], jobs: list[Job], cache_dir: Optional[str], workers: int,
             strict: bool) -> Iterator[EpisodeResult]:
    @ray.remote(num_cpus=1)
    class Worker:
        def __init__(self, suite: Suite, cache_dir: Optional[str], strict: bool) -> None:
            _single_thread()
            self.runner = EpisodeRunner(suite, cache_dir, strict)

        def prepare(self, seeds: list[int]) -> list[str]:
            return [self.runner.prepare(s) for s in seeds]

        def run(self, job: Job) -> EpisodeResult:
            return self.runner.run(*job)

    n = max(1, min(workers, len(jobs) or 1))
    suite_ref = ray.put(suite)
    actors = [Worker.remote(suite_ref, cache_dir, strict) for _ in range(n)]
    ray.get([a.prepare.remote(seeds[i::n]) for i, a in enumerate(actors)])      # each scene generated once
    from ray.util import ActorPool

    pool = ActorPool(actors)
    yield from pool.map_unordered(lambda a, job: a.run.remote(job), jobs)
    for a in actors:
        ray.kill(a)


def run_backend(backend: str, suite: Suite, seeds: Iterable[int], jobs: Iterable[Job], cache_dir: Optional[str],
                workers: int = 1, address: Optional[str] = None, strict: bool = False) -> Iterator[EpisodeResult]:
    """Generate the scenes of `seeds` once, then run `jobs`, yielding results as they finish; `strict`:
    see `EpisodeRunner`."""
    seeds, jobs = list(seeds), list(jobs)
    if backend == "local":
        return _local(suite, seeds, jobs, cache_dir, workers, strict)
    if backend == "ray":
        return _ray_episodes(suite, seeds, jobs, cache_dir, workers, address, strict)
    raise ValueError(f"Expected backend in {BACKENDS}, found {backend!r}")
