"""What the task-aware built-ins (oracle, colour) need from an env: its MorphoSim task kind."""

from __future__ import annotations

from typing import Any

__all__ = ["task_kind"]


def task_kind(env: Any, who: str) -> str:
    """The kind ("track", "reach", "find") of a MorphoSim env's task; ValueError naming `who`
    for an env without one."""
    task = getattr(getattr(env, "unwrapped", env), "task", None)
    kind = getattr(task, "kind", None)
    if not isinstance(kind, str):
        name = type(getattr(env, "unwrapped", env)).__name__
        raise ValueError(f"Expected a MorphoSim env with a task (Track, Reach or Find) for {who}, found {name}")
    return kind
