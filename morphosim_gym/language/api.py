"""`parse`: the public entry point of the command parameterizer."""

from __future__ import annotations

from typing import Any

from ..errors import CommandError
from .plan import Plan
from .rules import parse_rules
from .substitutions import check_strict

__all__ = ["parse"]


def parse(text: str, scene: Any = None, *, require_scene: bool = False, backend: str = "rules",
          llm: Any = None, strict: bool = False) -> Plan:
    """Turn a command into a validated `Plan`.

    Args:
        text: e.g. "a red ball bounces from right to left", "make the bus yellow", or both joined by
            "; then".
        scene: the scene an edit applies to (duck-typed: ``.objects``, each with ``.name`` and
            ``.category``); edit targets must resolve to its objects.
        require_scene: raise `CommandError` for an edit with no scene to apply to (and no generated
            plan before it in the same text). Off by default so that pure edit commands can be
            inspected without a scene; pronouns with nothing to refer to always raise.
        backend: "rules" (offline default), "llm" (an OpenAI-compatible chat endpoint, see
            `morphosim_gym.language.llm`), or "auto" ("llm" when an endpoint is configured, else
            "rules").
        llm: an `LLMConfig` for the "llm"/"auto" backends (default: from the environment).
        strict: raise `CommandError` when the plan would substitute anything for what the text asks
            (a noun outside the library grounded to the nearest one, a repaired misspelling; see
            `morphosim_gym.language.substitutions`) instead of returning the plan with them.

    Returns:
        A `Plan` with mode "generate" or "edit" (follow-up edits of a compound command in
        ``plan.then``).

    Raises:
        CommandError: the text could not be turned into a valid plan; no partial plan is returned.
    """
    plan = _parse(text, scene, require_scene, backend, llm)
    if strict:
        check_strict(plan)
    return plan


def _parse(text: str, scene: Any, require_scene: bool, backend: str, llm: Any) -> Plan:
    if backend == "rules":
        return parse_rules(text, scene, require_scene)
    if backend in ("llm", "auto"):
        from .llm import LLMConfig, parse_llm

        config = llm if llm is not None else LLMConfig.from_env()
        if backend == "auto" and not config.configured:
            return parse_rules(text, scene, require_scene)
        return parse_llm(text, scene, config=config, require_scene=require_scene)
    raise CommandError(f"Expected backend 'rules', 'llm' or 'auto', found {backend!r}")
