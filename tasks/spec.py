"""Task specifications: what a task is, as data (loadable from YAML, so tasks need no code).

A YAML task file names the task `kind` (which logic and rig: "track", "reach" or "find"),
its scene distribution (a prompt template with word lists, sampled with the episode's
random generator), its instruction template and optional overrides of the kind's reward
and success parameters. See `tasks/track.yaml` for a commented example.

```yaml
name: track-balls
kind: track
scenes:
  prompt: "a {color} {object} {motion}"
  target: object                 # the field that names the target object
  fields:
    color: [red, blue]
    object: [ball]
    motion: ["moves from left to right", "bounces from right to left"]
instruction: "keep the {target} in the centre of the view"
params:
  success_fraction: 0.6
```
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

__all__ = ["SceneRequest", "DistractorSpec", "SceneDistribution", "TaskSpec", "TASK_KINDS", "TASK_DIR",
           "load_task_spec", "builtin_task_names"]

TASK_KINDS = ("track", "reach", "find")
TASK_DIR = Path(__file__).resolve().parent
_FIELD = re.compile(r"\{([a-zA-Z_][a-zA-Z0-9_]*)\}")
_ARTICLE = re.compile(r"\b([aA]) ([aeiouAEIOU])")


@dataclass(frozen=True)
class SceneRequest:
    """One draw from a scene distribution.

    Attributes:
        prompt: the text to generate.
        target: the name the target object gets in the scene (the noun as written).
        target_description: words for the target in instructions ("red ball").
        fields: the chosen word of every field.
    """

    prompt: str
    target: str
    target_description: str
    fields: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class DistractorSpec:
    """Other objects placed with the target ({distractors} in the prompt).

    Attributes:
        count: (min, max) number of distractors, inclusive.
        objects: nouns to draw from.
        colors: colour words to draw from.
    """

    count: tuple[int, int] = (2, 3)
    objects: tuple[str, ...] = ()
    colors: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        lo, hi = (int(x) for x in self.count)
        if not 0 <= lo <= hi <= 8:
            raise ValueError(f"Expected distractors.count (min, max) with 0 <= min <= max <= 8, found {self.count!r}")
        object.__setattr__(self, "count", (lo, hi))
        object.__setattr__(self, "objects", tuple(self.objects))
        object.__setattr__(self, "colors", tuple(self.colors))
        if hi > 0 and (not self.objects or not self.colors):
            raise ValueError("Expected distractors.objects and distractors.colors to be non-empty lists, found "
                             f"{len(self.objects)} objects and {len(self.colors)} colors")


@dataclass(frozen=True)
class SceneDistribution:
    """A prompt template and the words its fields are drawn from (uniformly, independently).

    Attributes:
        prompt: template with `{field}` slots; a field's words may contain slots themselves.
            `{distractors}` expands to "a blue cube and a green mug" from `distractors`.
        fields: field name -> words.
        target: the field whose word names the target object.
        target_color: the field with the target's colour word (used to describe it), or None.
        distractors: the distractor spec, if the template uses `{distractors}`.
    """

    prompt: str
    fields: Mapping[str, tuple[str, ...]]
    target: str = "object"
    target_color: str | None = "color"
    distractors: DistractorSpec | None = None

    def __post_init__(self) -> None:
        fields = {str(k): tuple(str(w) for w in v) for k, v in dict(self.fields).items()}
        for k, words in fields.items():
            if not words:
                raise ValueError(f"Expected at least one word for scenes.fields.{k}, found an empty list")
        object.__setattr__(self, "fields", fields)
        if self.target not in fields:
            raise ValueError(f"Expected scenes.target to name a field, found {self.target!r}; fields: {sorted(fields)}")
        if self.target_color is not None and self.target_color not in fields:
            raise ValueError(f"Expected scenes.target_color to name a field or be null, found {self.target_color!r}; "
                             f"fields: {sorted(fields)}")
        used = set(_FIELD.findall(self.prompt))
        for words in fields.values():
            for w in words:
                used |= set(_FIELD.findall(w))
        unknown = used - set(fields) - {"distractors"}
        if unknown:
            raise ValueError(f"Expected every {{slot}} of scenes.prompt to be a field, found unknown {sorted(unknown)}; "
                             f"fields: {sorted(fields)}")
        if "{distractors}" in self.prompt and self.distractors is None:
            raise ValueError("Expected a scenes.distractors section for a prompt with {distractors}, found none")
        if self.target not in used:
            raise ValueError(f"Expected the target field {{{self.target}}} to appear in scenes.prompt, found "
                             f"{self.prompt!r}")

    def sample(self, rng: np.random.Generator) -> SceneRequest:
        """Draw a prompt (all choices from `rng`, in a fixed order)."""
        chosen = {k: words[int(rng.integers(len(words)))] for k, words in sorted(self.fields.items())}
        target = chosen[self.target]
        color = chosen.get(self.target_color) if self.target_color else None
        values = dict(chosen)
        if self.distractors is not None and "{distractors}" in self.prompt:
            values["distractors"] = self._distractors(rng, target, color)
        text = self.prompt
        for _ in range(6):                     # fields may contain fields
            new = _FIELD.sub(lambda m: values.get(m.group(1), m.group(0)), text)
            if new == text:
                break
            text = new
        text = " ".join(text.split()).replace(" ,", ",").replace(" ;", ";")
        text = _ARTICLE.sub(lambda m: m.group(1) + "n " + m.group(2), text)      # "a orange" -> "an orange"
        description = f"{color} {target}" if color else target
        return SceneRequest(text, target, description, chosen)

    def _distractors(self, rng: np.random.Generator, target: str, color: str | None) -> str:
        d = self.distractors
        assert d is not None
        n = int(rng.integers(d.count[0], d.count[1] + 1))
        taken = {(color, target)}
        items = []
        for _ in range(n):
            for _attempt in range(50):
                pair = (d.colors[int(rng.integers(len(d.colors)))], d.objects[int(rng.integers(len(d.objects)))])
                if pair not in taken:
                    break
            else:
                continue
            taken.add(pair)
            items.append(f"a {pair[0]} {pair[1]}")
        if not items:
            return ""
        if len(items) == 1:
            return items[0]
        return ", ".join(items[:-1]) + " and " + items[-1]


@dataclass(frozen=True)
class TaskSpec:
    """A task as data.

    Attributes:
        name: the task's name.
        kind: "track", "reach" or "find" (which logic and rig).
        scenes: the scene distribution.
        instruction: template with `{target}` (the target's description).
        params: overrides of the kind's reward / success / start parameters (see each task's `PARAMS`).
        description: free text.
    """

    name: str
    kind: str
    scenes: SceneDistribution
    instruction: str = "{target}"
    params: Mapping[str, Any] = field(default_factory=dict)
    description: str = ""

    def __post_init__(self) -> None:
        if self.kind not in TASK_KINDS:
            raise ValueError(f"Expected kind in {TASK_KINDS}, found {self.kind!r}")
        if "{target}" not in self.instruction:
            raise ValueError(f"Expected instruction to contain {{target}}, found {self.instruction!r}")
        object.__setattr__(self, "params", dict(self.params))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], source: str = "task") -> "TaskSpec":
        """Build from a mapping (the YAML structure); errors name the offending key."""
        if not isinstance(d, Mapping):
            raise ValueError(f"Expected {source} to be a mapping, found {type(d).__name__}")
        known = {"name", "kind", "scenes", "instruction", "params", "description"}
        unknown = set(d) - known
        if unknown:
            raise ValueError(f"Expected keys of a task in {sorted(known)}, found unknown {sorted(unknown)} in {source}")
        for key in ("name", "kind", "scenes"):
            if key not in d:
                raise ValueError(f"Expected key {key!r} in {source}, found keys {sorted(d)}")
        s = d["scenes"]
        if not isinstance(s, Mapping):
            raise ValueError(f"Expected scenes to be a mapping in {source}, found {type(s).__name__}")
        _check_types(d, source)
        s_known = {"prompt", "fields", "target", "target_color", "distractors"}
        if set(s) - s_known:
            raise ValueError(f"Expected keys of scenes in {sorted(s_known)}, found unknown {sorted(set(s) - s_known)} "
                             f"in {source}")
        if "prompt" not in s or "fields" not in s:
            raise ValueError(f"Expected scenes.prompt and scenes.fields in {source}, found keys {sorted(s)}")
        dist = None
        if s.get("distractors") is not None:
            dd = s["distractors"]
            d_known = {"count", "objects", "colors"}
            if not isinstance(dd, Mapping) or set(dd) - d_known:
                raise ValueError(f"Expected scenes.distractors with keys {sorted(d_known)} in {source}, found {dd!r}")
            dist = DistractorSpec(**{k: (tuple(v) if isinstance(v, (list, tuple)) else v) for k, v in dd.items()})
        fields = s["fields"]
        if not isinstance(fields, Mapping):
            raise ValueError(f"Expected scenes.fields to be a mapping of lists in {source}, found {type(fields).__name__}")
        for k, v in fields.items():
            if not isinstance(v, (list, tuple)):
                raise ValueError(f"Expected scenes.fields.{k} to be a list of words in {source}, found {v!r}")
        scenes = SceneDistribution(str(s["prompt"]), {k: tuple("" if w is None else str(w) for w in v)
                                                      for k, v in fields.items()},
                                   str(s.get("target", "object")),
                                   s.get("target_color", "color"), dist)
        params = d.get("params") or {}
        if not isinstance(params, Mapping):
            raise ValueError(f"Expected params to be a mapping in {source}, found {type(params).__name__}")
        return cls(str(d["name"]), str(d["kind"]), scenes, str(d.get("instruction", "{target}")), dict(params),
                   str(d.get("description", "")))


# the type of every scalar a task file holds (key path -> kind of `config_yaml.expect`; "?" = or null)
_TYPES = {("name",): "text", ("kind",): "string", ("instruction",): "text", ("description",): "text",
          ("scenes", "prompt"): "text", ("scenes", "target"): "string", ("scenes", "target_color"): "string?",
          ("scenes", "distractors"): "mapping?", ("params",): "mapping?"}
_DISTRACTOR_TYPES = {"count": "list", "objects": "list", "colors": "list"}


def _check_types(d: Mapping[str, Any], source: str) -> None:
    """`ConfigError` ("<source>: key 'scenes.target': expected a string, found [1]") for a value of the
    wrong type, before any is used (a wrong type used to surface as a raw TypeError)."""
    from morphosim_gym.config_yaml import expect

    for keys, kind in _TYPES.items():
        parent: Any = d
        for k in keys[:-1]:
            parent = parent.get(k) if isinstance(parent, Mapping) else None
        if not isinstance(parent, Mapping) or keys[-1] not in parent:
            continue
        value = parent[keys[-1]]
        if not (kind.endswith("?") and value is None):
            expect(value, kind.rstrip("?"), ".".join(keys), source)
    dd = d["scenes"].get("distractors") or {}
    for k, kind in _DISTRACTOR_TYPES.items():
        if k in dd:
            expect(dd[k], kind, f"scenes.distractors.{k}", source)
    for i, v in enumerate(dd.get("count", ())):
        expect(v, "integer", f"scenes.distractors.count[{i}]", source)
    for k, v in (d.get("params") or {}).items():
        expect(v, "number", f"params.{k}", source)


def builtin_task_names() -> list[str]:
    """Names of the task files that ship with the package (`tasks/*.yaml`)."""
    return sorted(p.stem for p in TASK_DIR.glob("*.yaml"))


def load_task_spec(source: str | Path | Mapping[str, Any] | TaskSpec) -> TaskSpec:
    """A `TaskSpec` from a built-in name ("track"), a YAML path, a mapping, or a spec (returned as is)."""
    if isinstance(source, TaskSpec):
        return source
    if isinstance(source, Mapping):
        return TaskSpec.from_dict(source)
    from morphosim_gym.config_yaml import ConfigError, load_yaml_file

    text = str(source)
    path = Path(text)
    if not path.suffix and (TASK_DIR / f"{text}.yaml").exists():
        path = TASK_DIR / f"{text}.yaml"
    if not path.exists():
        raise ValueError(f"Expected a built-in task name in {builtin_task_names()} or a YAML file, found {text!r}")
    data = load_yaml_file(path)
    try:
        return TaskSpec.from_dict(data, source=str(path))
    except ValueError as exc:
        if str(path) in str(exc):
            raise
        raise ConfigError(f"{path}: {exc}") from None

