"""`Plan`: the structured, validated output of the command parameterizer (paper: P = (M, Q)).

A plan is JSON both ways (`Plan.to_dict`, `Plan.from_dict`, `Plan.to_json`, `Plan.from_json`);
`from_dict` validates and says which key is wrong. All dataclasses are frozen; sequences are tuples.

Modes
-----
- ``generate``: `objects`, `motions` (at most one per object), `camera`, `setting`.
- ``edit``: `edits`, an ordered list of `EditOp` applied one after the other.
- A compound command ("a red cube moves to the plate ...; then make the cube blue") is the plan of
  its first segment with the follow-up edit plans in `then`, in order (flat: a plan in `then` has an
  empty `then` itself and is always an edit plan).

Conventions (the generation camera looks along world +y from the -y side, level)
--------------------------------------------------------------------------------
- World frame z-up, metres. Image right = world +x, image up = world +z.
- ``direction_world``: unit 3-vector in the world, or None when the text gives no direction (a
  motion "to the plate" gets its direction from where the generator places the plate).
  left (-1,0,0), right (1,0,0), up (0,0,1), down (0,0,-1), towards the camera (0,-1,0), away from
  the camera (0,1,0), north +y, east +x, south -y, west -x; combinations are normalised.
- ``direction_image``: the direction as seen by the generation camera, image x right, y DOWN, unit
  length, or (0, 0) when the motion is along the view axis. ``direction_depth``: the component
  along the view axis of the unit world direction (+1 away from the camera, -1 towards it). So
  (direction_image scaled by its share, direction_depth) is the direction in the camera's OpenCV
  frame; "towards the camera" is image (0, 0), depth -1; "upwards" is image (0, -1), depth 0.
  Both are derived from ``direction_world`` (never set them by hand).
- ``clockwise`` (circle paths, camera orbits): as seen from above (+z) looking down.
- Speeds are factors, 1.0 = normal; see `SPEED_WORDS` in `morphosim_gym.language.lexicon`.

Recolour parameters (what the editor applies to each selected Gaussian colour c in [0, 1]):
- ``assign``: ``color.rgb`` -> c' = rgb.
- ``additive``: ``delta`` (3 numbers in [-1, 1]) -> c' = clip(c + delta, 0, 1); ``color`` names the
  colour added or taken away ("redder": red, delta = 0.3 * rgb(red)).
- ``multiplicative``: ``factor_rgb`` (3 numbers > 0) -> c' = clip(c * factor_rgb, 0, 1).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar, Mapping, Sequence

from ..colors import color_rgb
from ..errors import CommandError
from .open_vocab import is_open_category
from .vocabulary import CATEGORIES, SETTINGS

__all__ = ["MODES", "PATHS", "CAMERA_MOTIONS", "CAMERA_DIRECTIONS", "EDIT_OPS", "RECOLOR_MODES", "MAX_COUNT",
           "ColorSpec", "ObjectSpec", "MotionSpec", "CameraSpec", "Target", "EditOp", "RecolorOp", "RemoveOp",
           "ExtractOp", "ReverseOp", "RedirectOp", "SpeedOp", "StopOp", "CameraOp", "ScaleOp", "SwapOp", "InsertOp",
           "LightOp", "SkyOp", "TextureOp", "SettingOp", "ViewOp", "SensorOp", "DelayOp", "LIGHT_MODES", "SKY_NAMES",
           "TEXTURE_PATTERNS", "INSERT_RELATIONS", "SENSOR_EFFECTS", "EDIT_KINDS", "EDIT_KEYS",
           "edit_op", "Plan", "world_to_image"]

MODES = ("generate", "edit")
PATHS = ("straight", "bounce", "circle", "zigzag", "oscillate", "stop")
CAMERA_MOTIONS = ("fixed", "orbit", "pan", "dolly")
CAMERA_DIRECTIONS: dict[str, tuple[str | None, ...]] = {
    "fixed": (None,), "orbit": (None, "clockwise", "counterclockwise"), "pan": (None, "left", "right"),
    "dolly": (None, "in", "out"),
}
EDIT_OPS = ("recolor", "remove", "extract", "reverse", "redirect", "speed", "stop", "camera", "scale", "swap", "insert",
            "light", "sky", "texture", "setting", "view", "sensor", "delay")
# Scene-wide and object-level perturbation vocabularies (the axis edits' fields).
LIGHT_MODES = ("brightness", "temperature", "direction")
SKY_NAMES = ("clear", "sunset", "overcast", "night", "dawn")
TEXTURE_PATTERNS = ("checkered", "striped", "dotted", "metallic", "matte", "glossy", "noisy")
INSERT_RELATIONS = ("next_to", "occluding", "behind", "in_front")
SENSOR_EFFECTS = ("noise", "blur", "jpeg")
RECOLOR_MODES = ("assign", "additive", "multiplicative")
GROUNDINGS = ("vocabulary", "embedding", "open", "kind", "given")   # "kind": a stand-in of the same kind
MAX_COUNT = 20
MAX_SPEED = 10.0

Vec3 = tuple[float, float, float]


def _err(path: str, expected: str, found: Any) -> CommandError:
    return CommandError(f"Invalid plan: expected {path} to be {expected}, found {found!r}")


def _num(v: Any, path: str, lo: float | None = None, hi: float | None = None, open_lo: bool = False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(float(v)):
        raise _err(path, "a finite number", v)
    v = float(v)
    if lo is not None and (v < lo or (open_lo and v <= lo)):
        raise _err(path, f"a number {'>' if open_lo else '>='} {lo}", v)
    if hi is not None and v > hi:
        raise _err(path, f"a number <= {hi}", v)
    return v


def _str(v: Any, path: str, choices: Sequence[Any] | None = None, optional: bool = False) -> str | None:
    if v is None and optional:
        return None
    if not isinstance(v, str) or not v.strip():
        raise _err(path, "a non-empty string" + (" or null" if optional else ""), v)
    if choices is not None and v not in choices:
        raise _err(path, f"one of {[c for c in choices if c is not None]}", v)
    return v


def _vec(v: Any, path: str, n: int, lo: float = -math.inf, hi: float = math.inf) -> tuple[float, ...]:
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise _err(path, f"a list of {n} numbers", v)
    out = tuple(_num(x, f"{path}[{i}]") for i, x in enumerate(v))
    if any(x < lo or x > hi for x in out):
        raise _err(path, f"{n} numbers in [{lo}, {hi}]", list(v))
    return out


def _unit(v: Any, path: str) -> Vec3 | None:
    if v is None:
        return None
    x = _vec(v, path, 3)
    norm = math.sqrt(sum(c * c for c in x))
    if norm < 1e-6:
        raise _err(path, "a non-zero direction vector or null", list(v))
    return tuple(round(c / norm, 6) + 0.0 for c in x)


def world_to_image(d: Vec3 | None) -> tuple[tuple[float, float], float]:
    """``(direction_image, direction_depth)`` of a unit world direction for the generation camera.

    Image x = world x, image y (down) = -world z, depth (forward) = world y.
    """
    if d is None:
        return (0.0, 0.0), 0.0
    ix, iy, depth = d[0], -d[2], d[1]
    n = math.hypot(ix, iy)
    if n < 1e-6:
        return (0.0, 0.0), round(depth, 6) + 0.0
    return (round(ix / n, 6) + 0.0, round(iy / n, 6) + 0.0), round(depth, 6) + 0.0


def _check_keys(d: Any, cls: type, path: str) -> Mapping[str, Any]:
    if not isinstance(d, Mapping):
        raise _err(path, "an object (dict)", d)
    allowed = {f.name for f in fields(cls)}
    for k in d:
        if k not in allowed:
            raise CommandError(f"Invalid plan: unknown key {path}.{k}; expected keys of {cls.__name__}: "
                               f"{sorted(allowed)}")
    return d


def _plain(v: Any) -> Any:
    if isinstance(v, tuple):
        return [_plain(x) for x in v]
    if hasattr(v, "to_dict"):
        return v.to_dict()
    return v


class _Spec:
    """Shared JSON helpers for the plan dataclasses."""

    def to_dict(self) -> dict:
        """JSON-friendly form (tuples become lists, nested specs become dicts)."""
        return {f.name: _plain(getattr(self, f.name)) for f in fields(self)}  # type: ignore[arg-type]


@dataclass(frozen=True)
class ColorSpec(_Spec):
    """A colour: canonical name ("red", "lightblue", "pale red") and RGB in [0, 1]."""

    name: str
    rgb: Vec3

    def __post_init__(self) -> None:
        _str(self.name, "color.name")
        object.__setattr__(self, "rgb", _vec(self.rgb, "color.rgb", 3, 0.0, 1.0))

    @classmethod
    def from_name(cls, name: str) -> "ColorSpec":
        """The colour of a name such as "navy" or "light red"; CommandError if unknown."""
        try:
            return cls(name, color_rgb(name))
        except ValueError as exc:
            raise CommandError(str(exc)) from None

    @classmethod
    def from_dict(cls, d: Any, path: str = "color") -> "ColorSpec":
        d = _check_keys(d, cls, path)
        name = _str(d.get("name"), f"{path}.name")
        if d.get("rgb") is None:
            try:
                return cls(name, color_rgb(name))
            except ValueError:
                raise _err(f"{path}.name", "a known colour name (or give rgb)", name) from None
        return cls(name, _vec(d["rgb"], f"{path}.rgb", 3, 0.0, 1.0))


@dataclass(frozen=True)
class ObjectSpec(_Spec):
    """An object to generate.

    Attributes:
        name: unique within the plan, what motions and edits refer to: the noun, then "ball_2"...
            for a second object with the same noun.
        noun: the noun as written, singular ("sedan", "ball").
        category: the generator category it is grounded to ("car").
        color: requested colour, or None.
        size: size word as written ("small", "very large"), or None.
        scale: size factor from the size word (1.0 = normal).
        count: how many instances (from "two balls", "a herd of sheep"...).
        grounding: "vocabulary" (rule table), "embedding" (nearest category by MiniLM), "open" (a basic
            shape or real asset by MiniLM, see `open_vocab`) or "given".
        similarity: cosine similarity of the embedding grounding, else None.
    """

    name: str
    noun: str
    category: str
    color: ColorSpec | None = None
    size: str | None = None
    scale: float = 1.0
    count: int = 1
    grounding: str = "vocabulary"
    similarity: float | None = None

    def __post_init__(self) -> None:
        _str(self.name, "object.name")
        _str(self.noun, "object.noun")
        open_cat = isinstance(self.category, str) and is_open_category(self.category)
        _str(self.category, "object.category", None if open_cat else list(CATEGORIES))
        _str(self.size, "object.size", optional=True)
        object.__setattr__(self, "scale", _num(self.scale, "object.scale", 0.0, 10.0, open_lo=True))
        if isinstance(self.count, bool) or not isinstance(self.count, int) or not 1 <= self.count <= MAX_COUNT:
            raise _err("object.count", f"an integer in [1, {MAX_COUNT}]", self.count)
        _str(self.grounding, "object.grounding", GROUNDINGS)
        if self.similarity is not None:
            object.__setattr__(self, "similarity", _num(self.similarity, "object.similarity", -1.0, 1.0))

    @classmethod
    def from_dict(cls, d: Any, path: str = "object") -> "ObjectSpec":
        d = _check_keys(d, cls, path)
        color = d.get("color")
        noun = d.get("noun") or d.get("name")
        kw = dict(name=d.get("name") or noun, noun=noun, category=d.get("category"),
                  color=None if color is None else ColorSpec.from_dict(color, f"{path}.color"),
                  size=d.get("size"), scale=d.get("scale", 1.0), count=d.get("count", 1),
                  grounding=d.get("grounding", "given"), similarity=d.get("similarity"))
        return _build(cls, kw, path)


@dataclass(frozen=True)
class MotionSpec(_Spec):
    """How one object moves during the generated clip.

    Attributes:
        target: the `ObjectSpec.name` that moves (all its instances).
        path: one of `PATHS`: "straight", "bounce" (hops along the direction, or in place),
            "circle" (around `around`, or a loop), "zigzag", "oscillate" (back and forth along the
            direction), "stop" (stays still).
        direction_world: unit world vector or None (see module docstring).
        speed: speed factor (1.0 = normal); speed_word: the words it came from, or None.
        start, end: names of objects of the plan the motion starts at / heads to, or None.
        around: name of the object a circle path goes around, or None.
        clockwise: for circle paths, True/False as seen from above, None if unspecified.
        direction_image, direction_depth: derived from direction_world (not init arguments).
    """

    target: str
    path: str = "straight"
    direction_world: Vec3 | None = None
    speed: float = 1.0
    speed_word: str | None = None
    start: str | None = None
    end: str | None = None
    around: str | None = None
    clockwise: bool | None = None
    direction_image: tuple[float, float] = field(init=False)
    direction_depth: float = field(init=False)

    def __post_init__(self) -> None:
        _str(self.target, "motion.target")
        _str(self.path, "motion.path", PATHS)
        object.__setattr__(self, "direction_world", _unit(self.direction_world, "motion.direction_world"))
        object.__setattr__(self, "speed", _num(self.speed, "motion.speed", 0.0, MAX_SPEED, open_lo=True))
        for name in ("speed_word", "start", "end", "around"):
            _str(getattr(self, name), f"motion.{name}", optional=True)
        if self.clockwise is not None and not isinstance(self.clockwise, bool):
            raise _err("motion.clockwise", "true, false or null", self.clockwise)
        if self.clockwise is not None and self.path != "circle":
            raise _err("motion.clockwise", "null unless path is 'circle'", self.clockwise)
        if self.path == "stop" and (self.direction_world is not None or self.end is not None):
            raise CommandError("Invalid plan: a 'stop' motion has no direction or end")
        if self.start is not None and self.start == self.end:
            raise CommandError(f"Invalid plan: motion of {self.target!r} starts and ends at {self.start!r}")
        img, depth = world_to_image(self.direction_world)
        object.__setattr__(self, "direction_image", img)
        object.__setattr__(self, "direction_depth", depth)

    @classmethod
    def from_dict(cls, d: Any, path: str = "motion") -> "MotionSpec":
        d = _check_keys(d, cls, path)
        kw = {k: v for k, v in d.items() if k not in ("direction_image", "direction_depth")}
        return _build(cls, kw, path)


@dataclass(frozen=True)
class CameraSpec(_Spec):
    """The generation camera's motion, or a camera change in an edit.

    Attributes:
        motion: "fixed", "orbit" (circles the scene centre or `target`), "pan" (turns in place),
            "dolly" (moves along its view axis; "zoom" words map here).
        direction: orbit "clockwise"/"counterclockwise" (seen from above), pan "left"/"right",
            dolly "in"/"out"; None when unspecified (the generator chooses).
        speed: factor (1.0 = normal); speed_word: its words or None.
        target: name of an object of the plan the camera circles or looks at; None = the scene centre
            (also when the text names the setting: "circles the table" on a tabletop).
    """

    motion: str = "fixed"
    direction: str | None = None
    speed: float = 1.0
    speed_word: str | None = None
    target: str | None = None

    def __post_init__(self) -> None:
        _str(self.motion, "camera.motion", CAMERA_MOTIONS)
        if self.direction not in CAMERA_DIRECTIONS[self.motion]:
            raise _err("camera.direction", f"one of {CAMERA_DIRECTIONS[self.motion]} for a '{self.motion}' camera",
                       self.direction)
        object.__setattr__(self, "speed", _num(self.speed, "camera.speed", 0.0, MAX_SPEED, open_lo=True))
        _str(self.speed_word, "camera.speed_word", optional=True)
        _str(self.target, "camera.target", optional=True)

    @classmethod
    def from_dict(cls, d: Any, path: str = "camera") -> "CameraSpec":
        return _build(cls, dict(_check_keys(d, cls, path)), path)


@dataclass(frozen=True)
class Target(_Spec):
    """What an edit applies to.

    Attributes:
        text: the words as written ("the vehicle", "it", "the fish").
        noun: singular noun ("vehicle"), "*" for everything, "camera" for the camera.
        category: grounded category (a category, a setting name such as "water", "camera"), or None
            for "*".
        objects: names of the objects it resolved to: scene objects when a scene was given, the
            plan's objects in a compound command, () otherwise.
        object_ids: ids of those scene objects (their `.id`, else their index in ``scene.objects``);
            () without a scene.
        color: a colour qualifier ("the red ball"), or None.
    """

    text: str
    noun: str
    category: str | None = None
    objects: tuple[str, ...] = ()
    object_ids: tuple[int, ...] = ()
    color: ColorSpec | None = None

    def __post_init__(self) -> None:
        _str(self.text, "target.text")
        _str(self.noun, "target.noun")
        _str(self.category, "target.category", optional=True)
        if not isinstance(self.objects, (tuple, list)) or not all(isinstance(o, str) for o in self.objects):
            raise _err("target.objects", "a list of object names", self.objects)
        object.__setattr__(self, "objects", tuple(self.objects))
        if not isinstance(self.object_ids, (tuple, list)) or not all(
                isinstance(i, int) and not isinstance(i, bool) for i in self.object_ids):
            raise _err("target.object_ids", "a list of integers", self.object_ids)
        object.__setattr__(self, "object_ids", tuple(self.object_ids))

    @classmethod
    def from_dict(cls, d: Any, path: str = "target") -> "Target":
        if isinstance(d, str):  # shorthand: a noun
            return cls(text=d, noun=d)
        d = dict(_check_keys(d, cls, path))
        d.setdefault("text", d.get("noun"))
        d.setdefault("noun", d.get("text"))
        if d.get("color") is not None:
            d["color"] = ColorSpec.from_dict(d["color"], f"{path}.color")
        return _build(cls, d, path)


# Every key an edit's dict form has, in order: `to_dict` writes them all (null where a kind has no such
# field) so that one JSON layout serves every kind, and `from_dict` accepts them all.
EDIT_KEYS = ("op", "targets", "mode", "color", "delta", "factor_rgb", "direction_world", "path", "end", "around",
             "clockwise", "factor", "speed", "speed_word", "camera", "category", "relation", "name", "amount",
             "seconds", "direction_image", "direction_depth")
_ABSENT: dict[str, Any] = {"direction_image": (0.0, 0.0), "direction_depth": 0.0}


@dataclass(frozen=True)
class EditOp(_Spec):
    """Base of the edit operations: one frozen dataclass per kind (`RecolorOp`, `RemoveOp`, ...).

    Attributes:
        op: the kind's name, one of `EDIT_OPS` (a class attribute).
        targets: what it applies to (empty only for a `CameraOp`).

    Build one by kind (`RemoveOp(targets=...)`) or by name (`edit_op("remove", targets=...)`,
    `EditOp.from_dict(d)`). `to_dict` writes every key of `EDIT_KEYS` (null where the kind has no
    such field).
    """

    op: ClassVar[str] = ""
    needs_targets: ClassVar[bool] = True
    targets: tuple[Target, ...] = ()

    def __post_init__(self) -> None:
        if type(self) is EditOp:
            raise CommandError(f"Invalid plan: EditOp is the base of the edit kinds; build one of {list(EDIT_OPS)} "
                               f"with edit_op(name, ...)")
        if not isinstance(self.targets, (tuple, list)) or not all(isinstance(t, Target) for t in self.targets):
            raise _err("edit.targets", "a list of targets", self.targets)
        object.__setattr__(self, "targets", tuple(self.targets))
        if self.needs_targets and not self.targets:
            raise _err("edit.targets", f"at least one target for op '{self.op}'", [])
        self._check()

    def _check(self) -> None:
        """Validate (and normalise) the kind's own fields."""

    def to_dict(self) -> dict:
        """The dict form: every key of `EDIT_KEYS`, null where this kind has no such field."""
        return {k: _plain(self.op if k == "op" else getattr(self, k, _ABSENT.get(k))) for k in EDIT_KEYS}

    @classmethod
    def from_dict(cls, d: Any, path: str = "edit") -> "EditOp":
        """Build and validate the edit of a dict (its ``op`` picks the kind)."""
        if not isinstance(d, Mapping):
            raise _err(path, "an object (dict)", d)
        for k in d:
            if k not in EDIT_KEYS:
                raise CommandError(f"Invalid plan: unknown key {path}.{k}; expected keys of EditOp: "
                                   f"{sorted(EDIT_KEYS)}")
        d = {k: v for k, v in d.items() if k not in _ABSENT}
        targets = d.get("targets", [])
        if not isinstance(targets, (list, tuple)):
            raise _err(f"{path}.targets", "a list", targets)
        d["targets"] = tuple(Target.from_dict(t, f"{path}.targets[{i}]") for i, t in enumerate(targets))
        if d.get("color") is not None:
            d["color"] = ColorSpec.from_dict(d["color"], f"{path}.color")
        if d.get("camera") is not None:
            d["camera"] = CameraSpec.from_dict(d["camera"], f"{path}.camera")
        return _build(edit_op, d, path)


