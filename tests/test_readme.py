"""Every fenced code block of README.md runs as written.

Each ```python block runs as a script in a fresh interpreter; each line of a ```bash block runs on its
own in bash, in a fresh folder (so a line that needs an earlier line's output says so with `&&`), with
`python` and `morphosim` meaning this interpreter and `python -m morphosim_gym.cli`; ```yaml blocks must
parse. The folder holds links to the repository's `examples/`, `tasks/` and `benchmarks/`.

What a command may not do here is listed below, visibly: install steps of a `&&` chain are dropped
(`INSTALL_STEPS`), and `RULES` marks commands slow, skips them, or runs a server until it answers, each
with its reason. Anything not listed runs in the default suite, so a new block is tested by default.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import tempfile
import textwrap
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.processes import wait_for_line

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
LINKED = ("examples", "tasks", "benchmarks")       # what the blocks may refer to, linked into their folder

# `&&` steps that install into a new environment: dropped, the rest of the chain runs. `.ci/run` runs the
# README's install and test line verbatim on a fresh machine.
INSTALL_STEPS = {
    r"^python3? -m venv\b": "creates a virtual environment (the tests already run in one)",
    r"^(\.|source) \S*activate$": "activates that environment",
    r"^pip install\b": "installs from a package index (.ci/run does it on a fresh machine)",
    r"^(sudo )?apt(-get)? ": "installs system packages (.ci/run does it on a fresh machine)",
}


@dataclass(frozen=True)
class Rule:
    """What to do with a command (a bash line or a python block) that matches `pattern` (re.search)."""

    pattern: str
    kind: str              # "skip", "slow" (run, marked slow), "serve" (run until its address answers; slow)
    reason: str
    append: str = ""       # arguments added to the command (kind "slow" only), said in the reason


RULES: tuple[Rule, ...] = (
    Rule(r"^python -m pytest\b", "skip", "the whole test suite, this file included; .ci/run runs it verbatim"),
    Rule(r"^morphosim bench my_suite\.yaml", "skip",
         "a template: my_suite.yaml and my_pkg.policies are the reader's own files"),
    Rule(r"^python examples/paper_scenes\.py\b", "slow",
         "generates, edits and renders the paper's scenes to videos (minutes)"),
    Rule(r"^morphosim bench smoke\b", "slow", "32 episodes (8 s with warm caches, 24 s cold)"),
    Rule(r"^morphosim bench track\b", "slow",
         "the full sweep is 720 episodes, a benchmark run: checked here on one seed per condition",
         append=" --episodes 1"),
    Rule(r"^morphosim view\b|&& morphosim view\b", "serve",
         "serves until Ctrl-C: run until it prints its address and the page answers, then stopped"),
    Rule(r"sim\.reconstruct\(", "slow", "fits a scene to a clip (about a minute)"),
    Rule(r"reconstruction=\"fit\"", "slow", "fits a pool of scenes for an env (about a minute)"),
    Rule(r"^morphosim warmup\b", "slow", "compiles every numba kernel (about 90 s on 2 cores with a cold cache)"),
    Rule(r"^morphosim collect smoke\b", "slow", "records the 32 episodes of the smoke suite as a dataset"),
    Rule(r"^morphosim collect track\b", "slow",
         "the full track suite on Ray is a data run: checked here on one seed per condition", append=" --episodes 1"),
    Rule(r"^morphosim collect --task\b", "slow", "200 episodes is a data run: checked here on 2",
         append=" --episodes 2"),
)


@dataclass(frozen=True)
class Block:
    """A fenced code block: its language, its text (dedented) and the README line of its opening fence."""

    lang: str
    code: str
    line: int


@dataclass(frozen=True)
class Case:
    """One thing to check: a python block, a bash line or a yaml block, and what to do with it."""

    id: str
    lang: str
    command: str           # what runs (install steps dropped, `append` added)
    written: str           # as written in the README
    kind: str              # "run", "slow", "serve", "skip", "parse"
    reason: str = ""
    dropped: tuple[str, ...] = ()


def fenced_blocks(text: str) -> list[Block]:
    """The README's fenced code blocks, indented ones (inside list items) included."""
    blocks, lines, i = [], text.split("\n"), 0
    while i < len(lines):
        m = re.match(r"^(\s*)```(\w*)\s*$", lines[i])
        if not m:
            i += 1
            continue
        indent, lang, start, body = m.group(1), m.group(2), i + 1, []
        i += 1
        while i < len(lines) and not re.match(rf"^{re.escape(indent)}```\s*$", lines[i]):
            body.append(lines[i])
            i += 1
        if i == len(lines):
            raise ValueError(f"README.md:{start}: a ``` block that never closes")
        blocks.append(Block(lang or "text", textwrap.dedent("\n".join(body)), start))
        i += 1
    return blocks


