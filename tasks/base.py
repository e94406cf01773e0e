"""`Task`: what to achieve in a scene (dm_control's task half of the world/task/factory split).

A task owns the scene distribution (from its `TaskSpec`), the choice and description of the
target, where the rig starts (relative to the scene), the reward as a sum of named terms,
and the success definition. It reads the world through small accessors
(`world.target_position(t)`, `world.target_radius`, `world.focus`...) and never renders:
the env hands it the task camera and that camera's instance map (`TaskView`).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from morphosim_gym.scene.camera import Camera

from .spec import SceneRequest, TaskSpec, load_task_spec

if TYPE_CHECKING:  # pragma: no cover
    from morphosim_gym.rig import Rig
    from morphosim_gym.scene import Scene4D, SceneObject

__all__ = ["Task", "TaskView", "Evaluation", "CAMERA_OVERRIDE_KEYS", "check_camera_override", "describe_object",
           "a_or_an"]

CAMERA_OVERRIDE_KEYS = ("position", "look_at", "fov_y_deg")
_BASIC_COLORS = ("red", "green", "blue", "yellow", "orange", "purple", "pink", "brown", "gray", "white", "black",
                 "cyan", "magenta")


def a_or_an(text: str) -> str:
    """'a' or 'an' before `text`."""
    return "an" if text[:1].lower() in "aeiou" else "a"


def describe_object(obj: "SceneObject", scene: "Scene4D | None" = None) -> str:
    """Words for an object in an instruction: its asked colour (nearest basic name) and what it is: the
    noun as written, unless the scene's provenance says that noun was substituted (a "kangaroo"
    generated as a duck is "the duck": the instruction names what is in the scene)."""
    noun = obj.category if obj.name.rsplit("_", 1)[-1].isdigit() else obj.name
    if noun == obj.name and scene is not None and obj.name in substituted_nouns(scene):
        noun = obj.category
    if obj.color is None:
        return noun
    from morphosim_gym.colors import color_rgb

    rgb = np.asarray(obj.color)
    best = min(_BASIC_COLORS, key=lambda c: float(np.sum((np.asarray(color_rgb(c)) - rgb) ** 2)))
    return f"{best} {noun}"


def substituted_nouns(scene: "Scene4D") -> frozenset[str]:
    """The words of the prompt that the scene shows as something else (its provenance's record)."""
    return frozenset(asked for asked, *_ in scene.provenance.substitutions)


def check_camera_override(camera: Any) -> dict:
    """Validate a reset `camera` option: a mapping with keys among `CAMERA_OVERRIDE_KEYS`."""
    if camera is None:
        return {}
    if not isinstance(camera, Mapping):
        raise ValueError(f"Expected options['camera'] to be a mapping with keys in {CAMERA_OVERRIDE_KEYS}, found "
                         f"{type(camera).__name__}")
    unknown = set(camera) - set(CAMERA_OVERRIDE_KEYS)
    if unknown:
        raise ValueError(f"Expected options['camera'] keys in {CAMERA_OVERRIDE_KEYS}, found unknown {sorted(unknown)}")
    out: dict = {}
    for key in ("position", "look_at"):
        if key in camera:
            v = np.asarray(camera[key], dtype=np.float64)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"Expected options['camera']['{key}'] as 3 finite numbers, found {camera[key]!r}")
            out[key] = v
    if "fov_y_deg" in camera:
        f = float(camera["fov_y_deg"])
        if not (math.isfinite(f) and 0.0 < f < 180.0):
            raise ValueError(f"Expected options['camera']['fov_y_deg'] in (0, 180), found {camera['fov_y_deg']!r}")
        out["fov_y_deg"] = f
    if "position" in out and "look_at" in out and np.linalg.norm(out["position"] - out["look_at"]) < 1e-9:
        raise ValueError("Expected options['camera'] position and look_at to differ, found the same point")
    return out