@dataclass(frozen=True)
class RecolorOp(EditOp):
    """Change colours. mode "assign" (`color`), "additive" (`delta`, `color` names it) or
    "multiplicative" (`factor_rgb`); see the module docstring."""

    op: ClassVar[str] = "recolor"
    mode: str | None = None
    color: ColorSpec | None = None
    delta: Vec3 | None = None
    factor_rgb: Vec3 | None = None

    def _check(self) -> None:
        _str(self.mode, "edit.mode", RECOLOR_MODES, optional=True)
        if self.mode is None:
            raise _err("edit.mode", f"one of {list(RECOLOR_MODES)} for op 'recolor'", None)
        if self.mode == "assign" and self.color is None:
            raise _err("edit.color", "a colour for an 'assign' recolour", None)
        if self.mode == "additive" and self.delta is None:
            raise _err("edit.delta", "3 numbers for an 'additive' recolour", None)
        if self.mode == "multiplicative" and self.factor_rgb is None:
            raise _err("edit.factor_rgb", "3 numbers for a 'multiplicative' recolour", None)
        if self.delta is not None:
            object.__setattr__(self, "delta", _vec(self.delta, "edit.delta", 3, -1.0, 1.0))
        if self.factor_rgb is not None:
            f = _vec(self.factor_rgb, "edit.factor_rgb", 3, 0.0, 100.0)
            if min(f) <= 0:
                raise _err("edit.factor_rgb", "3 numbers > 0", list(f))
            object.__setattr__(self, "factor_rgb", f)


