"""Vector envs on a few CPU cores, and registering YAML tasks as env ids."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Sequence

import gymnasium as gym

__all__ = ["make_vec", "register_task"]

_KIND_ENTRY = {
    "track": "morphosim_gym.envs.track:TrackEnv",
    "reach": "morphosim_gym.envs.reach:ReachEnv",
    "find": "morphosim_gym.envs.find:FindEnv",
}


def _make_one(env_id: str, kwargs: dict, wrappers: Sequence[Callable[[gym.Env], gym.Env]]) -> Callable[[], gym.Env]:
    def thunk() -> gym.Env:
        import morphosim_gym.envs  # noqa: F401  (registers the ids in a spawned worker)

        env = gym.make(env_id, **kwargs)
        for w in wrappers:
            env = w(env)
        return env

    return thunk


def make_vec(env_id: str, num_envs: int, vectorization_mode: str = "async", render_threads: Optional[int] = None,
             wrappers: Sequence[Callable[[gym.Env], gym.Env]] = (), context: Optional[str] = None,
             **kwargs: Any) -> gym.vector.VectorEnv:
    """A vector env of `num_envs` copies of `env_id`.

    Args:
        env_id: a registered id (e.g. "MorphoSim/Track-v0").
        num_envs: how many envs.
        vectorization_mode: "async" (one process per env; the fast choice on several cores) or "sync".
        render_threads: numba threads per env; None = the envs' default (1: on a few cores, small
            renders gain little from threads and lose a lot when the cores are shared).
        wrappers: callables applied to each env after `gym.make`.
        context: multiprocessing start method for "async" (default "spawn": the parent may
            already run numba's threading layer, which is not safe to fork).
        kwargs: passed to `gym.make` for every env.

    Examples:
        >>> venv = make_vec("MorphoSim/Track-v0", 8, scene_pool=8)   # doctest: +SKIP
    """
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"Expected num_envs as a positive integer, found {num_envs!r}")
    if vectorization_mode not in ("async", "sync"):
        raise ValueError(f"Expected vectorization_mode 'async' or 'sync', found {vectorization_mode!r}")
    if render_threads is not None:
        kwargs = dict(kwargs, render_threads=render_threads)
    fns = [_make_one(env_id, dict(kwargs), tuple(wrappers)) for _ in range(num_envs)]
    if vectorization_mode == "sync":
        return gym.vector.SyncVectorEnv(fns)
    return gym.vector.AsyncVectorEnv(fns, context=context or "spawn")


def register_task(source: str | Path | Mapping[str, Any], env_id: Optional[str] = None, **kwargs: Any) -> str:
    """Register a task (a YAML path, a built-in name or a mapping) as a Gymnasium id and return it.

    The id defaults to "MorphoSim/<Name>-v0" from the task's `name` (e.g. a task named
    "track-balls" becomes "MorphoSim/TrackBalls-v0"); `kwargs` become the id's default
    constructor arguments.
    """
    from morphosim_gym.tasks import load_task_spec

    spec = load_task_spec(source)
    if env_id is None:
        name = "".join(part.capitalize() for part in spec.name.replace("_", "-").split("-") if part)
        env_id = f"MorphoSim/{name}-v0"
    task_arg = str(source) if isinstance(source, (str, Path)) else spec
    gym.register(id=env_id, entry_point=_KIND_ENTRY[spec.kind], kwargs=dict(kwargs, task=task_arg))
    return env_id