@dataclass
class TaskView:
    """What the task sees of a rendered step: the task camera and its instance map [H, W]."""

    camera: Camera
    instance: np.ndarray
    t: float


@dataclass
class Evaluation:
    """A step's outcome: reward (the sum of `terms`), success, termination, and measurements."""

    reward: float
    terms: dict[str, float]
    success: bool
    terminate: bool = False
    metrics: dict[str, Any] = field(default_factory=dict)


class Task:
    """Base of the task kinds: everything the env calls on a task is declared here.

    Subclasses set the class attributes and implement `make_rig`, `initialize_episode`,
    `measure` and `evaluate`; the env hands `measure` and `evaluate` the task camera's view of
    the step it rendered (`TaskView`), so a task never renders and never reads the env.

    Attributes:
        kind: the task kind ("track", "reach", "find"), matched against the env's.
        task_camera: the rig camera whose view (`TaskView`) the task measures.
        default_cameras: the observed cameras when the env's `cameras` is None.
        render_agent: whether the rig's own geoms are drawn when the env's `render_agent` is None.
        PARAMS: defaults of every tunable number, overridable from YAML `params` or keywords.
    """

    kind = ""
    task_camera = ""
    default_cameras: tuple[str, ...] = ()
    render_agent = False
    PARAMS: dict[str, float] = {}

    def __init__(self, spec: TaskSpec | str | Mapping[str, Any], **params: float) -> None:
        self.spec = load_task_spec(spec)
        if self.spec.kind != self.kind:
            raise ValueError(f"Expected a task spec of kind {self.kind!r}, found {self.spec.kind!r}")
        merged = dict(self.PARAMS)
        for source, values in (("params", self.spec.params), ("keyword", params)):
            unknown = set(values) - set(self.PARAMS)
            if unknown:
                raise ValueError(f"Expected {self.kind} task parameters in {sorted(self.PARAMS)}, found unknown "
                                 f"{sorted(unknown)} ({source})")
            for k, v in values.items():
                try:
                    merged[k] = float(v)
                except (TypeError, ValueError) as exc:
                    raise ValueError(f"Expected a number for task parameter {k!r}, found {v!r}") from exc
                if not math.isfinite(merged[k]):
                    raise ValueError(f"Expected a finite number for task parameter {k!r}, found {v!r}")
        self.params = merged
        self._validate_params()

    def _validate_params(self) -> None:
        """Subclasses check ranges of their parameters."""

    # --------------------------------------------------------------- scenes
    def make_rig(self) -> "Rig":
        """A fresh rig for this task (one per env)."""
        raise NotImplementedError

    def sample_scene(self, rng: np.random.Generator) -> SceneRequest:
        """A draw from the task's scene distribution."""
        return self.spec.scenes.sample(rng)

    def resolve_target(self, scene: "Scene4D", name: str | None = None) -> "SceneObject":
        """The target object: `name` (an object's name or category) or, when None, the first moving
        object (else the first non-background object). `ValueError` if the scene has no such object."""
        candidates = [o for o in scene.objects if o.role != "background"]
        if name is not None:
            for o in candidates:
                if o.name == name:
                    return o
            for o in candidates:
                if o.category == name:
                    return o
            raise ValueError(f"Expected the prompt to name the target {name!r}, found objects "
                             f"{[o.name for o in candidates]} (prompt: {scene.provenance.prompt!r})")
        if not candidates:
            raise ValueError(f"Expected the prompt to describe at least one object to be the target, found only "
                             f"the setting {[o.name for o in scene.objects]} (prompt: {scene.provenance.prompt!r})")
        moving = [o for o in candidates if o.dynamic]
        return (moving or candidates)[0]

    def instruction(self, description: str) -> str:
        """The instruction text for a target description ("red ball")."""
        return self.spec.instruction.replace("{target}", description)

    # -------------------------------------------------------------- episode
    def initialize_episode(self, world: Any, rig: Any, rng: np.random.Generator, camera: Mapping[str, Any]) -> None:
        """Place the rig relative to the scene and draw its start state (all randomness from `rng`)."""
        raise NotImplementedError

    def change_view(self, world: Any, rig: Any, fov_ratio: float, shift: np.ndarray) -> None:
        """Follow a mid-episode edit of the scene's generation camera ("widen the field of view",
        "raise the camera by 0.5 metres"): scale the observing camera's field of view by `fov_ratio`
        and move it by `shift` (metres, world frame). A task without it refuses such edits."""
        raise ValueError(f"Expected a task that follows mid-episode camera edits, found {type(self).__name__} "
                         f"without change_view (apply the edit at reset instead)")

    def measure(self, world: Any, rig: Any, view: TaskView) -> dict[str, Any]:
        """Task measurements of the current state, from the world, the rig and the view the env
        just rendered (no reward, no bookkeeping)."""
        raise NotImplementedError

    def evaluate(self, world: Any, rig: Any, view: TaskView, action: np.ndarray) -> Evaluation:
        """Reward terms, success and termination after a step, from the view the env rendered after
        applying `action` (updates episode statistics)."""
        raise NotImplementedError

    def get_state(self) -> dict[str, Any]:
        """A copy of the task's episode state (its attributes; the spec and parameters, which an
        episode never changes, are shared), for `set_state` to return to."""
        shared = {"spec", "params"}
        return copy.deepcopy({k: v for k, v in vars(self).items() if k not in shared})

    def set_state(self, state: Mapping[str, Any]) -> None:
        """Return to a `get_state` result of this task (the state stays usable for further calls)."""
        vars(self).update(copy.deepcopy(dict(state)))

    def reset_metrics(self) -> dict[str, Any]:
        """Episode statistics as they stand at reset (merged into the reset info after `measure`);
        none by default."""
        return {}

    def reward_range(self) -> tuple[float, float]:
        """(min, max) of the reward."""
        return (-float(self.params.get("ctrl_cost", 0.0)), 1.0)

    @staticmethod
    def ctrl_term(action: np.ndarray, cost: float) -> float:
        """-cost * mean(action^2), in [-cost, 0] for actions in [-1, 1]."""
        a = np.asarray(action, dtype=np.float64)
        if a.ndim == 1 and 0 < a.size < 8:       # numpy's mean sums fewer than 8 values in order from 0.0
            total = 0.0
            for x in a.tolist():
                total += x * x
            return -float(cost) * (total / a.size)
        return -float(cost) * float(np.mean(a * a)) if a.size else 0.0

    @staticmethod
    def pixel_offset(camera: Camera, point: np.ndarray | None) -> tuple[float, float]:
        """(normalised distance of a world point's projection from the image centre, camera depth).

        The distance is measured in half-image units per axis (1 = the image border); a point
        behind the camera or missing gets 4.0."""
        if point is None:
            return 4.0, 0.0
        u, v, z = camera.project_point(point)
        if not z > camera.near:
            return 4.0, z
        dx = (u - camera.width / 2) / (camera.width / 2)
        dy = (v - camera.height / 2) / (camera.height / 2)
        return min(math.hypot(dx, dy), 4.0), z

    @staticmethod
    def mask_stats(instance: np.ndarray, object_id: int) -> tuple[int, float, float]:
        """(pixel count, normalised centroid distance from the image centre, area fraction) of an object
        in an instance map; distance 4.0 when the object is not visible."""
        mask = instance == object_id
        count = int(np.count_nonzero(mask))
        h, w = instance.shape
        if count == 0:
            return 0, 4.0, 0.0
        rows, cols = np.nonzero(mask)
        dx = (cols.mean() + 0.5 - w / 2) / (w / 2)
        dy = (rows.mean() + 0.5 - h / 2) / (h / 2)
        return count, float(math.hypot(dx, dy)), count / float(h * w)