@dataclass(frozen=True)
class RemoveOp(EditOp):
    """Delete the targets from the scene."""

    op: ClassVar[str] = "remove"


@dataclass(frozen=True)
class ExtractOp(EditOp):
    """Keep only the targets."""

    op: ClassVar[str] = "extract"


@dataclass(frozen=True)
class ReverseOp(EditOp):
    """Play the targets' motion backwards."""

    op: ClassVar[str] = "reverse"


@dataclass(frozen=True)
class StopOp(EditOp):
    """Freeze the targets at their first pose."""

    op: ClassVar[str] = "stop"


def _check_speed(op: Any, required: bool) -> None:
    """`factor` (relative) and `speed` (absolute) in (0, MAX_SPEED]; exactly one when `required`."""
    if op.factor is not None:
        object.__setattr__(op, "factor", _num(op.factor, "edit.factor", 0.0, MAX_SPEED, open_lo=True))
    if op.speed is not None:
        object.__setattr__(op, "speed", _num(op.speed, "edit.speed", 0.0, MAX_SPEED, open_lo=True))
    if required and (op.factor is None) == (op.speed is None):
        raise CommandError("Invalid plan: a 'speed' edit has exactly one of factor and speed")
    _str(op.speed_word, "edit.speed_word", optional=True)


