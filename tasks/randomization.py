"""Domain randomisation over the perturbation axes: which axes an episode gets, from declared distributions.

A randomisation file (`tasks/randomization/*.yaml`, or any path) looks like:

```yaml
name: track_train
max_axes: 3                       # at most this many axes per episode (default: no limit)
held_out: [occlusion, swap_target, sensor_jpeg]   # never sampled: kept for evaluation
axes:
  target_size:                    # a registry axis (tasks.axes.AXES)
    p: 0.3                        # chance per episode
    edits: "make the {target} {factor} times as big"      # optional: the axis's sentence with parameters
    params: {factor: {uniform: [0.5, 2.0]}}              # a parameter: uniform [lo, hi] or choice [...]
  light_dim: {p: 0.3, edits: "make the light {word}", params: {word: {choice: [brighter, dimmer]}}}
  recolor_target: {p: 0.3}        # the registry's own sentence
  camera_shift: {p: 0.2, params: {orbit_deg: {uniform: [-30, 30]}}}   # the camera axis: its shift's keys
```

`sample_axes(config, rng, values)` is a pure function of the generator and the scene's template
values (`tasks.axes.template_values`): the axes drawn in the file's order (each with its `p`, at
most `max_axes`), their edit sentences, the camera shift, and the axes skipped because they do
not apply to the scene (with the reason). `envs.AxisRandomization` runs it at every reset, seeded
by the episode seed.
"""

from __future__ import annotations

import math
import string
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Optional

import numpy as np

from .axes import AXES, TEMPLATE_FIELDS, AxisNotApplicable, fill_templates

__all__ = ["AxisDraw", "Randomization", "RandomizationDraw", "load_randomization", "sample_axes",
           "RANDOMIZATION_DIR"]

RANDOMIZATION_DIR = Path(__file__).resolve().parent / "randomization"
_KEYS = ("name", "description", "max_axes", "held_out", "axes")
_AXIS_KEYS = ("p", "edits", "params")
_CAMERA_PARAMS = ("orbit_deg", "pitch_deg", "distance_scale")


@dataclass(frozen=True)
class AxisDraw:
    """One axis's distribution: probability `p`, sentence templates, parameter distributions
    (name -> ("uniform", (lo, hi)) or ("choice", values))."""

    name: str
    p: float
    edits: tuple[str, ...]
    params: Mapping[str, tuple[str, tuple]] = field(default_factory=dict)
    camera: Optional[Mapping[str, float]] = None


@dataclass(frozen=True)
class Randomization:
    """A randomisation file (see the module docstring)."""

    name: str
    axes: tuple[AxisDraw, ...]
    held_out: tuple[str, ...] = ()
    max_axes: Optional[int] = None
    description: str = ""


@dataclass(frozen=True)
class RandomizationDraw:
    """What one episode got: the axes applied, their sentences, the camera shift, and the skipped axes."""

    axes: tuple[str, ...]
    edits: tuple[str, ...]
    camera: Mapping[str, float]
    params: Mapping[str, Mapping[str, Any]]
    skipped: Mapping[str, str]

    def to_info(self) -> dict:
        """A plain dict for `info["randomization"]`."""
        return {"axes": list(self.axes), "edits": list(self.edits), "camera": dict(self.camera),
                "params": {k: dict(v) for k, v in self.params.items()}, "skipped": dict(self.skipped)}


def _fail(msg: str, source: str) -> ValueError:
    return ValueError(f"{msg} in randomisation {source}")


def _param(name: str, spec: Any, where: str, source: str) -> tuple[str, tuple]:
    if not isinstance(spec, Mapping) or len(spec) != 1 or next(iter(spec)) not in ("uniform", "choice"):
        raise _fail(f"Expected {where}.params.{name} as {{uniform: [lo, hi]}} or {{choice: [...]}}, found {spec!r}",
                    source)
    kind, v = next(iter(spec.items()))
    if not isinstance(v, list) or not v:
        raise _fail(f"Expected a non-empty list for {where}.params.{name}.{kind}, found {v!r}", source)
    if kind == "uniform":
        if len(v) != 2 or not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                                  for x in v) or v[0] > v[1]:
            raise _fail(f"Expected {where}.params.{name}.uniform as [lo, hi] with lo <= hi, found {v!r}", source)
    return kind, tuple(v)


