"""Optional LLM backend: any OpenAI-compatible chat-completions endpoint writes the `Plan` JSON.

Configuration (`LLMConfig`), from a YAML/dict config or the environment:

| key | environment | default | meaning |
|---|---|---|---|
| base_url | MORPHOSIM_LLM_BASE_URL | none | e.g. ``http://127.0.0.1:8000/v1`` (``/chat/completions`` is appended) |
| model | MORPHOSIM_LLM_MODEL | none | model name sent in the request |
| api_key | MORPHOSIM_LLM_API_KEY | none | sent as ``Authorization: Bearer ...`` when set |
| timeout_s | MORPHOSIM_LLM_TIMEOUT_S | 30 | wall clock of the whole parse: connecting, every read, every retry |
| fallback | MORPHOSIM_LLM_FALLBACK | "rules" | after a failure: "rules" (use the rule parser) or "raise" |
| max_retries | MORPHOSIM_LLM_MAX_RETRIES | 1 | extra attempts after an invalid answer, each told the validation error |
| temperature | | 0.0 | sampling temperature |

Flow: ask for JSON in the Plan schema (the prompt carries the schema, the vocabularies and an
example made by the rule parser, so it never drifts from the code) -> `Plan.from_dict` validates ->
edit targets are resolved against the scene like the rule parser's -> on a validation error, ask
again once with the error -> then fall back to the rules or raise `CommandError`. A network or HTTP
failure falls back too, or raises `BackendUnavailableError` with ``fallback="raise"``.

The endpoint is not trusted (see `http_client`): one deadline bounds the whole parse, replies
over 1 MiB are refused unread, malformed, binary, truncated, deeply nested or huge-number
replies are errors naming the problem (never a raw exception), and a long reply is not sent
back to the model on retry. Only the standard library is used (urllib).
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, fields, replace
from typing import Any, Mapping, Optional

from ..errors import BackendUnavailableError, CommandError
from .http_client import Deadline, loads_bounded, post_json
from .grounding import ALL_WORDS, ground_noun, resolve_in_scene, scene_items
from .plan import CAMERA_DIRECTIONS, EDIT_OPS, PATHS, RECOLOR_MODES, Plan
from .rules import EXAMPLES, parse_rules
from .vocabulary import CATEGORIES, SETTINGS

__all__ = ["LLMConfig", "parse_llm", "system_prompt", "chat"]

RESEND_CHARS = 8000      # a previous reply longer than this is not sent back to the model on retry
ERROR_CHARS = 300        # the validation error told to the model on retry is cut to this length

_ENV = {"base_url": "MORPHOSIM_LLM_BASE_URL", "model": "MORPHOSIM_LLM_MODEL", "api_key": "MORPHOSIM_LLM_API_KEY",
        "timeout_s": "MORPHOSIM_LLM_TIMEOUT_S", "fallback": "MORPHOSIM_LLM_FALLBACK",
        "max_retries": "MORPHOSIM_LLM_MAX_RETRIES"}


@dataclass(frozen=True)
class LLMConfig:
    """Where and how to ask an OpenAI-compatible endpoint (see the module docstring)."""

    base_url: str | None = None
    model: str | None = None
    api_key: str | None = None
    timeout_s: float = 30.0
    fallback: str = "rules"
    max_retries: int = 1
    temperature: float = 0.0

    def __post_init__(self) -> None:
        for name in ("base_url", "model", "api_key"):
            v = getattr(self, name)
            if v is not None and (not isinstance(v, str) or not v.strip()):
                raise ValueError(f"Expected llm.{name} as a non-empty string or null, found {v!r}")
        if self.base_url is not None and not re.match(r"^https?://", self.base_url):
            raise ValueError(f"Expected llm.base_url to start with http:// or https://, found {self.base_url!r}")
        try:
            t = float(self.timeout_s)
        except (TypeError, ValueError):
            raise ValueError(f"Expected llm.timeout_s as a number of seconds, found {self.timeout_s!r}") from None
        if not 0 < t <= 600:
            raise ValueError(f"Expected llm.timeout_s in (0, 600], found {self.timeout_s!r}")
        object.__setattr__(self, "timeout_s", t)
        if self.fallback not in ("rules", "raise"):
            raise ValueError(f"Expected llm.fallback 'rules' or 'raise', found {self.fallback!r}")
        try:
            r = int(self.max_retries)
        except (TypeError, ValueError):
            raise ValueError(f"Expected llm.max_retries as an integer, found {self.max_retries!r}") from None
        if not 0 <= r <= 5 or str(r) != str(self.max_retries).strip():
            raise ValueError(f"Expected llm.max_retries as an integer in [0, 5], found {self.max_retries!r}")
        object.__setattr__(self, "max_retries", r)
        if not isinstance(self.temperature, (int, float)) or not 0 <= self.temperature <= 2:
            raise ValueError(f"Expected llm.temperature in [0, 2], found {self.temperature!r}")

    @property
    def configured(self) -> bool:
        """Whether an endpoint and a model are set."""
        return bool(self.base_url and self.model)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> "LLMConfig":
        """Build from a config mapping (e.g. the ``llm:`` section of a YAML file); unknown keys are errors."""
        d = dict(d or {})
        allowed = {f.name for f in fields(cls)}
        for k in d:
            if k not in allowed:
                raise ValueError(f"Unknown key llm.{k}; expected one of {sorted(allowed)}")
        return cls(**d)

    @classmethod
    def from_yaml(cls, path: str) -> "LLMConfig":
        """Read the ``llm:`` section (or the whole file) of a YAML config."""
        from ..config_yaml import load_yaml_file

        data = load_yaml_file(path) or {}
        if not isinstance(data, dict):
            raise ValueError(f"Expected a mapping in {path}, found {type(data).__name__}")
        return cls.from_dict(data.get("llm", data))

    @classmethod
    def from_env(cls, environ: Mapping[str, str] | None = None, **overrides: Any) -> "LLMConfig":
        """Read MORPHOSIM_LLM_* variables; keyword arguments override them."""
        env = os.environ if environ is None else environ
        kw: dict[str, Any] = {}
        for key, var in _ENV.items():
            if env.get(var):
                kw[key] = env[var]
        kw.update(overrides)
        return cls(**kw)


def system_prompt() -> str:
    """The instructions sent to the model: schema, vocabularies, conventions and an example."""
    example = parse_rules("a red cube moves to the plate while the camera circles the table; then make the cube "
                          "blue and reverse its motion").to_dict()
    return (
        "You turn a user's command for a 4D scene simulator into JSON. Reply with ONE JSON object and nothing else.\n"
        "Schema (a Plan): {mode: 'generate'|'edit', text, objects: [ObjectSpec], motions: [MotionSpec], "
        "camera: CameraSpec|null, setting: str|null, edits: [EditOp], then: [Plan]}.\n"
        "ObjectSpec: {name (unique), noun (as written, singular), category, color: {name, rgb: [r,g,b] in 0..1}|null, "
        "size: str|null, scale: number, count: int}.\n"
        f"MotionSpec: {{target: object name, path: one of {list(PATHS)}, direction_world: unit [x,y,z] or null, "
        "speed: factor (1 normal, 0.5 slowly, 2 quickly, 0.2 at a crawl, 3 very fast), speed_word, start, end, around: "
        "object names or null, clockwise: bool|null}.\n"
        f"CameraSpec: {{motion: one of {list(CAMERA_DIRECTIONS)}, direction: {CAMERA_DIRECTIONS}, speed, target}}.\n"
        f"EditOp: {{op: one of {list(EDIT_OPS)}, targets: [{{text, noun}}], mode: one of {list(RECOLOR_MODES)} "
        "(recolor only), color, delta (additive), factor_rgb (multiplicative), direction_world, path, end, around, "
        "clockwise (redirect), factor (relative speed > 0) or speed (absolute), camera (op 'camera')}.\n"
        "World frame z-up; the camera looks along +y: left = [-1,0,0], right = [1,0,0], up = [0,0,1], down = "
        "[0,0,-1], towards the camera = [0,-1,0], away = [0,1,0], north = +y, east = +x.\n"
        f"Categories (use exactly these): {', '.join(CATEGORIES)}.\n"
        f"Settings: {', '.join(SETTINGS)}.\n"
        "A command that describes a scene is 'generate'; one that changes an existing scene is 'edit'. Follow-up "
        "edits of a compound command go in 'then' as edit plans. Objects that motions go to/from/around must be "
        "objects of the plan.\n"
        f"Example for 'a red cube moves to the plate while the camera circles the table; then make the cube blue "
        f"and reverse its motion':\n{json.dumps(example)}"
    )


def _user_message(text: str, scene: Any) -> str:
    msg = f"Command: {text}"
    if scene is not None:
        items = scene_items(scene)
        msg += "\nScene objects (edit targets must be among them): " + ", ".join(
            f"{it.name} ({it.category})" for it in items)
    return msg


def chat(config: LLMConfig, messages: list[dict], deadline: Optional[Deadline] = None) -> str:
    """One chat-completions request, within `deadline` (default: `config.timeout_s` from now);
    returns the message content.

    Raises:
        BackendUnavailableError: not configured, unreachable, too slow, HTTP error, or a reply that
            is not the expected JSON (the message says which).
    """
    if not config.configured:
        raise BackendUnavailableError("No LLM endpoint configured: set MORPHOSIM_LLM_BASE_URL and MORPHOSIM_LLM_MODEL "
                                      "(or llm.base_url / llm.model in the config)")
    url = config.base_url.rstrip("/") + "/chat/completions"
    body = {"model": config.model, "messages": messages, "temperature": config.temperature,
            "response_format": {"type": "json_object"}}
    headers = {"Authorization": f"Bearer {config.api_key}"} if config.api_key else {}
    payload = post_json(url, body, headers, deadline or Deadline(config.timeout_s))
    try:
        content = payload["choices"][0]["message"]["content"]
    except (KeyError, IndexError, TypeError):
        raise BackendUnavailableError(f"LLM endpoint {url} answered without choices[0].message.content") from None
    if not isinstance(content, str):
        raise BackendUnavailableError(f"LLM endpoint {url} answered a non-text message")
    return content


def _extract_json(content: str) -> Any:
    s = content.strip()
    start = s.find("```")                  # str.find, not a regex: linear on any reply
    end = s.find("```", start + 3) if start >= 0 else -1
    if end >= 0:
        inner = s[start + 3:end]
        s = (inner[4:] if inner.startswith("json") else inner).strip()
    if not s.startswith("{"):
        a, b = s.find("{"), s.rfind("}")
        if a >= 0 and b > a:
            s = s[a:b + 1]
    try:
        return loads_bounded(s)
    except ValueError as exc:
        raise CommandError(f"the reply is not usable JSON ({exc})") from None


def _finish(plan: Plan, text: str, scene: Any, require_scene: bool, top: bool = True) -> Plan:
    """Resolve edit targets like the rule parser does, and mark the plan as the LLM's."""
    items = scene_items(scene) if scene is not None else None
    names = {o.name for o in plan.objects} if plan.mode == "generate" else None

    def fix_plan(p: Plan, known: set[str] | None) -> Plan:
        edits = []
        for e in p.edits:
            targets = []
            for t in e.targets:
                noun = t.noun.lower()
                if noun in ("camera", "view"):
                    targets.append(replace(t, noun="camera", category="camera"))
                    continue
                if known is not None:
                    objs = t.objects or tuple(o.name for o in plan.objects if o.name == noun or o.noun == noun
                                              or o.category == noun or noun in ALL_WORDS)
                    if not objs:
                        raise CommandError(f"target {t.text!r} is not an object of the plan {sorted(known)}")
                    targets.append(replace(t, objects=tuple(objs)))
                elif items is not None:
                    hits = resolve_in_scene(noun, items, t.text)
                    cats = {h.category for h in hits}
                    targets.append(replace(t, category=cats.pop() if len(cats) == 1 else None,
                                           objects=tuple(h.name for h in hits), object_ids=tuple(h.id for h in hits)))
                else:
                    if require_scene:
                        raise CommandError("there is no scene to edit")
                    cat = t.category or (None if noun in ALL_WORDS else ground_noun(noun, settings=True).category)
                    targets.append(replace(t, category=cat))
            edits.append(replace(e, targets=tuple(targets)))
        return replace(p, edits=tuple(edits), backend="llm")

    then = tuple(fix_plan(p, names) for p in plan.then)
    head = fix_plan(replace(plan, then=()), None if plan.mode == "edit" else names)
    return Plan.from_dict({**replace(head, then=then, text=text).to_dict()})