@dataclass(frozen=True)
class RedirectOp(EditOp):
    """A new direction and/or path shape and/or an object to head to (`end`) or circle (`around`);
    optionally a speed change too (`factor` or `speed`). direction_image/direction_depth are derived."""

    op: ClassVar[str] = "redirect"
    direction_world: Vec3 | None = None
    path: str | None = None
    end: str | None = None
    around: str | None = None
    clockwise: bool | None = None
    factor: float | None = None
    speed: float | None = None
    speed_word: str | None = None
    direction_image: tuple[float, float] = field(init=False)
    direction_depth: float = field(init=False)

    def _check(self) -> None:
        object.__setattr__(self, "direction_world", _unit(self.direction_world, "edit.direction_world"))
        _str(self.path, "edit.path", PATHS, optional=True)
        _str(self.end, "edit.end", optional=True)
        _str(self.around, "edit.around", optional=True)
        if self.clockwise is not None and not isinstance(self.clockwise, bool):
            raise _err("edit.clockwise", "true, false or null", self.clockwise)
        if self.direction_world is None and self.path is None and self.end is None and self.around is None:
            raise CommandError("Invalid plan: a 'redirect' edit needs a direction, a path or an end")
        _check_speed(self, required=False)
        img, depth = world_to_image(self.direction_world)
        object.__setattr__(self, "direction_image", img)
        object.__setattr__(self, "direction_depth", depth)


