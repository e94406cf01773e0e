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


@pytest.mark.slow
def test_first_env_step_after_warmup_takes_seconds(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))   # an empty cache, as after pip install
    warm = subprocess.run([sys.executable, "-m", "morphosim_gym.cli", "warmup", "--only", "Track", "--only", "render:"
                           " forward", "--only", "skinning"], env=env, capture_output=True, text=True, timeout=900)
    assert warm.returncode == 0, warm.stderr
    assert "Track-v0" in warm.stdout and "s  render: forward" in warm.stdout
    step = subprocess.run([sys.executable, "-c", FIRST_STEP], env=env, capture_output=True, text=True, timeout=300)
    assert step.returncode == 0, step.stderr
    assert json.loads(step.stdout.strip().splitlines()[-1])["first_step_s"] < 10.0
