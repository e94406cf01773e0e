"""The `morphosim` command starts light and answers a missing optional package with its install line.

Start-up is checked by what a fresh interpreter has imported (not by timing): `--help` and a
`parse` that needs no embedding load no torch, numba, MuJoCo or sentence-transformers. Missing
extras are simulated in a subprocess whose import system refuses the named modules.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import textwrap
import types

import pytest

from morphosim_gym import cli
from morphosim_gym.extras import EXIT_MISSING_EXTRA, EXTRAS, install_line, missing_modules, require_extra

HEAVY = ("torch", "numba", "mujoco", "sentence_transformers")

# A subprocess that runs `morphosim ARGS` with the modules in BLOCKED made unimportable, then prints
# which heavy modules got imported (on stdout's last line, as JSON).
BLOCKING_RUNNER = textwrap.dedent("""
    import importlib.abc, json, sys

    BLOCKED, HEAVY = (set(names) for names in json.loads(sys.argv[1]))

    class Uninstalled(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in BLOCKED:
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
            return None

    sys.meta_path.insert(0, Uninstalled())
    from morphosim_gym.cli import main
    try:
        code = main(sys.argv[2:])
    except SystemExit as exc:
        code = exc.code
    print(json.dumps({"loaded": sorted(m for m in sys.modules if m.split(".")[0] in HEAVY)}))
    sys.exit(code)
""")


def morphosim(*args: str, blocked: tuple[str, ...] = (), cwd=None, timeout: float = 300) -> tuple[int, str, str, list]:
    """Run `morphosim ARGS` in a fresh interpreter; (exit status, stdout without the last line, stderr, heavy
    modules imported)."""
    proc = subprocess.run([sys.executable, "-c", BLOCKING_RUNNER, json.dumps([list(blocked), list(HEAVY)]), *args],
                          capture_output=True, text=True, cwd=cwd, timeout=timeout, check=False)
    lines = proc.stdout.rstrip("\n").split("\n")
    loaded = json.loads(lines[-1])["loaded"]
    return proc.returncode, "\n".join(lines[:-1]), proc.stderr, loaded


# ----------------------------------------------------------------------------- start-up imports
def test_help_imports_no_heavy_module():
    code, out, err, loaded = morphosim("--help")
    assert code == 0, err
    assert loaded == [], f"morphosim --help imported {loaded}"
    for name in cli.SUBCOMMANDS:
        assert name in out


def test_parse_of_a_known_sentence_imports_no_heavy_module():
    code, out, err, loaded = morphosim("parse", "a red ball bounces from right to left", "--compact")
    assert code == 0, err
    assert json.loads(out)["objects"][0]["category"] == "ball"
    assert loaded == [], f"morphosim parse imported {loaded}"


def test_import_morphosim_gym_is_light_and_still_registers_the_envs():
    probe = ("import sys, morphosim_gym, gymnasium; "
             f"print(sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r})); "
             "print('MorphoSim/Track-v0' in gymnasium.registry)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "[]" and out[1] == "True", out


def test_public_names_resolve_lazily_and_render_stays_the_function():
    import morphosim_gym as ms

    for name in ms.__all__:
        assert getattr(ms, name) is not None, name
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        ms.nothing  # noqa: B018
    # the subpackage imported before the name is read (as MorphoSim's modules do) must not shadow the function
    probe = ("import morphosim_gym as ms; from morphosim_gym.render.api import render; "
             "print(ms.render is render, type(ms.render).__name__)")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "function"], out


# ----------------------------------------------------------------------------- the subcommand table
def test_the_table_lists_every_command_with_its_own_help():
    sub = next(a for a in cli.build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert list(sub.choices) == list(cli.SUBCOMMANDS)
    helps = {choice.dest: choice.help for choice in sub._choices_actions}
    for name, entry in cli.SUBCOMMANDS.items():
        assert helps[name] == entry.help, (name, helps[name], entry.help)
        assert sub.choices[name]._actions, name


def test_a_command_loads_only_its_own_module():
    parser = cli.build_parser(["parse"])
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert any("--scene" in a.option_strings for a in sub.choices["parse"]._actions)
    assert not any("--policy" in a.option_strings for a in sub.choices["bench"]._actions)   # a listing only


def test_a_new_table_row_is_a_new_command(monkeypatch, capsys):
    module = types.ModuleType("morphosim_fake_cli")

    def register(sub):
        sub.add_parser("fake", help="a fake command").set_defaults(func=lambda args: 7)

    module.register = register
    monkeypatch.setitem(sys.modules, "morphosim_fake_cli", module)
    monkeypatch.setitem(cli.SUBCOMMANDS, "fake", cli.Subcommand("morphosim_fake_cli:register", "a fake command"))
    assert cli.main(["fake"]) == 7
    assert cli.main([]) == cli.EXIT_USAGE
    assert "fake" in capsys.readouterr().out


def test_a_missing_package_deep_in_a_command_is_answered_without_a_traceback(monkeypatch, capsys):
    module = types.ModuleType("morphosim_fake_cli")

    def fail(args):
        raise ModuleNotFoundError("No module named 'matplotlib'", name="matplotlib")

    module.register = lambda sub: sub.add_parser("fake").set_defaults(func=fail)
    monkeypatch.setitem(sys.modules, "morphosim_fake_cli", module)
    monkeypatch.setitem(cli.SUBCOMMANDS, "fake", cli.Subcommand("morphosim_fake_cli:register", "fails"))
    assert cli.main(["fake"]) == EXIT_MISSING_EXTRA
    err = capsys.readouterr().err
    assert err.strip() == ("morphosim fake: error: the Python package 'matplotlib' is not installed (extra 'bench'); "
                           'install it with: pip install -e ".[bench]"')


# ----------------------------------------------------------------------------- missing extras
def test_require_extra_names_the_missing_modules_and_the_install_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "viser", None)       # find_spec treats a None entry as not importable
    assert missing_modules(["viser", "json"]) == ["viser"]
    with pytest.raises(Exception, match=r'morphosim view needs viser from the \'viewer\' extra, which is not '
                                        r'installed; install it with: pip install -e "\.\[viewer\]"$'):
        require_extra("viewer", "viser", needed_for="morphosim view")
    with pytest.raises(ValueError, match="Expected modules of the 'viewer' extra"):
        require_extra("viewer", "matplotlib", needed_for="x")
    with pytest.raises(ValueError, match="Expected an extra among"):
        install_line("nothing")


def test_every_extra_is_in_pyproject_and_every_cli_install_line_in_the_readme():
    from pathlib import Path

    import tomllib

    root = Path(__file__).resolve().parents[1]
    extras = tomllib.loads((root / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert set(EXTRAS) <= set(extras)
    readme = (root / "README.md").read_text()
    for extra in ("bench", "viewer"):                      # the extras the command line asks for
        assert install_line(extra) in readme, extra


def _assert_missing_extra(code: int, out: str, err: str, extra: str, module: str) -> None:
    assert code == EXIT_MISSING_EXTRA, (code, out, err)
    assert "Traceback" not in err and "Traceback" not in out, err
    assert module in err and err.rstrip().endswith(f"install it with: {install_line(extra)}"), err
    assert len(err.strip().splitlines()) == 1, err


def test_bench_without_matplotlib_stops_before_any_episode(tmp_path):
    out = tmp_path / "smoke"
    code, stdout, err, _ = morphosim("bench", "smoke", "--policy", "oracle", "--out", str(out), "--no-progress",
                                     "--cache-dir", str(tmp_path / "cache"), blocked=("matplotlib",))
    _assert_missing_extra(code, stdout, err, "bench", "matplotlib")
    assert not out.exists() and not (tmp_path / "cache").exists(), "an episode ran"


@pytest.mark.parametrize("command,module", [("bench", "ray"), ("bench", "psutil"), ("collect", "psutil")])
def test_ray_backend_without_its_packages_stops_before_any_episode(tmp_path, command, module):
    out = tmp_path / "smoke"
    code, stdout, err, _ = morphosim(command, "smoke", "--backend", "ray", "--out", str(out), "--no-progress",
                                     "--cache-dir", str(tmp_path / "cache"), blocked=(module,))
    _assert_missing_extra(code, stdout, err, "bench", module)
    assert not out.exists() and not (tmp_path / "cache").exists(), "an episode ran"


def test_bench_list_needs_no_extra():
    code, out, err, _ = morphosim("bench", "--list", blocked=("matplotlib", "ray"))
    assert code == 0 and "smoke" in out, err


def test_view_without_viser_stops_before_making_a_scene(tmp_path):
    code, out, err, _ = morphosim("view", "a red ball bounces from right to left", "--port", "0",
                                       blocked=("viser",), cwd=tmp_path)
    _assert_missing_extra(code, out, err, "viewer", "viser")
    assert "preparing" not in out, out


def test_env_view_without_viser_stops_before_making_the_env(tmp_path):
    code, out, err, _ = morphosim("view", "--env", "MorphoSim/Track-v0", "--port", "0", blocked=("viser",),
                                       cwd=tmp_path)
    _assert_missing_extra(code, out, err, "viewer", "viser")
    assert "making" not in out, out


def test_quality_without_brisque_stops_before_generating(tmp_path):
    report = tmp_path / "q.md"
    code, out, err, _ = morphosim("quality", "a red ball", "--out", str(report), blocked=("brisque",))
    _assert_missing_extra(code, out, err, "bench", "brisque")
    assert not report.exists()


def test_the_lower_layers_hints_are_the_readme_lines(monkeypatch):
    """metrics sits below extras.py in the layers, so its hint is a literal: it must stay the README's line."""
    from morphosim_gym.metrics import brisque_score
    from morphosim_gym.viewer import app

    monkeypatch.setitem(sys.modules, "brisque", None)
    with pytest.raises(ImportError) as info:
        brisque_score._model_class()
    assert str(info.value).endswith(install_line("bench"))
    assert app.PIP_HINT == install_line("viewer")