@dataclass(frozen=True)
class SpeedOp(EditOp):
    """Change speed: a relative `factor` ("twice as fast" 2.0) or an absolute `speed` from an adverb
    ("move slowly" 0.5, `speed_word` its words); exactly one of the two."""

    op: ClassVar[str] = "speed"
    factor: float | None = None
    speed: float | None = None
    speed_word: str | None = None

    def _check(self) -> None:
        _check_speed(self, required=True)


@dataclass(frozen=True)
class CameraOp(EditOp):
    """A new camera motion (`camera`); no targets."""

    op: ClassVar[str] = "camera"
    needs_targets: ClassVar[bool] = False
    camera: CameraSpec | None = None

    def _check(self) -> None:
        if self.targets or not isinstance(self.camera, CameraSpec):
            raise CommandError("Invalid plan: a 'camera' edit has a camera and no targets")


# -- perturbation axes: object size, swap, insertion, lighting, sky, texture, setting, view, sensor, delay -----
@dataclass(frozen=True)
class ScaleOp(EditOp):
    """Resize the targets about their base point by `factor` ("twice as big" 2.0)."""

    op: ClassVar[str] = "scale"
    factor: float = 1.0

    def _check(self) -> None:
        object.__setattr__(self, "factor", _num(self.factor, "edit.factor", 0.0, MAX_SPEED, open_lo=True))


