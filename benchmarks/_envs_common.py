"""What the env benchmarks (`envs.py`, `gpu_envs.py`) share: scene kinds, random-action rollouts,
timers around the render and skinning calls, machine facts.
"""

from __future__ import annotations

import os
import platform
import time
from typing import Any, Callable

import numpy as np

#: scene kinds -> env arguments: "procedural" (`assets="off"`: today's light scenes, no sky, as
#: `MORPHOSIM_ASSET_SOURCES=""`), "real" (the default `assets="auto"`: real assets and HDR skies
#: where installed)
SCENES = ("procedural", "real")
WARMUP_STEPS = 10


def scene_kwargs(scenes: str) -> dict:
    """Env arguments of a scene kind (`SCENES`)."""
    from morphosim_gym import GenerationConfig, SimConfig
    from morphosim_gym.envs.config import DEFAULT_SIM_CONFIG

    if scenes == "real":
        return {}
    if scenes == "procedural":
        gen = DEFAULT_SIM_CONFIG.generation
        return {"sim": SimConfig(reconstruction=DEFAULT_SIM_CONFIG.reconstruction,
                                 generation=GenerationConfig(**{**_fields(gen), "assets": "off"}))}
    raise ValueError(f"Expected scenes in {SCENES}, found {scenes!r}")


def _fields(cfg: Any) -> dict:
    import dataclasses

    return {f.name: getattr(cfg, f.name) for f in dataclasses.fields(cfg)}


def random_actions(space_shape: tuple, seed: int = 0) -> Callable[[], np.ndarray]:
    """A callable giving uniform [-1, 1] float32 actions of this shape (seeded)."""
    rng = np.random.default_rng(seed)
    return lambda: rng.uniform(-1, 1, space_shape).astype(np.float32)


def vector_rollout(venv: Any, steps: int, warmup: int = WARMUP_STEPS, on_start: Callable[[], Any] = None) -> float:
    """Seconds of `steps` random-action steps of a vector env (after `warmup` untimed ones, then
    `on_start()`); the env is reset with seed 0 first and autoresets itself."""
    venv.reset(seed=0)
    act = random_actions(venv.action_space.shape)
    for _ in range(warmup):
        venv.step(act())
    if on_start is not None:
        on_start()
    t0 = time.perf_counter()
    for _ in range(steps):
        venv.step(act())
    return time.perf_counter() - t0


def single_rollout(env: Any, steps: int, warmup: int = 20) -> float:
    """Seconds of `steps` random-action steps of one env (resetting it when an episode ends)."""
    env.reset(seed=0)
    act = random_actions(env.action_space.shape)

    def run(k: int) -> None:
        for _ in range(k):
            _, _, term, trunc, _ = env.step(act())
            if term or trunc:
                env.reset()

    run(warmup)
    t0 = time.perf_counter()
    run(steps)
    return time.perf_counter() - t0


class CallTimer:
    """Wall time spent inside some functions, by wrapping them (`install`) until `uninstall`.

    `CallTimer({"render": [(native_vector, "render_batch")], "skinning": [(SceneWorld, "gaussians")]})`
    sums the time of each group's calls in `seconds[group]`."""

    def __init__(self, groups: dict[str, list[tuple[Any, str]]]) -> None:
        self.groups = groups
        self.seconds = {g: 0.0 for g in groups}
        self._undo: list[tuple[Any, str, Any]] = []

    def install(self) -> "CallTimer":
        for group, targets in self.groups.items():
            for owner, name in targets:
                self._wrap(owner, name, group)
        return self

    def uninstall(self) -> None:
        for owner, name, orig in reversed(self._undo):
            setattr(owner, name, orig)
        self._undo.clear()

    def _wrap(self, owner: Any, name: str, group: str) -> None:
        orig = getattr(owner, name)
        seconds = self.seconds

        def timed(*a, **k):
            t0 = time.perf_counter()
            try:
                return orig(*a, **k)
            finally:
                seconds[group] += time.perf_counter() - t0

        setattr(owner, name, timed)
        self._undo.append((owner, name, orig))


def render_and_skinning_timer() -> CallTimer:
    """A `CallTimer` of a native vector env's batched render and its skinning (scene and agent)."""
    from morphosim_gym.envs import native_vector
    from morphosim_gym.envs.world import SceneWorld
    from morphosim_gym.rig.base import Rig

    return CallTimer({"render": [(native_vector, "render_batch")],
                      "skinning": [(SceneWorld, "gaussians"), (Rig, "gaussians")]})


def machine() -> dict:
    """CPU count, Python version and the load average now."""
    return {"cpus": os.cpu_count(), "python": platform.python_version(),
            "loadavg_at_end": [round(x, 2) for x in os.getloadavg()]}
