"""Check the import contracts (`[tool.importlinter]` in pyproject.toml) on the installed layout.

`envs/` and `tasks/` install as `morphosim_gym.envs` and `morphosim_gym.tasks` (setuptools
`package-dir`), but import-linter finds a package's modules by walking its directory, so it would
not see them. This stages the package as installed (`morphosim_gym/` with every mapped directory
inside it) in a temporary directory and runs import-linter there.

    python .ci/lint_layers.py          # exit status 0 when every contract is kept
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = "morphosim_gym"


def stage(dest: Path) -> Path:
    """Copy the package into `dest` the way it installs; returns the staged package directory."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    mapping: dict[str, str] = config["tool"]["setuptools"]["package-dir"]
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(ROOT / mapping.get(PACKAGE, PACKAGE), dest / PACKAGE, ignore=ignore)
    for name, folder in mapping.items():
        if name.startswith(PACKAGE + "."):
            target = dest.joinpath(*name.split("."))
            if target.exists():
                raise SystemExit(f"Expected {name} to come only from {folder}/, found {target} as well")
            shutil.copytree(ROOT / folder, target, ignore=ignore)
    return dest / PACKAGE


def main() -> int:
    from importlinter.cli import lint_imports

    with tempfile.TemporaryDirectory(prefix="lint-layers-") as tmp:
        stage(Path(tmp))
        cwd = os.getcwd()
        os.chdir(tmp)                       # import-linter puts the working directory first on sys.path
        try:
            return lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True, no_logo=True)
        finally:
            os.chdir(cwd)


if __name__ == "__main__":
    sys.exit(main())