@dataclass(frozen=True)
class SwapOp(EditOp):
    """Replace each target by a new object of `category` (optional `color`), same place, size and motion."""

    op: ClassVar[str] = "swap"
    category: str = ""
    color: ColorSpec | None = None

    def _check(self) -> None:
        if not self.category:
            raise _err("edit.category", "the category of the new object for op 'swap'", self.category)
        _str(self.category, "edit.category")


@dataclass(frozen=True)
class InsertOp(EditOp):
    """Add a static object of `category` (optional `color`) placed by `relation` to the targets (its anchors):
    "next_to" beside it, "occluding" between the generation camera and it, "behind" / "in_front" along the view."""

    op: ClassVar[str] = "insert"
    category: str = ""
    color: ColorSpec | None = None
    relation: str = "next_to"

    def _check(self) -> None:
        if not self.category:
            raise _err("edit.category", "the category of the new object for op 'insert'", self.category)
        _str(self.relation, "edit.relation", INSERT_RELATIONS)


@dataclass(frozen=True)
class LightOp(EditOp):
    """Change the light baked into every colour: mode "brightness" (`factor` > 0 multiplies), "temperature"
    (`amount` in [-1, 1]: < 0 cooler, > 0 warmer) or "direction" (`direction_world`, light coming from there)."""

    op: ClassVar[str] = "light"
    needs_targets: ClassVar[bool] = False
    mode: str = "brightness"
    factor: float | None = None
    amount: float | None = None
    direction_world: Vec3 | None = None

    def _check(self) -> None:
        _str(self.mode, "edit.mode", LIGHT_MODES)
        if self.mode == "brightness":
            object.__setattr__(self, "factor", _num(self.factor, "edit.factor", 0.0, 10.0, open_lo=True))
        elif self.mode == "temperature":
            object.__setattr__(self, "amount", _num(self.amount, "edit.amount", -1.0, 1.0))
        else:
            d = _unit(self.direction_world, "edit.direction_world")
            if d is None:
                raise _err("edit.direction_world", "a direction for a 'direction' light edit", None)
            object.__setattr__(self, "direction_world", d)


@dataclass(frozen=True)
class SkyOp(EditOp):
    """Show the named sky (one of `SKY_NAMES`) behind the scene."""

    op: ClassVar[str] = "sky"
    needs_targets: ClassVar[bool] = False
    name: str = "clear"

    def _check(self) -> None:
        _str(self.name, "edit.name", SKY_NAMES)


@dataclass(frozen=True)
class TextureOp(EditOp):
    """Give the targets a surface pattern or material (`name`, one of `TEXTURE_PATTERNS`)."""

    op: ClassVar[str] = "texture"
    name: str = ""

    def _check(self) -> None:
        _str(self.name, "edit.name", TEXTURE_PATTERNS)


