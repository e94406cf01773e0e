"""Benchmark suites as data: a base task and scene distribution, named perturbations, seeds.

A suite file (`tasks/suites/*.yaml`, or any path) looks like:

```yaml
name: track
env: MorphoSim/Track-v0          # which env runs the episodes
task: track                      # optional: the base task (built-in name or YAML path); default the env's
scenes: {...}                    # optional: the scene distribution, as in a task file (default the task's)
env_kwargs: {width: 64}          # optional: keyword arguments of the env (not sim/prompt/target/scene_seed)
world: {reconstruction: fit, reconstruction_config: fast}   # optional: the worlds (default: the envs'
                                 # ground truth, envs.config.DEFAULT_SIM_CONFIG); also `generation:
                                 # {num_frames: 25, width: 64, height: 64}` over the envs' clip settings
seed: 0                          # episode seeds are seed, seed + 1, ..., seed + episodes - 1
episodes: 20
frames: 4                        # frames kept for the report's strips (first seed only; 0 = none)
perturbations:
  - name: recolor_target
    edits: "make the {target} {new_color}"        # one language edit or a list of them
  - name: reverse_target
    edits: ["reverse the motion of the {target}"]
    at: 20                                        # before the 20th step (0 = at reset, the default)
  - name: camera_shift
    camera: {orbit_deg: 25}                       # relative to the scene: the reset camera option (at: k moves it before step k)
  - axis: target_size                             # an axis of the registry (`tasks.axes.AXES`); keys given
    at: 10                                        # here (name, edits, at, camera) override the axis's
axes: all                                         # optional: one perturbation per registry axis (or a list
                                                  # of names), before `perturbations` (then optional)
```

Every episode of a perturbation is paired with the unperturbed ("base") episode of the same
seed: same prompt, scene seed, reset seed and policy seed. Edit texts are templates:
`{target}` ("red ball"), `{target_noun}`, `{target_color}`, `{distractor}` (the first other
object, "blue cube"), `{distractor_noun}`, `{new_color}` (a colour no object of the scene has),
`{ground}` (the ground's name), `{swap_noun}` (a shape the target is not); see `tasks.axes`.

Errors: an unknown or invalid top-level key is a `SuiteError` naming the key and the file
(nothing runs); an invalid perturbation entry is kept with its `error`, so the runner records
each of its episodes as failed with that text and the sweep goes on.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import string
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional

from morphosim_gym.envs import ENTRY_POINTS, env_id_of
from morphosim_gym.limits import EPISODE_PLAN_BYTES, MAX_EPISODES, format_bytes
from morphosim_gym.tasks import TASK_DIR, TaskSpec, load_task_spec
from morphosim_gym.tasks.axes import AXES, TEMPLATE_FIELDS

__all__ = ["Suite", "Perturbation", "CameraShift", "SuiteError", "load_suite", "builtin_suite_names", "SUITE_DIR",
           "ENV_TASKS", "TEMPLATE_FIELDS", "BASE", "WORLD_KEYS", "world_sim_config"]

SUITE_DIR = TASK_DIR / "suites"
BASE = "base"
ENV_TASKS = {env_id_of(kind): kind for kind in ENTRY_POINTS}      # env id -> the task kind it runs
SUITE_KEYS = ("name", "env", "description", "task", "scenes", "env_kwargs", "world", "seed", "episodes", "frames",
              "axes", "perturbations")
WORLD_KEYS = ("reconstruction", "reconstruction_config", "generation")
PERTURBATION_KEYS = ("name", "axis", "description", "edits", "at", "camera")
CAMERA_KEYS = ("orbit_deg", "pitch_deg", "distance_scale", "fov_y_deg")
RESERVED_ENV_KWARGS = ("sim", "prompt", "target", "scene_seed", "scene_pool", "task", "render_mode", "on_edit_error",
                       "disable_env_checker")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")


class SuiteError(ValueError):
    """A suite file that cannot be run (the message names the key and the file)."""


@dataclass(frozen=True)
class CameraShift:
    """Move the env's camera relative to the scene's generation camera (the reset `camera` option at
    reset; `MorphoSimEnv.move_camera` mid-episode, by the same offset from the generation camera).

    Attributes:
        orbit_deg: yaw about the vertical axis through the scene centre, degrees.
        pitch_deg: then pitch about the camera's own x axis through the scene centre, degrees.
        distance_scale: then scale the distance to the scene centre.
        fov_y_deg: a new vertical field of view (None keeps the task's).
    """

    orbit_deg: float = 0.0
    pitch_deg: float = 0.0
    distance_scale: float = 1.0
    fov_y_deg: Optional[float] = None

    @property
    def moves(self) -> bool:
        """Whether the camera position changes (else only the field of view)."""
        return self.orbit_deg != 0.0 or self.pitch_deg != 0.0 or self.distance_scale != 1.0


@dataclass(frozen=True)
class Perturbation:
    """One named counterfactual: language edits (at reset or before a step) and/or a camera shift.

    Attributes:
        name: unique within the suite, not "base".
        edits: edit command templates, applied in order.
        at: 0 = at reset (before the first observation); k >= 1 = just before the k-th step.
        camera: a camera shift (at reset for at: 0, else just before the at-th step), or None.
        description: free text.
        error: why the entry is invalid (its episodes are recorded as failed), or None.
    """

    name: str
    edits: tuple[str, ...] = ()
    at: int = 0
    camera: Optional[CameraShift] = None
    description: str = ""
    error: Optional[str] = None


@dataclass(frozen=True)
class Suite:
    """A benchmark suite (see the module docstring). `perturbations` excludes the implicit base."""

    name: str
    env_id: str
    task: TaskSpec
    seed: int
    episodes: int
    perturbations: tuple[Perturbation, ...]
    env_kwargs: Mapping[str, Any] = field(default_factory=dict)
    frames: int = 4
    description: str = ""
    source: str = "<mapping>"
    world: Mapping[str, Any] = field(default_factory=dict)

    @property
    def seeds(self) -> list[int]:
        """The episode seeds."""
        return list(range(self.seed, self.seed + self.episodes))

    @property
    def conditions(self) -> list[Perturbation]:
        """The base condition followed by the perturbations."""
        return [Perturbation(BASE)] + list(self.perturbations)

    def perturbation(self, name: str) -> Perturbation:
        """The condition of this name ("base" included)."""
        for p in self.conditions:
            if p.name == name:
                return p
        raise ValueError(f"Expected a perturbation of suite {self.name!r}, found {name!r}; "
                         f"known: {[p.name for p in self.conditions]}")

    def with_episodes(self, episodes: int) -> "Suite":
        """The same suite with another episode count."""
        from dataclasses import replace

        return replace(self, episodes=_episodes(episodes, self.source, 1 + len(self.perturbations)))

    def with_world(self, **world: Any) -> "Suite":
        """The same suite in other worlds (`world` keys: reconstruction, reconstruction_config,
        generation; None values are left out)."""
        from dataclasses import replace

        merged = {**self.world, **{k: v for k, v in world.items() if v is not None}}
        return replace(self, world=_world(merged, self.source))

    def digest(self) -> str:
        """A content hash of everything that decides what an episode of a given seed is (not the file
        path, nor which seeds run: a sweep resumed with more episodes keeps the ones it has)."""
        data = {"name": self.name, "env": self.env_id, "task": _spec_dict(self.task),
                "env_kwargs": dict(self.env_kwargs), "frames": self.frames,
                "perturbations": [asdict(p) for p in self.perturbations]}
        if self.world:                         # absent for the default worlds: older digests still hold
            data["world"] = dict(self.world)
        return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _spec_dict(spec: TaskSpec) -> dict:
    return {"name": spec.name, "kind": spec.kind, "scenes": asdict(spec.scenes), "instruction": spec.instruction,
            "params": dict(spec.params)}


# ------------------------------------------------------------------ loading
def builtin_suite_names() -> list[str]:
    """Names of the suites that ship with the package (`tasks/suites/*.yaml`)."""
    return sorted(p.stem for p in SUITE_DIR.glob("*.yaml"))


def load_suite(source: str | Path | Mapping[str, Any]) -> Suite:
    """A `Suite` from a built-in name ("smoke"), a YAML path or a mapping; `SuiteError` on bad keys."""
    if isinstance(source, Mapping):
        return _suite_from_dict(source, "<mapping>", Path.cwd())
    from morphosim_gym.config_yaml import ConfigError, load_yaml_file

    text = str(source)
    path = Path(text)
    if not path.suffix and (SUITE_DIR / f"{text}.yaml").exists():
        path = SUITE_DIR / f"{text}.yaml"
    if not path.is_file():
        raise SuiteError(f"Expected a built-in suite name in {builtin_suite_names()} or a suite YAML file, "
                         f"found {text!r}")
    try:
        data = load_yaml_file(path)
    except ConfigError as exc:
        raise SuiteError(str(exc)) from None
    return _suite_from_dict(data, str(path), path.parent)


def _suite_from_dict(d: Any, source: str, base_dir: Path) -> Suite:
    if not isinstance(d, Mapping):
        raise SuiteError(f"Expected a suite to be a mapping, found {type(d).__name__} in {source}")
    unknown = sorted(set(d) - set(SUITE_KEYS))
    if unknown:
        raise SuiteError(f"Unknown key {unknown[0]!r} in suite {source}; expected keys among {list(SUITE_KEYS)}")
    for key in ("name", "env") + (() if "axes" in d else ("perturbations",)):
        if key not in d:
            raise SuiteError(f"Expected key {key!r} in suite {source}, found keys {sorted(d)}")
    name = str(d["name"])
    if not _NAME.match(name):
        raise SuiteError(f"Expected 'name' of letters, digits, '_', '.', '-' in suite {source}, found {name!r}")
    env_id = d["env"]
    if not isinstance(env_id, str) or env_id not in ENV_TASKS:
        raise SuiteError(f"Expected 'env' in {list(ENV_TASKS)} in suite {source}, found {env_id!r}")
    task = _task(d.get("task"), d.get("scenes"), env_id, source, base_dir)
    env_kwargs = d.get("env_kwargs") or {}
    if not isinstance(env_kwargs, Mapping):
        raise SuiteError(f"Expected 'env_kwargs' to be a mapping in suite {source}, found {env_kwargs!r}")
    reserved = sorted(set(env_kwargs) & set(RESERVED_ENV_KWARGS))
    if reserved:
        raise SuiteError(f"Expected env_kwargs without {reserved[0]!r} (the runner sets it) in suite {source}")
    perts = d.get("perturbations", [])
    if not isinstance(perts, list):
        raise SuiteError(f"Expected 'perturbations' to be a list in suite {source}, found {type(perts).__name__}")
    perts = _axis_entries(d.get("axes"), source) + perts
    items = tuple(_perturbation(p, i, source) for i, p in enumerate(perts))
    names = [p.name for p in items]
    for i, p in enumerate(items):
        if p.name in names[:i]:
            raise SuiteError(f"Expected unique perturbation names in suite {source}, found {p.name!r} twice")
    frames = d.get("frames", 4)
    if isinstance(frames, bool) or not isinstance(frames, int) or not 0 <= frames <= 12:
        raise SuiteError(f"Expected 'frames' as an integer in [0, 12] in suite {source}, found {frames!r}")
    return Suite(name=name, env_id=env_id, task=task, seed=_nonneg_int(d.get("seed", 0), "seed", source),
                 episodes=_episodes(d.get("episodes", 10), source, 1 + len(items)), perturbations=items,
                 env_kwargs=dict(env_kwargs), frames=frames, description=str(d.get("description", "")),
                 source=source, world=_world(d.get("world") or {}, source))


def _world(w: Any, source: str) -> dict[str, Any]:
    """A suite's `world` mapping, checked (the `SimConfig` it makes is built the same way)."""
    if not isinstance(w, Mapping):
        raise SuiteError(f"Expected 'world' to be a mapping with keys among {list(WORLD_KEYS)} in suite {source}, "
                         f"found {w!r}")
    unknown = sorted(set(w) - set(WORLD_KEYS))
    if unknown:
        raise SuiteError(f"Unknown key {unknown[0]!r} in 'world' of suite {source}; expected keys among "
                         f"{list(WORLD_KEYS)}")
    out = dict(w)
    if "generation" in out:
        if not isinstance(out["generation"], Mapping):
            raise SuiteError(f"Expected world.generation as a mapping of GenerationConfig fields in suite {source}, "
                             f"found {out['generation']!r}")
        out["generation"] = dict(out["generation"])
    try:
        world_sim_config(out)
    except (TypeError, ValueError) as exc:
        raise SuiteError(f"Invalid 'world' in suite {source}: {exc}") from None
    return out


def world_sim_config(world: Mapping[str, Any]) -> Any:
    """The `SimConfig` of a suite's worlds: `envs.config.DEFAULT_SIM_CONFIG` with `world` over it."""
    from dataclasses import replace

    from morphosim_gym.envs.config import DEFAULT_SIM_CONFIG
    from morphosim_gym.reconstruct.presets import resolve_reconstruction_config

    cfg = DEFAULT_SIM_CONFIG
    if "generation" in world:
        cfg = replace(cfg, generation=replace(cfg.generation, **world["generation"]))
    cfg = replace(cfg, **{k: v for k, v in world.items() if k != "generation"})
    if cfg.reconstruction == "fit":
        resolve_reconstruction_config(cfg.reconstruction_config)
    return cfg


def _task(task: Any, scenes: Any, env_id: str, source: str, base_dir: Path) -> TaskSpec:
    kind = ENV_TASKS[env_id]
    ref = kind if task is None else task
    if isinstance(ref, str) and (ref.endswith(".yaml") or ref.endswith(".yml")) and not Path(ref).is_absolute():
        ref = str(base_dir / ref)
    try:
        spec = load_task_spec(ref)
    except ValueError as exc:
        raise SuiteError(f"Invalid 'task' in suite {source}: {exc}") from None
    if spec.kind != kind:
        raise SuiteError(f"Expected a task of kind {kind!r} for {env_id} in suite {source}, found {spec.kind!r}")
    if scenes is None:
        return spec
    try:
        data = dict(_spec_dict(spec), scenes=scenes, description=spec.description)
        return TaskSpec.from_dict(data, source=f"{source} (scenes)")
    except (ValueError, TypeError) as exc:
        raise SuiteError(f"Invalid 'scenes' in suite {source}: {exc}") from None


def _axis_entries(axes: Any, source: str) -> list[dict]:
    """The perturbation entries of a suite's `axes` key ("all", or a list of registry names)."""
    if axes is None:
        return []
    names = list(AXES) if axes == "all" else axes
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise SuiteError(f"Expected 'axes' as 'all' or a list of axis names in suite {source}, found {axes!r}")
    unknown = [n for n in names if n not in AXES]
    if unknown:
        raise SuiteError(f"Unknown axis {unknown[0]!r} in suite {source}; known axes: {list(AXES)}")
    return [{"axis": n} for n in names]


def _with_axis(p: Mapping[str, Any], where: str) -> Mapping[str, Any]:
    """An entry with `axis: NAME` completed from the registry (the entry's own keys win)."""
    name = p.get("axis")
    if name is None:
        return p
    axis = AXES.get(name) if isinstance(name, str) else None
    if axis is None:
        raise SuiteError(f"Unknown axis {name!r} in {where}; known axes: {list(AXES)}")
    base: dict[str, Any] = {"name": axis.name, "description": axis.description, "at": axis.at}
    if axis.edits:
        base["edits"] = list(axis.edits)
    if axis.camera is not None:
        base["camera"] = dict(axis.camera)
    base.update({k: v for k, v in p.items() if k != "axis"})
    return base


def _perturbation(p: Any, index: int, source: str) -> Perturbation:
    """A perturbation entry; an invalid one comes back with its `error` set (named if possible)."""
    key = "name" if isinstance(p, Mapping) and p.get("name") is not None else "axis"
    name = str(p.get(key)) if isinstance(p, Mapping) and p.get(key) is not None else f"perturbation_{index}"
    try:
        return _check_perturbation(p, index, source)
    except SuiteError as exc:
        return Perturbation(name if _NAME.match(name) and name != BASE else f"perturbation_{index}", error=str(exc))


def _check_perturbation(p: Any, index: int, source: str) -> Perturbation:
    where = f"perturbations[{index}] of suite {source}"
    if not isinstance(p, Mapping):
        raise SuiteError(f"Expected {where} to be a mapping, found {p!r}")
    unknown = sorted(set(p) - set(PERTURBATION_KEYS))
    if unknown:
        raise SuiteError(f"Unknown key {unknown[0]!r} in {where}; expected keys among {list(PERTURBATION_KEYS)}")
    p = _with_axis(p, where)
    name = p.get("name")
    if not isinstance(name, str) or not _NAME.match(name) or name == BASE:
        raise SuiteError(f"Expected 'name' (letters, digits, '_', '.', '-'; not 'base') in {where}, found {name!r}")
    edits = p.get("edits", ())
    edits = (edits,) if isinstance(edits, str) else edits
    if not isinstance(edits, (list, tuple)) or not all(isinstance(e, str) and e.strip() for e in edits):
        raise SuiteError(f"Expected 'edits' as an edit command or a list of them in {where}, found {edits!r}")
    for e in edits:
        for _, fld, _, _ in string.Formatter().parse(e):
            if fld is not None and fld not in TEMPLATE_FIELDS:
                raise SuiteError(f"Unknown template field {{{fld}}} in edit {e!r} of {where}; known fields: "
                                 f"{list(TEMPLATE_FIELDS)}")
    at = p.get("at", 0)
    if isinstance(at, bool) or not isinstance(at, int) or at < 0:
        raise SuiteError(f"Expected 'at' as a step number >= 0 in {where}, found {at!r}")
    camera = _camera(p["camera"], where) if p.get("camera") is not None else None
    if not edits and camera is None:
        raise SuiteError(f"Expected 'edits' or 'camera' in {where}, found neither")
    return Perturbation(name, tuple(edits), at, camera, str(p.get("description", "")))


def _camera(c: Any, where: str) -> CameraShift:
    if not isinstance(c, Mapping):
        raise SuiteError(f"Expected 'camera' to be a mapping with keys among {list(CAMERA_KEYS)} in {where}, "
                         f"found {c!r}")
    unknown = sorted(set(c) - set(CAMERA_KEYS))
    if unknown:
        raise SuiteError(f"Unknown key {unknown[0]!r} in 'camera' of {where}; expected keys among {list(CAMERA_KEYS)}")
    values: dict[str, float] = {}
    for key, v in c.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise SuiteError(f"Expected camera.{key} as a finite number in {where}, found {v!r}")
        values[key] = float(v)
    if values.get("distance_scale", 1.0) <= 0:
        raise SuiteError(f"Expected camera.distance_scale > 0 in {where}, found {values['distance_scale']}")
    if "fov_y_deg" in values and not 0 < values["fov_y_deg"] < 180:
        raise SuiteError(f"Expected camera.fov_y_deg in (0, 180) in {where}, found {values['fov_y_deg']}")
    return CameraShift(**values)


def _nonneg_int(v: Any, key: str, source: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 0:
        raise SuiteError(f"Expected {key!r} as an integer >= 0 in suite {source}, found {v!r}")
    return v


def _positive_int(v: Any, key: str, source: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise SuiteError(f"Expected {key!r} as an integer >= 1 in suite {source}, found {v!r}")
    return v


def _episodes(v: Any, source: str, conditions: int) -> int:
    """An episode count in [1, MAX_EPISODES]; the error states what a larger sweep would hold in memory."""
    n = _positive_int(v, "episodes", source)
    if n > MAX_EPISODES:
        planned = n * conditions
        raise SuiteError(f"Expected 'episodes' as an integer in [1, {MAX_EPISODES}] in suite {source}, found {n}: "
                         f"{planned} planned episodes ({conditions} conditions) would need "
                         f"{format_bytes(planned * EPISODE_PLAN_BYTES)} of bookkeeping before the first one ran")
    return n
