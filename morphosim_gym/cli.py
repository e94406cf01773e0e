"""The `morphosim` command line: one subcommand per layer.

Each subcommand lives next to the code it drives, in a module that defines
`register(subparsers)`, which adds its parser and sets `func` to a callable taking the
parsed arguments and returning an exit code.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from typing import Sequence

__all__ = ["main", "build_parser"]

# Modules that define `register(subparsers)`, in the order `morphosim --help` lists them.
SUBCOMMAND_MODULES: tuple[str, ...] = (
    "morphosim_gym.generate.cli",
    "morphosim_gym.reconstruct.cli",
    "morphosim_gym.scene.cli",
    "morphosim_gym.assets.cli",
    "morphosim_gym.language.cli",
    "morphosim_gym.viewer.cli",
    "morphosim_gym.bench.cli",
    "morphosim_gym.bench.collect_cli",
    "morphosim_gym.warmup",
)


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every available subcommand."""
    parser = argparse.ArgumentParser(prog="morphosim", description="MorphoSim Gym: language-driven, editable 4D worlds.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `morphosim` script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except ValueError as exc:  # our errors subclass ValueError and carry a message for people
        print(f"morphosim {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