def _axis(name: Any, d: Any, source: str) -> AxisDraw:
    where = f"axes.{name}"
    if name not in AXES:
        raise _fail(f"Unknown axis {name!r}; known axes: {list(AXES)}", source)
    d = {} if d is None else d
    if not isinstance(d, Mapping) or set(d) - set(_AXIS_KEYS):
        raise _fail(f"Expected {where} as a mapping with keys among {list(_AXIS_KEYS)}, found {d!r}", source)
    p = d.get("p", 1.0)
    if isinstance(p, bool) or not isinstance(p, (int, float)) or not 0.0 <= p <= 1.0:
        raise _fail(f"Expected {where}.p in [0, 1], found {p!r}", source)
    axis = AXES[name]
    edits = d.get("edits", axis.edits)
    edits = (edits,) if isinstance(edits, str) else tuple(edits)
    params = {k: _param(k, v, where, source) for k, v in dict(d.get("params") or {}).items()}
    if axis.camera is not None:
        bad = sorted(set(params) - set(_CAMERA_PARAMS))
        if bad:
            raise _fail(f"Expected {where}.params among {list(_CAMERA_PARAMS)} for a camera axis, found {bad[0]!r}",
                        source)
    for e in edits:
        for _, fld, _, _ in string.Formatter().parse(e):
            if fld is not None and fld not in TEMPLATE_FIELDS and fld not in params:
                raise _fail(f"Unknown field {{{fld}}} in {where}.edits {e!r}; known: {list(TEMPLATE_FIELDS)} and "
                            f"the axis's params", source)
    return AxisDraw(name, float(p), edits, params, None if axis.camera is None else dict(axis.camera))


def load_randomization(source: str | Path | Mapping[str, Any]) -> Randomization:
    """A `Randomization` from a built-in name ("track"), a YAML path or a mapping; `ValueError` naming the key."""
    where = "<mapping>"
    if not isinstance(source, Mapping):
        from morphosim_gym.config_yaml import load_yaml_file

        path = Path(str(source))
        if not path.suffix and (RANDOMIZATION_DIR / f"{source}.yaml").exists():
            path = RANDOMIZATION_DIR / f"{source}.yaml"
        if not path.is_file():
            raise ValueError(f"Expected a built-in randomisation name or a YAML file, found {str(source)!r}")
        where, source = str(path), load_yaml_file(path)
    d = source
    if not isinstance(d, Mapping) or set(d) - set(_KEYS) or "axes" not in d:
        raise _fail(f"Expected a mapping with keys among {list(_KEYS)} and 'axes', found "
                    f"{sorted(d) if isinstance(d, Mapping) else type(d).__name__}", where)
    if not isinstance(d["axes"], Mapping) or not d["axes"]:
        raise _fail("Expected 'axes' as a non-empty mapping of axis name -> distribution", where)
    axes = tuple(_axis(k, v, where) for k, v in d["axes"].items())
    held = tuple(d.get("held_out") or ())
    unknown = [h for h in held if h not in AXES]
    if unknown:
        raise _fail(f"Unknown held-out axis {unknown[0]!r}", where)
    both = [a.name for a in axes if a.name in held]
    if both:
        raise _fail(f"Expected held-out axes to be left out of 'axes', found {both[0]!r} in both", where)
    m = d.get("max_axes")
    if m is not None and (isinstance(m, bool) or not isinstance(m, int) or m < 1):
        raise _fail(f"Expected max_axes as an integer >= 1, found {m!r}", where)
    return Randomization(str(d.get("name", "randomization")), axes, held, m, str(d.get("description", "")))


def _draw(kind: str, values: tuple, rng: np.random.Generator) -> Any:
    if kind == "uniform":
        return round(float(rng.uniform(values[0], values[1])), 2)
    return values[int(rng.integers(len(values)))]


def sample_axes(config: Randomization, rng: np.random.Generator,
                values: Mapping[str, Optional[str]]) -> RandomizationDraw:
    """One episode's draw (see the module docstring). Every axis consumes the same random numbers
    whether or not it applies, so one axis's applicability never shifts another's draw."""
    names: list[str] = []
    edits: list[str] = []
    camera: dict[str, float] = {}
    params: dict[str, dict[str, Any]] = {}
    skipped: dict[str, str] = {}
    for axis in config.axes:
        fire = bool(rng.random() < axis.p)
        drawn = {k: _draw(kind, v, rng) for k, (kind, v) in axis.params.items()}
        if not fire or (config.max_axes is not None and len(names) >= config.max_axes):
            continue
        if axis.camera is not None:
            camera.update(dict(axis.camera, **{k: float(v) for k, v in drawn.items()}))
        else:
            try:
                texts = fill_templates(axis.name, axis.edits, dict(values, **{k: str(v) for k, v in drawn.items()}))
            except AxisNotApplicable as exc:
                skipped[axis.name] = str(exc)
                continue
            edits.extend(texts)
        names.append(axis.name)
        params[axis.name] = drawn
    return RandomizationDraw(tuple(names), tuple(edits), camera, params, skipped)
