"""Which scene an episode gets: `SceneSource` (scenes by prompt and seed, cached) and
`SceneChooser` (reset options, the env's prompt, the pre-built pool or the task's distribution).

A pool is built at construction, in parallel when asked (`pool.build_scenes`: a process pool or
Ray, with a progress bar, every wait bounded), and every pooled scene is checked for the target
there, so a prompt whose scene lacks the target fails at `make`, not at some later reset.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any, Optional

import numpy as np

from morphosim_gym.scene import Scene4D
from morphosim_gym.tasks import Task
from morphosim_gym.tasks.spec import SceneRequest

from .options import ResetOptions
from .pool import build_one, build_scenes

__all__ = ["SceneSource", "SceneChooser"]

_SEED_RANGE = 2 ** 31 - 1


class SceneSource:
    """Scenes by (prompt, seed) through a `MorphoSim`, with an in-memory LRU cache.

    With `reconstruction="oracle"` (the envs' default) `MorphoSim.generate` composes the ground
    truth directly, without rendering the clip frames that path discards; with "fit" it
    reconstructs the clip (cached on disk by the reconstruction). Scenes are built with one numba
    (and torch) thread, here as in `build_many`'s workers, so a scene does not depend on how it
    was built.
    """

    def __init__(self, sim: Any, cache_size: int = 32) -> None:
        self.sim = sim
        self.cache_size = int(cache_size)
        self._cache: OrderedDict[tuple[str, int], Scene4D] = OrderedDict()

    def get(self, prompt: str, seed: int) -> Scene4D:
        """The scene of a prompt and seed (cached)."""
        key = (prompt, int(seed))
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key]
        scene = self._generate(prompt, int(seed))
        self._cache[key] = scene
        while len(self._cache) > self.cache_size:
            self._cache.popitem(last=False)
        return scene

    def build_many(self, keys: list[tuple[str, int]], workers: Optional[int] = 1, backend: str = "process",
                   timeout_s: Optional[float] = None, progress: Optional[bool] = None) -> list[Scene4D]:
        """The scenes of (prompt, seed) `keys`, the missing ones built at once (`pool.build_scenes`)
        and all kept in the cache (which grows to hold them)."""
        keys = [(str(p), int(s)) for p, s in keys]
        self.cache_size = max(self.cache_size, len(set(keys) | set(self._cache)))   # room for every pool built into it
        missing = list(dict.fromkeys(k for k in keys if k not in self._cache))
        for key, scene in zip(missing, build_scenes(self.sim, missing, workers, backend, progress, timeout_s)):
            self._cache[key] = scene
        return [self.get(*k) for k in keys]

    def _generate(self, prompt: str, seed: int) -> Scene4D:
        return build_one(self.sim, prompt, seed)


class SceneChooser:
    """The (request, scene seed) of each reset.

    Args:
        task: the env's task (its scene distribution).
        prompt: the env's fixed prompt, or None for the task's distribution.
        target: the env's target name (None: the task's choice).
        scene_seed: the env's fixed generation seed, or None to draw one per reset.
        pool: pre-draw this many (request, seed) pairs from `pool_seed`; resets without a
            prompt or scene seed option draw from them. None: no pool.
        pool_seed: the pool's seed.
    """

    def __init__(self, task: Task, prompt: Optional[str], target: Optional[str], scene_seed: Optional[int],
                 pool: Optional[int] = None, pool_seed: int = 0) -> None:
        self.task, self.prompt, self.target, self.scene_seed = task, prompt, target, scene_seed
        self.pool: list[tuple[SceneRequest, int]] = []
        if pool is not None:
            rng = np.random.default_rng([pool_seed, 0x5EED])
            for _ in range(pool):
                request = self.request(rng)
                self.pool.append((request, self._seed(rng, None)))

    def prebuild(self, source: SceneSource, workers: Optional[int] = 1, backend: str = "process",
                 timeout_s: Optional[float] = None) -> None:
        """Generate the pool's scenes into `source` (`workers` at a time; its cache holds them all),
        and check that each has its target (`ValueError` naming the prompt otherwise)."""
        if not self.pool:
            return
        scenes = source.build_many([(r.prompt, seed) for r, seed in self.pool], workers, backend, timeout_s)
        for (request, seed), scene in zip(self.pool, scenes):
            try:
                self.task.resolve_target(scene, self.target or request.target or None)
            except ValueError as exc:
                raise ValueError(f"Scene pool: the scene of {request.prompt!r} (seed {seed}) has no target: "
                                 f"{exc}") from None

    def request(self, rng: np.random.Generator) -> SceneRequest:
        """The env's prompt, or a draw from the task's scene distribution."""
        if self.prompt is not None:
            return SceneRequest(self.prompt, self.target or "", "")
        return self.task.sample_scene(rng)

    def choose(self, rng: np.random.Generator, options: ResetOptions) -> tuple[SceneRequest, int]:
        """The scene request and seed of a reset with `options`."""
        if options.prompt is not None:
            target = options.target if options.target is not None else self.target
            request = SceneRequest(options.prompt, target or "", "")
            return request, self._seed(rng, options.scene_seed)
        if self.pool and options.scene_seed is None:
            return self.pool[int(rng.integers(len(self.pool)))]
        request = self.request(rng)
        return request, self._seed(rng, options.scene_seed)

    def _seed(self, rng: np.random.Generator, given: Optional[int]) -> int:
        seed = given if given is not None else self.scene_seed
        return int(rng.integers(_SEED_RANGE)) if seed is None else int(seed)
