"""`morphosim warmup` compiles the kernels into numba's cache, so that a fresh process's first env
step takes seconds instead of a minute of compiling."""

import json
import os
import subprocess
import sys

import pytest

from morphosim_gym.warmup import STEPS, warm_up

FIRST_STEP = """
import json, time
t0 = time.perf_counter()
import gymnasium as gym, morphosim_gym
env = gym.make("MorphoSim/Track-v0"); env.reset(seed=0); env.step(env.action_space.sample()); env.close()
print(json.dumps({"first_step_s": time.perf_counter() - t0}))
"""


def test_steps_are_chosen_by_name_and_reported():
    seen = []
    done = warm_up(["skinning"], report=seen.append)
    assert [s.name for s in done] == [n for n, _ in STEPS if "skinning" in n] and done == seen
    assert all(s.seconds >= 0 for s in done)
    with pytest.raises(ValueError, match="warm-up step"):
        warm_up(["no such step"])


def test_the_cli_lists_warmup():
    from morphosim_gym.cli import build_parser

    args = build_parser().parse_args(["warmup", "--only", "Track"])
    assert args.only == ["Track"] and callable(args.func)


def _cache_files(root) -> dict:
    """numba's cache files under `root` (index and compiled objects) with their sizes and times."""
    out = {}
    for dirpath, _, files in os.walk(root):
        for f in files:
            st = os.stat(os.path.join(dirpath, f))
            out[os.path.join(dirpath, f)] = (st.st_size, st.st_mtime_ns)
    return out


@pytest.mark.slow
def test_first_env_step_after_warmup_takes_seconds(tmp_path):
    """After warmup, a fresh process's first Track step compiles nothing (numba's cache gains and
    rewrites no file: every kernel it runs was loaded). Wall time is printed, not asserted: it
    depends on the machine's load (2.8-3.8 s on a shared 2-core machine, 11 s at load 10)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))   # an empty cache, as after pip install
    warm = subprocess.run([sys.executable, "-m", "morphosim_gym.cli", "warmup", "--only", "Track", "--only", "render:"
                           " forward", "--only", "skinning"], env=env, capture_output=True, text=True, timeout=900)
    assert warm.returncode == 0, warm.stderr
    assert "Track-v0" in warm.stdout and "s  render: forward" in warm.stdout
    before = _cache_files(tmp_path / "numba")
    assert before, "warmup wrote nothing into numba's cache"
    step = subprocess.run([sys.executable, "-c", FIRST_STEP], env=env, capture_output=True, text=True, timeout=300)
    assert step.returncode == 0, step.stderr
    print("first Track step after warmup:", json.loads(step.stdout.strip().splitlines()[-1])["first_step_s"], "s")
    assert _cache_files(tmp_path / "numba") == before, "the first env step compiled kernels that warmup did not"