def bash_lines(code: str) -> list[str]:
    """The commands of a bash block: its non-blank lines without comments, continuations joined."""
    out, pending = [], ""
    for raw in code.split("\n"):
        line = pending + (raw.lstrip() if pending else raw)
        if line.rstrip().endswith("\\"):
            pending = line.rstrip()[:-1].rstrip() + " "
            continue
        pending = ""
        line = _strip_comment(line).strip()
        if line:
            out.append(line)
    return out


def _strip_comment(line: str) -> str:
    """`line` without a trailing `# comment` (a `#` outside quotes, after a space)."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            quote = None if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or line[i - 1].isspace()):
            return line[:i]
    return line


def _rule_for(command: str) -> Rule | None:
    return next((r for r in RULES if re.search(r.pattern, command)), None)


def _case(id_: str, lang: str, command: str, written: str, dropped: tuple[str, ...] = ()) -> Case:
    rule = _rule_for(command)
    if rule is None:
        return Case(id_, lang, command, written, "run", dropped=dropped)
    return Case(id_, lang, command + rule.append, written, rule.kind, rule.reason, dropped)


def readme_cases(text: str) -> list[Case]:
    """Every check the README asks for, in its order."""
    cases = []
    for block in fenced_blocks(text):
        where = f"README.md:{block.line}"
        if block.lang == "python":
            cases.append(_case(f"{where} python", "python", block.code, block.code))
        elif block.lang == "bash":
            cases.extend(_bash_case(f"{where}+{n} bash: {line[:60]}", line)
                         for n, line in enumerate(bash_lines(block.code)))
        elif block.lang == "yaml":
            cases.append(Case(f"{where} yaml", "yaml", block.code, block.code, "parse"))
        else:
            cases.append(Case(f"{where} {block.lang}", block.lang, "", block.code, "skip",
                              f"a ```{block.lang} block is not code to run"))
    return cases


def _bash_case(id_: str, line: str) -> Case:
    """A bash line's check: its install steps dropped, the rest under `RULES`."""
    steps = [s.strip() for s in line.split(" && ")]
    dropped = tuple(s for s in steps if any(re.search(p, s) for p in INSTALL_STEPS))
    kept = " && ".join(s for s in steps if s not in dropped)
    if kept:
        return _case(id_, "bash", kept, line, dropped)
    reasons = sorted({r for s in dropped for p, r in INSTALL_STEPS.items() if re.search(p, s)})
    return Case(id_, "bash", "", line, "skip", "only install steps: " + "; ".join(reasons), dropped)


CASES = readme_cases(README.read_text())


def _param(case: Case):
    marks = {"slow": [pytest.mark.slow], "serve": [pytest.mark.slow]}.get(case.kind, [])
    return pytest.param(case, id=case.id, marks=marks)


# ----------------------------------------------------------------------------- running
def _workdir(tmp_path: Path) -> Path:
    for name in LINKED:
        (tmp_path / name).symlink_to(ROOT / name, target_is_directory=True)
    return tmp_path


def _env() -> dict[str, str]:
    env = dict(os.environ, MORPHOSIM_PY=sys.executable, PYTHONUNBUFFERED="1", MPLBACKEND="Agg")
    env.pop("PYTHONPATH", None)
    return env


# `python` and `morphosim` are this interpreter and its command line (the scripts on PATH may belong to
# another checkout).
BASH_PRELUDE = ('set -eo pipefail\n'
                'python() { "$MORPHOSIM_PY" "$@"; }\n'
                'python3() { "$MORPHOSIM_PY" "$@"; }\n'
                'morphosim() { "$MORPHOSIM_PY" -m morphosim_gym.cli "$@"; }\n')


