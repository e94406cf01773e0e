"""The one command-line setting of the grounding level: `--grounding LEVEL` (and `--strict`, its old
spelling for "exact"), shared by `morphosim parse`, `generate`, `view` and `bench`."""

from __future__ import annotations

import argparse

from .grounding import DEFAULT_LEVEL, LEVEL_VAR, LEVELS

__all__ = ["add_grounding_flags", "grounding_from_args"]

HELP = (f"how a noun outside the vocabulary grounds (default: ${LEVEL_VAR}, else {DEFAULT_LEVEL}): exact (fail, exit 2, "
        "instead of substituting anything, a repaired misspelling included), checked (only what WordNet or a very "
        "close match confirms; else fail listing the nearest candidates), kind (as checked, else a stand-in of the "
        "same kind, e.g. kangaroo -> a mammal, with a note), nearest (the nearest category, shape or asset)")


def add_grounding_flags(p: argparse.ArgumentParser) -> None:
    """Add `--grounding` and the deprecated `--strict` (= `--grounding exact`)."""
    p.add_argument("--grounding", choices=LEVELS, default=None, help=HELP)
    p.add_argument("--strict", action="store_true", help="deprecated: the same as --grounding exact")


def grounding_from_args(args: argparse.Namespace) -> str | None:
    """The level the flags ask for (None: the environment's, else the default)."""
    return "exact" if getattr(args, "strict", False) else getattr(args, "grounding", None)
