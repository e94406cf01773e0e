"""Command parsers: the one protocol (`Parser`) and the registry `SimConfig.parser` names.

    parser = PARSERS.create("llm", LLMConfig(base_url="http://127.0.0.1:8000/v1", model="m"))
    plan = parser.parse("make the ball blue", scene)

| name | parser |
|---|---|
| "rules" | the offline rule parser (default) |
| "llm" | an OpenAI-compatible endpoint (`llm.LLMConfig`; its fallback decides what a failure gives) |
| "auto" | "llm" when the `LLMConfig` names an endpoint and a model, else "rules" |

A factory takes an `LLMConfig` or None (None: read from the MORPHOSIM_LLM_* environment when
the parser needs one) and returns a `Parser`; ``"module:factory"`` names import `module` and call
`factory(llm_config)` (that runs its code).
"""

from __future__ import annotations

from typing import Any, Optional, Protocol, runtime_checkable

from ..registry import Registry
from .plan import Plan
from .rules import parse_rules

__all__ = ["Parser", "PARSERS", "RulesParser", "LLMParser", "AutoParser", "make_parser"]


@runtime_checkable
class Parser(Protocol):
    """Text (and the scene an edit applies to) -> a validated `Plan`; `CommandError` for bad text."""

    name: str

    def parse(self, text: str, scene: Any = None, *, require_scene: bool = False) -> Plan:
        ...


class RulesParser:
    """The offline rule parser (`rules.parse_rules`)."""

    name = "rules"

    def parse(self, text: str, scene: Any = None, *, require_scene: bool = False) -> Plan:
        return parse_rules(text, scene, require_scene)


class LLMParser:
    """The LLM backend (`llm.parse_llm`) with one `LLMConfig` (None: from the environment, read now)."""

    name = "llm"

    def __init__(self, config: Any = None) -> None:
        from .llm import LLMConfig

        if config is not None and not isinstance(config, LLMConfig):
            raise ValueError(f"Expected llm as an LLMConfig or None, found {type(config).__name__}")
        self.config = config if config is not None else LLMConfig.from_env()

    def parse(self, text: str, scene: Any = None, *, require_scene: bool = False) -> Plan:
        from .llm import parse_llm

        return parse_llm(text, scene, config=self.config, require_scene=require_scene)


class AutoParser(LLMParser):
    """"llm" when the config names an endpoint and a model, else "rules"."""

    name = "auto"

    def parse(self, text: str, scene: Any = None, *, require_scene: bool = False) -> Plan:
        if not self.config.configured:
            return parse_rules(text, scene, require_scene)
        return super().parse(text, scene, require_scene=require_scene)


PARSERS: Registry[Parser] = Registry("parser", Parser)
PARSERS.register("rules", lambda llm=None: RulesParser())
PARSERS.register("llm", LLMParser)
PARSERS.register("auto", AutoParser)


def make_parser(name: str, llm: Optional[Any] = None) -> Parser:
    """`PARSERS.create(name, llm)`."""
    return PARSERS.create(name, llm)
