"""Killing the runner mid-sweep and restarting it loses and duplicates no episode."""

import json
import os
import signal
import subprocess
import sys
import time

from morphosim_gym.bench import load_suite, plan_episodes, run_sweep

from .conftest import REPO, strip_timing

POLICIES = ["oracle", "random"]
EPISODES = 6


def _command(out, cache_dir):
    cmd = [sys.executable, "-m", "morphosim_gym.cli", "bench", "smoke", "--episodes", str(EPISODES), "--out", str(out),
           "--cache-dir", cache_dir, "--no-progress"]
    for p in POLICIES:
        cmd += ["--policy", p]
    return cmd


def _lines(path):
    return path.read_bytes().count(b"\n") if path.exists() else 0


def test_sigkill_mid_sweep_then_resume(tmp_path, cache_dir):
    suite = load_suite("smoke").with_episodes(EPISODES)
    total = len(plan_episodes(suite, POLICIES))
    out = tmp_path / "sweep"
    log = out / "results.jsonl"
    proc = subprocess.Popen(_command(out, cache_dir), cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while _lines(log) < 5 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    done_at_kill = _lines(log)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.read().decode()[-2000:]
    assert 5 <= done_at_kill < total                      # it really was mid-sweep
    assert not (out / "results.json").exists()

    rerun = subprocess.run(_command(out, cache_dir), cwd=REPO, capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr[-2000:]
    assert f"{total - done_at_kill} run, {done_at_kill} resumed" in rerun.stdout

    keys = [json.loads(line)["key"] for line in log.read_text().splitlines()]
    assert len(keys) == len(set(keys)) == total           # nothing duplicated, nothing lost
    assert set(keys) == {k.id for k in plan_episodes(suite, POLICIES)}
    resumed = json.loads((out / "results.json").read_text())["episodes"]
    straight = run_sweep(suite, POLICIES, tmp_path / "straight", cache_dir=cache_dir, progress=False, report=False)
    assert strip_timing(resumed) == strip_timing([dict(r) for r in straight.records])
