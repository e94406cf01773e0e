"""Optional extras: which imports each `pip install -e ".[EXTRA]"` provides, and the check
commands run before doing any work.

`require_extra("bench", "matplotlib", needed_for="the report's plots")` looks the modules up
without importing them and raises `MissingExtraError` (a `BackendUnavailableError`) naming the
missing ones and the README's install line; the `morphosim` command answers it with exit
status `EXIT_MISSING_EXTRA` and that one line, no traceback. No module here imports anything
heavy, so every layer may use it.
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass

from .errors import BackendUnavailableError

__all__ = ["Extra", "EXTRAS", "EXIT_MISSING_EXTRA", "MissingExtraError", "install_line", "missing_modules",
           "require_extra", "extra_providing", "missing_package_message"]

# `morphosim`'s exit status when an optional package (or backend) is missing. Not 3: `morphosim bench` exits
# with its number of failed episodes (0-250) and 255 when the sweep cannot run, so 254 is free in every command.
EXIT_MISSING_EXTRA = 254


@dataclass(frozen=True)
class Extra:
    """One optional extra of pyproject.toml: its name and the import names it provides."""

    name: str
    modules: tuple[str, ...]     # top-level import names, e.g. "skimage" for scikit-image

    @property
    def install_line(self) -> str:
        return install_line(self.name)


EXTRAS: dict[str, Extra] = {
    "bench": Extra("bench", ("ray", "psutil", "matplotlib", "brisque", "libsvm", "skimage", "pyinstrument")),
    "viewer": Extra("viewer", ("viser",)),
    "diffusion": Extra("diffusion", ("diffusers", "transformers", "sentencepiece", "google.protobuf")),
    "train": Extra("train", ("stable_baselines3",)),
    "gsplat": Extra("gsplat", ("gsplat",)),
    "test": Extra("test", ("pytest", "xdist", "hypothesis", "moviepy", "selenium")),
}


class MissingExtraError(BackendUnavailableError):
    """Packages of an optional extra are not installed; the message gives the install line."""

    def __init__(self, extra: str, modules: list[str], needed_for: str) -> None:
        self.extra, self.modules, self.needed_for = extra, list(modules), needed_for
        super().__init__(f"{needed_for} needs {', '.join(modules)} from the {extra!r} extra, which is not installed; "
                         f"install it with: {install_line(extra)}")


def install_line(extra: str) -> str:
    """The README's install command of an extra, e.g. `pip install -e ".[bench]"`."""
    if extra not in EXTRAS:
        raise ValueError(f"Expected an extra among {sorted(EXTRAS)}, found {extra!r}")
    return f'pip install -e ".[{extra}]"'


def missing_modules(modules: tuple[str, ...] | list[str]) -> list[str]:
    """The modules of `modules` that cannot be found, looked up without importing them."""
    missing = []
    for name in modules:
        try:
            found = importlib.util.find_spec(name) is not None
        except (ImportError, ValueError):       # a missing parent package, or a module without a spec
            found = False
        if not found:
            missing.append(name)
    return missing


def require_extra(extra: str, *modules: str, needed_for: str) -> None:
    """Raise `MissingExtraError` unless `modules` (default: all of the extra's) are installed."""
    if extra not in EXTRAS:
        raise ValueError(f"Expected an extra among {sorted(EXTRAS)}, found {extra!r}")
    unknown = [m for m in modules if m not in EXTRAS[extra].modules]
    if unknown:
        raise ValueError(f"Expected modules of the {extra!r} extra {EXTRAS[extra].modules}, found {unknown}")
    missing = missing_modules(modules or EXTRAS[extra].modules)
    if missing:
        raise MissingExtraError(extra, missing, needed_for)


def extra_providing(module: str) -> str | None:
    """The extra whose packages provide `module` (a dotted name is matched by its top level)."""
    for extra in EXTRAS.values():
        for name in extra.modules:
            if module == name or module.startswith(name + ".") or name.startswith(module + "."):
                return extra.name
    return None


def missing_package_message(module: str) -> str:
    """What to tell a person when `import module` failed because it is not installed."""
    extra = extra_providing(module)
    if extra is not None:
        return f"the Python package {module!r} is not installed (extra {extra!r}); install it with: {install_line(extra)}"
    return (f"the Python package {module!r} is not installed; install the project's dependencies with: "
            f"pip install -e .")
