"""The `morphosim` command line: one subcommand per layer, imported only when it runs.

Each subcommand lives next to the code it drives, in a module that defines a register
function `register(subparsers)`, which adds its parser(s) and sets `func` to a callable taking
the parsed arguments and returning an exit code. `SUBCOMMANDS` maps each command name to that
function ("module:function") and its one-line help: `morphosim --help` lists the table without
importing any subcommand module, and `morphosim NAME ...` imports only NAME's module.

Exit statuses common to every command: 0 success, 2 a usage error or bad input (the message
names it), 254 a missing optional package or unavailable backend (the message gives the install
line, e.g. `pip install -e ".[bench]"`). `morphosim bench` adds its own (see its --help).
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from .errors import BackendUnavailableError
from .extras import EXIT_MISSING_EXTRA, missing_package_message

__all__ = ["main", "build_parser", "Subcommand", "SUBCOMMANDS", "EXIT_USAGE", "EXIT_MISSING_EXTRA"]

EXIT_USAGE = 2


@dataclass(frozen=True)
class Subcommand:
    """Where a command is defined ("module:function", the function adds its parser) and its one-line help."""

    register: str
    help: str

    def load(self) -> Callable[[argparse._SubParsersAction], None]:
        module, _, function = self.register.partition(":")
        return getattr(importlib.import_module(module), function or "register")


# Command name -> its register function and help, in the order `morphosim --help` lists them. A register
# function may add several commands (its module's); their rows point to the same function.
SUBCOMMANDS: dict[str, Subcommand] = {
    "generate": Subcommand("morphosim_gym.generate.cli:register",
                           "generate a 4D scene from a sentence: video, scene file, clip, summary"),
    "render": Subcommand("morphosim_gym.generate.cli:register", "render a scene file to a video (optionally orbiting it)"),
    "edit": Subcommand("morphosim_gym.generate.cli:register",
                       "edit a scene by language and write it with a before/after video"),
    "reconstruct": Subcommand("morphosim_gym.reconstruct.cli:register",
                              "fit dynamic Gaussians with a feature field to a clip (.mclip) or a video"),
    "info": Subcommand("morphosim_gym.scene.cli:register", "describe a scene (.msim) or clip (.mclip) file"),
    "export-ply": Subcommand("morphosim_gym.scene.cli:register", "write one frame of a scene as a standard 3DGS .ply"),
    "assets": Subcommand("morphosim_gym.assets.cli:register",
                         "list, search and show the real assets (meshes, splats, skies)"),
    "parse": Subcommand("morphosim_gym.language.cli:register", "parse a command into a plan and print it as JSON"),
    "view": Subcommand("morphosim_gym.viewer.cli:register", "open a scene, a prompt or an env in the browser viewer"),
    "bench": Subcommand("morphosim_gym.bench.cli:register", "run a counterfactual robustness suite on a policy"),
    "quality": Subcommand("morphosim_gym.bench.cli:register",
                          "BRISQUE / NIQE (and CLIP, Q-Align when available) of generated scenes"),
    "collect": Subcommand("morphosim_gym.bench.collect_cli:register",
                          "record a policy's episodes (base and counterfactual) as a LeRobot v3.0 dataset"),
    "warmup": Subcommand("morphosim_gym.warmup:register",
                         "compile and cache every numba kernel once (first use then takes seconds)"),
}


def build_parser(load: Iterable[str] | None = None) -> argparse.ArgumentParser:
    """The top-level parser. Commands named in `load` (default: all) get their full parsers, which imports
    their modules; the others are listed by name and help only."""
    wanted = set(SUBCOMMANDS) if load is None else set(load)
    registers = {SUBCOMMANDS[name].register for name in wanted if name in SUBCOMMANDS}
    parser = argparse.ArgumentParser(prog="morphosim", description="MorphoSim Gym: language-driven, editable 4D worlds.",
                                     epilog=f"Exit status: 0 success, {EXIT_USAGE} usage error or bad input, {EXIT_MISSING_EXTRA} a "
                                            "missing optional package (the message gives the install line); see each "
                                            "command's --help.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    done: set[str] = set()
    for name, entry in SUBCOMMANDS.items():
        if entry.register not in registers:
            sub.add_parser(name, help=entry.help, add_help=False)
        elif entry.register not in done:
            entry.load()(sub)
            done.add(entry.register)
    return parser


def _command_of(argv: Sequence[str]) -> str | None:
    """The subcommand named in `argv` (the top-level parser takes no option with a value), if any."""
    first = next((a for a in argv if not a.startswith("-")), None)
    return first if first in SUBCOMMANDS else None


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the `morphosim` script."""
    argv = list(sys.argv[1:] if argv is None else argv)
    command = _command_of(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _note_printer(command)
        return _run(argv, command)


def _note_printer(command: str | None) -> Callable[..., None]:
    """`warnings.showwarning` for the CLI: a substitution (`SubstitutionWarning`) is one line on stderr,
    "morphosim CMD: note: noun 'kangaroo' is not in the library: using duck (similarity 0.59)", each
    once; other warnings print as Python prints them."""
    shown: set[str] = set()
    default = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
        if category.__name__ != "SubstitutionWarning":
            default(message, category, filename, lineno, file, line)
            return
        if str(message) not in shown:
            shown.add(str(message))
            print(f"morphosim {command}: note: {message}" if command else f"morphosim: note: {message}",
                  file=sys.stderr)
    return show


def _run(argv: list[str], command: str | None) -> int:
    try:
        parser = build_parser([command] if command else [])
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return EXIT_USAGE
        return int(args.func(args) or 0)
    except (ValueError, ImportError, BackendUnavailableError) as exc:
        answer = _answer(exc)
        if answer is None:
            raise
        message, code = answer
        print(f"morphosim {command}: error: {message}" if command else f"morphosim: error: {message}",
              file=sys.stderr)
        return code


def _answer(exc: Exception) -> tuple[str, int] | None:
    """The one-line message and exit status for an error a person can act on; None for a bug (re-raised)."""
    if isinstance(exc, ValueError):             # our errors subclass ValueError and carry a message for people
        return str(exc), EXIT_USAGE
    if isinstance(exc, ImportError):
        if _is_ours(exc.name):                  # one of our modules failing to import is a bug, not an install
            return None
        missing = isinstance(exc, ModuleNotFoundError) and exc.name
        return (missing_package_message(exc.name) if missing else str(exc)), EXIT_MISSING_EXTRA
    return str(exc), EXIT_MISSING_EXTRA         # BackendUnavailableError, MissingExtraError included


def _is_ours(module: str | None) -> bool:
    return bool(module) and module.split(".")[0] == __package__


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
