"""Task definitions (installed as morphosim_gym.tasks): what to achieve, as code and as YAML.

Three task kinds ship: `TrackTask` (pan-tilt camera keeps a moving object centred),
`ReachTask` (6-DoF arm intercepts a moving object) and `FindTask` (free camera finds and
centres the named object among distractors). Each kind reads a `TaskSpec` (scene
distribution, instruction, parameter overrides); the built-in specs are the YAML files of
this package (`track.yaml`, `reach.yaml`, `find.yaml`), and a user's YAML file with the
same structure defines a new task without code:

    from morphosim_gym.tasks import make_task
    task = make_task("my_task.yaml")            # or "track", or a TaskSpec / mapping
    env = gym.make("MorphoSim/Track-v0", task="my_task.yaml")
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from .base import CAMERA_OVERRIDE_KEYS, Evaluation, Task, TaskView, check_camera_override, describe_object
from .find import FindTask
from .reach import ReachTask
from .rewards import tolerance
from .spec import (TASK_DIR, TASK_KINDS, DistractorSpec, SceneDistribution, SceneRequest, TaskSpec,
                   builtin_task_names, load_task_spec)
from .track import TrackTask

__all__ = ["Task", "TrackTask", "ReachTask", "FindTask", "TASK_CLASSES", "make_task", "TaskSpec", "SceneDistribution",
           "DistractorSpec", "SceneRequest", "TaskView", "Evaluation", "load_task_spec", "builtin_task_names",
           "tolerance", "CAMERA_OVERRIDE_KEYS", "check_camera_override", "describe_object", "TASK_DIR", "TASK_KINDS"]

TASK_CLASSES: dict[str, type[Task]] = {"track": TrackTask, "reach": ReachTask, "find": FindTask}


def make_task(source: str | Path | Mapping[str, Any] | TaskSpec, **params: float) -> Task:
    """The task of a spec (a built-in name, a YAML path, a mapping or a `TaskSpec`), with optional
    parameter overrides."""
    spec = load_task_spec(source)
    return TASK_CLASSES[spec.kind](spec, **params)