@dataclass(frozen=True)
class SettingOp(EditOp):
    """Move the scene to another setting (`name`, one of `SETTINGS`): ground colour, backdrop and sky."""

    op: ClassVar[str] = "setting"
    needs_targets: ClassVar[bool] = False
    name: str = ""

    def _check(self) -> None:
        _str(self.name, "edit.name", tuple(SETTINGS))


@dataclass(frozen=True)
class ViewOp(EditOp):
    """Change the generation camera: field of view times `factor` and/or raise it by `amount` metres
    (looking at the same point)."""

    op: ClassVar[str] = "view"
    needs_targets: ClassVar[bool] = False
    factor: float | None = None
    amount: float | None = None

    def _check(self) -> None:
        if self.factor is None and self.amount is None:
            raise CommandError("Invalid plan: a 'view' edit has a field-of-view factor or a height change")
        if self.factor is not None:
            object.__setattr__(self, "factor", _num(self.factor, "edit.factor", 0.1, 3.0))
        if self.amount is not None:
            object.__setattr__(self, "amount", _num(self.amount, "edit.amount", -100.0, 100.0))


@dataclass(frozen=True)
class SensorOp(EditOp):
    """Degrade what the cameras record (`name`: "noise", "blur" or "jpeg") with strength `amount` in (0, 1];
    the scene carries it and `envs.SensorEffects` applies it to the observations."""

    op: ClassVar[str] = "sensor"
    needs_targets: ClassVar[bool] = False
    name: str = "noise"
    amount: float = 0.5

    def _check(self) -> None:
        _str(self.name, "edit.name", SENSOR_EFFECTS)
        object.__setattr__(self, "amount", _num(self.amount, "edit.amount", 0.0, 1.0, open_lo=True))


@dataclass(frozen=True)
class DelayOp(EditOp):
    """Shift the targets' motion in time: it starts `seconds` later (< 0: earlier), held at its ends."""

    op: ClassVar[str] = "delay"
    seconds: float = 0.0

    def _check(self) -> None:
        object.__setattr__(self, "seconds", _num(self.seconds, "edit.seconds", -3600.0, 3600.0))


EDIT_KINDS: dict[str, type[EditOp]] = {k.op: k for k in (RecolorOp, RemoveOp, ExtractOp, ReverseOp, RedirectOp,
                                                          SpeedOp, StopOp, CameraOp, ScaleOp, SwapOp, InsertOp,
                                                          LightOp, SkyOp, TextureOp, SettingOp, ViewOp, SensorOp,
                                                          DelayOp)}
_INIT_FIELDS = {k: frozenset(f.name for f in fields(k) if f.init) for k in EDIT_KINDS.values()}


def edit_op(op: Any, **fields_: Any) -> EditOp:
    """The edit of kind `op` (a name of `EDIT_OPS`) with the given fields; a field another kind has
    may be given as None (the dict form has them all), any other value is an error naming it."""
    kind = EDIT_KINDS[_str(op, "edit.op", EDIT_OPS)]  # type: ignore[index]
    own = _INIT_FIELDS[kind]
    for k, v in fields_.items():
        if k not in own:
            if k not in EDIT_KEYS:
                raise CommandError(f"Invalid plan: unknown key edit.{k}; expected keys of EditOp: {sorted(EDIT_KEYS)}")
            if v is not None:
                raise _err(f"edit.{k}", f"null for op '{op}'", v)
    return kind(**{k: v for k, v in fields_.items() if k in own})