def _plan_from_reply(content: str, text: str, scene: Any, require_scene: bool) -> Plan:
    """The plan in a reply's content; `CommandError` naming the problem for anything else."""
    data = _extract_json(content)
    try:
        plan = Plan.from_dict(data)
        return _finish(plan, text, scene, require_scene)
    except CommandError:
        raise
    except (ValueError, TypeError, KeyError, IndexError, AttributeError, RecursionError) as exc:
        message = f"{type(exc).__name__}: {exc}"
        raise CommandError(f"the reply is not a valid plan ({message[:ERROR_CHARS]})") from None


def _retry_messages(content: str, error: Exception) -> list[dict]:
    """What is added to the conversation to ask again: the reply (unless it is long) and its error."""
    problem = str(error)[:ERROR_CHARS]
    if len(content) <= RESEND_CHARS:
        return [{"role": "assistant", "content": content},
                {"role": "user", "content": f"That JSON is not a valid plan: {problem}. Reply with the corrected "
                                            f"JSON object only."}]
    return [{"role": "user", "content": f"Your reply ({len(content)} characters) was not a valid plan: {problem}. "
                                        f"Reply with one short JSON object only."}]


def parse_llm(text: str, scene: Any = None, config: LLMConfig | None = None, require_scene: bool = False) -> Plan:
    """Parse with the LLM backend (see the module docstring for retries and fallback).

    Raises:
        CommandError: empty text, or (with ``fallback="raise"``) no valid plan after the retries.
        BackendUnavailableError: (with ``fallback="raise"``) the endpoint could not be used.
    """
    if not isinstance(text, str) or not text.strip():
        raise CommandError("Could not understand an empty command. Try e.g. " + ", ".join(EXAMPLES))
    config = config or LLMConfig.from_env()
    messages = [{"role": "system", "content": system_prompt()}, {"role": "user", "content": _user_message(text, scene)}]
    last_error: Exception | None = None
    deadline = Deadline(config.timeout_s)            # one limit for every attempt together
    for attempt in range(1 + config.max_retries):
        try:
            content = chat(config, messages, deadline)
        except BackendUnavailableError as exc:
            last_error = exc
            break
        try:
            return _plan_from_reply(content, text, scene, require_scene)
        except CommandError as exc:
            last_error = exc
            messages = messages + _retry_messages(content, exc)
    if config.fallback == "rules":
        return parse_rules(text, scene, require_scene)
    if isinstance(last_error, BackendUnavailableError):
        raise last_error
    raise CommandError(f"The LLM backend gave no valid plan for {text!r} after {1 + config.max_retries} attempts: "
                       f"{last_error}")
