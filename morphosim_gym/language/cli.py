"""`morphosim parse "..."`: print the plan of a command as JSON."""

from __future__ import annotations

import argparse
import sys

from .grounding_cli import add_grounding_flags, grounding_from_args

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `parse` subcommand."""
    p = sub.add_parser("parse", help="parse a command into a plan and print it as JSON")
    p.add_argument("text", nargs="+", help="the command (quote it, or pass its words)")
    p.add_argument("--scene", help="a scene file (.msim) whose objects edit targets must resolve to")
    p.add_argument("--backend", default="rules",
                   help="rules (offline default), llm (MORPHOSIM_LLM_* environment), auto, or module:factory "
                        "(imports and runs that module)")
    p.add_argument("--require-scene", action="store_true", help="fail on an edit with no scene to apply to")
    p.add_argument("--compact", action="store_true", help="one-line JSON")
    add_grounding_flags(p)
    p.set_defaults(func=_parse)


def _parse(args: argparse.Namespace) -> int:
    from .api import parse

    scene = None
    if args.scene:
        from ..scene.io import load_scene

        scene = load_scene(args.scene)
    text = " ".join(args.text)
    plan = parse(text, scene, require_scene=args.require_scene, backend=args.backend,
                 grounding=grounding_from_args(args))
    from .substitutions import warn

    warn(plan)                  # one note per substitution on stderr (the JSON on stdout stays clean)
    sys.stdout.write(plan.to_json(indent=None if args.compact else 2) + "\n")
    return 0