@dataclass(frozen=True)
class Plan(_Spec):
    """A parsed command.

    Attributes:
        mode: "generate" or "edit".
        text: the command text this plan came from (its segment, for plans in `then`).
        objects, motions, camera, setting, setting_source: generate plans only. `setting` is one of
            `SETTINGS`; setting_source is "text" (named), "inferred" (an object's habitat) or
            "default".
        edits: edit plans only, in order.
        then: follow-up edit plans, applied in order after this plan.
        backend: "rules" or "llm": who produced it.
    """

    mode: str
    text: str = ""
    objects: tuple[ObjectSpec, ...] = ()
    motions: tuple[MotionSpec, ...] = ()
    camera: CameraSpec | None = None
    setting: str | None = None
    setting_source: str | None = None
    edits: tuple[EditOp, ...] = ()
    then: tuple["Plan", ...] = ()
    backend: str = "rules"

    def __post_init__(self) -> None:
        _str(self.mode, "plan.mode", MODES)
        if not isinstance(self.text, str):
            raise _err("plan.text", "a string", self.text)
        for name, cls in (("objects", ObjectSpec), ("motions", MotionSpec), ("edits", EditOp), ("then", Plan)):
            v = getattr(self, name)
            if not isinstance(v, (tuple, list)) or not all(isinstance(x, cls) for x in v):
                raise _err(f"plan.{name}", f"a list of {cls.__name__}", v)
            object.__setattr__(self, name, tuple(v))
        _str(self.backend, "plan.backend", ("rules", "llm"))
        known = self._check_generate() if self.mode == "generate" else self._check_edit()
        for i, p in enumerate(self.then):
            if p.mode != "edit" or p.then:
                raise _err(f"plan.then[{i}]", "an edit plan without its own 'then'", p.mode)
        if known is not None:  # targets of follow-up edits resolve to this plan's objects
            for i, p in enumerate(self.then):
                for e in p.edits:
                    for t in e.targets:
                        bad = [o for o in t.objects if o not in known]
                        if bad:
                            raise _err(f"plan.then[{i}] target objects", f"names of objects of the plan {sorted(known)}",
                                       bad)

    def _check_generate(self) -> set[str]:
        """Defaults and cross-references of a generate plan; the names of its objects."""
        if self.edits:
            raise CommandError("Invalid plan: a generate plan has no edits (put them in 'then')")
        if self.camera is None:
            object.__setattr__(self, "camera", CameraSpec())
        if self.setting is None:
            object.__setattr__(self, "setting", "ground")
            object.__setattr__(self, "setting_source", self.setting_source or "default")
        _str(self.setting, "plan.setting", list(SETTINGS))
        _str(self.setting_source, "plan.setting_source", ("text", "inferred", "default"), optional=True)
        if self.setting_source is None:
            object.__setattr__(self, "setting_source", "text")
        if not self.objects and self.setting_source != "text":
            raise CommandError("Invalid plan: a generate plan needs at least one object or a named setting")
        names = [o.name for o in self.objects]
        if len(set(names)) != len(names):
            raise _err("plan.objects", "objects with unique names", names)
        moved = [m.target for m in self.motions]
        if len(set(moved)) != len(moved):
            raise _err("plan.motions", "at most one motion per object", moved)
        for m in self.motions:
            for key in ("target", "start", "end", "around"):
                ref = getattr(m, key)
                if ref is not None and ref not in names:
                    raise _err(f"plan.motions[{m.target}].{key}", f"the name of an object of the plan {names}", ref)
        if self.camera.target is not None and self.camera.target not in names:
            raise _err("plan.camera.target", f"the name of an object of the plan {names} or null", self.camera.target)
        return set(names)

    def _check_edit(self) -> None:
        if self.objects or self.motions or self.camera is not None or self.setting is not None:
            raise CommandError("Invalid plan: an edit plan has only edits (no objects, motions, camera, setting)")
        if not self.edits:
            raise _err("plan.edits", "at least one edit for an edit plan", [])

    # -- JSON ---------------------------------------------------------------------------------

    def to_json(self, indent: int | None = 2) -> str:
        """The plan as a JSON string."""
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_json(cls, text: str) -> "Plan":
        """Parse and validate a plan from JSON text."""
        try:
            d = json.loads(text)
        except json.JSONDecodeError as exc:
            raise CommandError(f"Invalid plan: not JSON ({exc})") from None
        return cls.from_dict(d)

    @classmethod
    def from_dict(cls, d: Any, path: str = "plan") -> "Plan":
        """Build and validate a plan from its dict form; missing optional keys take defaults and
        derived keys (rgb of a named colour, direction_image) are recomputed."""
        d = dict(_check_keys(d, cls, path))

        def seq(key: str, conv: Any) -> tuple:
            v = d.get(key, [])
            if v is None:
                v = []
            if not isinstance(v, (list, tuple)):
                raise _err(f"{path}.{key}", "a list", v)
            return tuple(conv(x, f"{path}.{key}[{i}]") for i, x in enumerate(v))

        d["objects"] = seq("objects", ObjectSpec.from_dict)
        d["motions"] = seq("motions", MotionSpec.from_dict)
        d["edits"] = seq("edits", EditOp.from_dict)
        d["then"] = seq("then", Plan.from_dict)
        if d.get("camera") is not None:
            d["camera"] = CameraSpec.from_dict(d["camera"], f"{path}.camera")
        return _build(cls, d, path)

    # -- helpers for downstream code --------------------------------------------------------

    def object(self, name: str) -> ObjectSpec:
        """The object called `name`; KeyError if none."""
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(name)

    def motion_of(self, name: str) -> MotionSpec | None:
        """The motion of object `name`, or None when it is static."""
        for m in self.motions:
            if m.target == name:
                return m
        return None

    def all_edits(self) -> tuple[EditOp, ...]:
        """This plan's edits followed by those of every plan in `then`, in order."""
        return self.edits + tuple(e for p in self.then for e in p.edits)


def _build(cls: type, kw: dict, path: str) -> Any:
    try:
        return cls(**kw)
    except CommandError as exc:
        msg = str(exc)
        prefix = "Invalid plan: expected "
        if msg.startswith(prefix) and path:
            # name the full key path: "plan.objects[0].category" instead of "object.category"
            rest = msg[len(prefix):]
            key = rest.split(" ", 1)[0]
            if "." in key:
                rest = f"{path}.{key.split('.', 1)[1]} {rest.split(' ', 1)[1]}"
            raise CommandError(prefix + rest) from None
        raise
    except TypeError as exc:
        raise CommandError(f"Invalid plan at {path}: {exc}") from None
