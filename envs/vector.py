"""Vector envs on a few CPU cores (a thin layer over `gym.make_vec`: the native batched
`MorphoSimVectorEnv`, or Gymnasium's sync / async vector envs), and registering YAML tasks as
env ids."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Mapping, Optional, Sequence

import gymnasium as gym

from . import ENTRY_POINTS, vector_entry_of

__all__ = ["make_vec", "register_task"]


def make_vec(env_id: str, num_envs: int, vectorization_mode: str = "async", render_threads: Optional[int] = None,
             wrappers: Sequence[Callable[[gym.Env], gym.Env]] = (), context: Optional[str] = None,
             **kwargs: Any) -> gym.vector.VectorEnv:
    """A vector env of `num_envs` copies of `env_id` (`gym.make_vec` with these defaults).

    Args:
        env_id: a registered id (e.g. "MorphoSim/Track-v0").
        num_envs: how many envs.
        vectorization_mode: "vector" (the native `MorphoSimVectorEnv`: all envs in this process,
            every step's cameras rendered in one batched call on all cores; the fast choice),
            "async" (one process per env) or "sync" (Gymnasium's SyncVectorEnv).
        render_threads: "sync"/"async": numba threads per env; None = the envs' default (1: on a
            few cores, small renders gain little from threads and lose a lot when the cores are
            shared). "vector": threads of the batched render (None: all of numba's threads).
        wrappers: callables applied to each env after `gym.make` ("sync"/"async" only; for
            "vector", pass `perturbations=[...]`, one `LanguagePerturbation` dict per env).
        context: multiprocessing start method for "async" (default "spawn": the parent may
            already run numba's threading layer, which is not safe to fork).
        kwargs: passed to `gym.make` for every env.

    Examples:
        >>> venv = make_vec("MorphoSim/Track-v0", 8, scene_pool=8)   # doctest: +SKIP
    """
    if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
        raise ValueError(f"Expected num_envs as a positive integer, found {num_envs!r}")
    if vectorization_mode not in ("vector", "async", "sync"):
        raise ValueError(f"Expected vectorization_mode 'vector', 'async' or 'sync', found {vectorization_mode!r}")
    if vectorization_mode == "vector":
        if wrappers:
            raise ValueError("Expected no wrappers with vectorization_mode='vector' (the native vector env steps "
                             "the envs itself), found some; pass perturbations=[{...}, ...] (one "
                             "LanguagePerturbation dict per env) for scheduled edits, or use 'sync'")
        return gym.make_vec(env_id, num_envs, vectorization_mode="vector_entry_point",
                            render_threads=render_threads, **kwargs)
    if render_threads is not None:
        kwargs = dict(kwargs, render_threads=render_threads)
    vector_kwargs = {"context": context or "spawn"} if vectorization_mode == "async" else {}
    return gym.make_vec(env_id, num_envs, vectorization_mode=vectorization_mode, vector_kwargs=vector_kwargs,
                        wrappers=list(wrappers), **kwargs)


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
    gym.register(id=env_id, entry_point=ENTRY_POINTS[spec.kind], vector_entry_point=vector_entry_of(spec.kind),
                 kwargs=dict(kwargs, task=task_arg))
    return env_id
