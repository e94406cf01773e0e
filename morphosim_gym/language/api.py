"""`parse`: the public entry point of the command parameterizer."""

from __future__ import annotations

from typing import Any

from ..errors import CommandError, UnknownBackendError
from .grounding import using_level
from .plan import Plan
from .substitutions import check_strict

__all__ = ["parse"]


def parse(text: str, scene: Any = None, *, require_scene: bool = False, backend: str = "rules",
          llm: Any = None, grounding: str | None = None, strict: bool = False) -> Plan:
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
            "rules"), or a ``"module:factory"`` parser (see `language.backends`).
        llm: an `LLMConfig` for the "llm"/"auto" backends (default: from the environment).
        grounding: the grounding level of nouns outside the vocabulary, one of
            `grounding.LEVELS` (None: `$MORPHOSIM_GROUNDING`, else "kind"; see `grounding.py`).
            "exact" raises `CommandError` when the plan would substitute anything for what the text
            asks (a noun outside the library, a repaired misspelling; see
            `morphosim_gym.language.substitutions`) instead of returning the plan with them.
        strict: deprecated alias of ``grounding="exact"``.

    Returns:
        A `Plan` with mode "generate" or "edit" (follow-up edits of a compound command in
        ``plan.then``).

    Raises:
        CommandError: the text could not be turned into a valid plan; no partial plan is returned.
    """
    from .backends import PARSERS

    try:
        parser = PARSERS.create(PARSERS.check(backend), llm)
    except UnknownBackendError as e:
        raise CommandError(f"Expected backend {PARSERS.known()}, found {backend!r}") from e
    with using_level("exact" if strict else grounding) as level:
        plan = parser.parse(text, scene, require_scene=require_scene)
    if level == "exact":
        check_strict(plan)
    return plan