def _stop_group(proc: subprocess.Popen) -> None:
    """End the command's whole process group (servers, Ray and pool workers it may have left)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    try:
        proc.wait(20)
    except subprocess.TimeoutExpired:
        pass


def _run(argv: list[str], cwd: Path, timeout: float) -> None:
    """Run `argv` in its own session with its output in files, so a child that outlives it (and keeps
    a pipe open) cannot stall the test; the whole group is ended afterwards."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(argv, cwd=cwd, env=_env(), stdin=subprocess.DEVNULL, stdout=out, stderr=err,
                                text=True, start_new_session=True)
        try:
            code = proc.wait(timeout)
        except subprocess.TimeoutExpired:
            code = None
        finally:
            _stop_group(proc)
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    assert code is not None, f"still running after {timeout:.0f} s\n--- stdout\n{stdout[-4000:]}\n--- stderr\n" \
                             f"{stderr[-4000:]}"
    assert code == 0, f"exit {code}\n--- stdout\n{stdout[-4000:]}\n--- stderr\n{stderr[-4000:]}"


def _serve(script: str, cwd: Path, timeout: float) -> None:
    """Run a server command until it prints ' at http://...', fetch that page, then stop its process group."""
    proc = subprocess.Popen(["bash", "-c", script], cwd=cwd, env=_env(), stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        found, lines = wait_for_line(proc, r" at (http://\S+)", timeout)
        url = found.group(1) if found else None
        assert url, f"no address printed (exit {proc.poll()}):\n{''.join(lines)[-4000:]}"
        page = urllib.request.urlopen(url, timeout=30).read().decode(errors="replace")
        assert "<html" in page.lower(), page[:500]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
            try:
                proc.wait(20)
            except subprocess.TimeoutExpired:
                pass
        _stop_group(proc)
        proc.stdout.close()


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_readme_block_runs_as_written(case: Case, tmp_path):
    if case.kind == "skip":
        pytest.skip(case.reason)
    if case.kind == "parse":
        import yaml

        assert yaml.safe_load(case.command) is not None
        return
    cwd = _workdir(tmp_path)
    timeout = 300 if case.kind == "run" else 600
    if case.lang == "python":
        (cwd / "readme_block.py").write_text(case.command)
        _run([sys.executable, "readme_block.py"], cwd, timeout)
    elif case.kind == "serve":
        _serve(BASH_PRELUDE + case.command, cwd, timeout)
    else:
        _run(["bash", "-c", BASH_PRELUDE + case.command], cwd, timeout)


# ----------------------------------------------------------------------------- the list itself
def test_every_rule_still_matches_a_readme_command():
    commands = [c.command for c in CASES if c.command]
    for rule in RULES:
        assert any(re.search(rule.pattern, c) for c in commands), f"stale rule (no README command matches): {rule}"


def test_the_ci_runs_the_readme_test_command_verbatim():
    tests = [c.written for c in CASES if c.lang == "bash" and re.search(r"\bpython -m pytest\b", c.written)]
    assert len(tests) == 1, tests
    assert tests[0] in (ROOT / ".ci" / "run").read_text().split("\n")


def test_the_block_reader_on_a_sample():
    sample = textwrap.dedent('''
        text
        ```bash
        pip install -e ".[bench]"     # a comment with "quotes"
        morphosim parse "make it #1" \\
            --compact
        python3 -m venv .venv && . .venv/bin/activate && python x.py
        ```
        - item:

          ```python
          print(1)
          ```
        ```
        plain
        ```
    ''')
    blocks = fenced_blocks(sample)
    assert [b.lang for b in blocks] == ["bash", "python", "text"]
    assert blocks[1].code == "print(1)"
    assert bash_lines(blocks[0].code) == ['pip install -e ".[bench]"', 'morphosim parse "make it #1" --compact',
                                          "python3 -m venv .venv && . .venv/bin/activate && python x.py"]
    cases = readme_cases(sample)
    assert [(c.kind, c.command) for c in cases] == [
        ("skip", ""), ("run", 'morphosim parse "make it #1" --compact'), ("run", "python x.py"),
        ("run", "print(1)"), ("skip", "")]
    assert cases[2].dropped == ("python3 -m venv .venv", ". .venv/bin/activate")
