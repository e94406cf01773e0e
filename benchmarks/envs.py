"""Env steps per second for every MorphoSim id: single env and 8-env vector envs.

    python benchmarks/envs.py                      # table + benchmarks/results/envs.json
    python benchmarks/envs.py --ids MorphoSim/Track-v0 --repeats 5 --breakdown

Every number is the median of `--repeats` runs (the machine is shared and noisy; the
spread is reported too). Settings: default env arguments (84x84 rgb, detail 0.35, 10 Hz)
plus `scene_pool=8`, random actions, autoreset included (episodes are 60 steps, or shorter
for Reach/Find when they succeed). Modes:

  single           one env (default `render_threads=1`)
  single-2threads  one env, `render_threads=None` (numba's default: both cores)
  single-fresh     one env without a pool: every reset composes a new scene (~30-60 ms)
  sync-8           SyncVectorEnv of 8 envs in one process
  async-8          AsyncVectorEnv of 8 envs, one process each (spawn)
  vector-8         the native MorphoSimVectorEnv of 8 envs: one process, one batched render of
                   all 8 cameras per step on all cores
  vector-8-1thread the same with its batched render on one numba thread
  vector-32        the same with 32 envs

`--breakdown` times the parts of a Track step (skinning, rendering, kinematics, reward,
observation) by calling them directly. `--ratios` measures single, vector-8 and sync-8
alternately in one run (A B C A B C ...) and reports per-round ratios (median) and the
vector-8 cost split (batched render, skinning, the rest: Python) for each id; on a shared
machine only these same-run ratios mean much.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import morphosim_gym as ms
from morphosim_gym.envs import ENV_IDS, make_vec

RESULTS = Path(__file__).resolve().parent / "results"
MODES = ("single", "single-2threads", "single-fresh", "sync-8", "async-8", "vector-8", "vector-8-1thread", "vector-32")


def _single(env_id: str, steps: int, **kw) -> float:
    env = gym.make(env_id, **kw)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    space = env.action_space
    for _ in range(20):                                   # warm up (JIT caches, first frames)
        _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, space.shape).astype(np.float32))
        if term or trunc:
            env.reset()
    t0 = time.perf_counter()
    for _ in range(steps):
        _, _, term, trunc, _ = env.step(rng.uniform(-1, 1, space.shape).astype(np.float32))
        if term or trunc:
            env.reset()
    rate = steps / (time.perf_counter() - t0)
    env.close()
    return rate


def _vector(env_id: str, steps: int, mode: str, n: int = 8, **kw) -> float:
    venv = make_vec(env_id, n, vectorization_mode=mode, **kw)
    venv.reset(seed=0)
    rng = np.random.default_rng(0)
    shape = venv.action_space.shape
    for _ in range(10):
        venv.step(rng.uniform(-1, 1, shape).astype(np.float32))
    t0 = time.perf_counter()
    for _ in range(steps):
        venv.step(rng.uniform(-1, 1, shape).astype(np.float32))
    rate = steps * n / (time.perf_counter() - t0)
    venv.close()
    return rate


def measure(env_id: str, mode: str, steps: int) -> float:
    if mode == "single":
        return _single(env_id, steps, scene_pool=8)
    if mode == "single-2threads":
        return _single(env_id, steps, scene_pool=8, render_threads=None)
    if mode == "single-fresh":
        return _single(env_id, steps)
    if mode == "sync-8":
        return _vector(env_id, max(1, steps // 8), "sync", scene_pool=8)
    if mode == "async-8":
        return _vector(env_id, max(1, steps // 8), "async", scene_pool=8)
    if mode in ("vector-8", "vector-32"):
        n = int(mode.split("-")[1])
        return _vector(env_id, max(1, steps // n), "vector", n=n, scene_pool=8)
    if mode == "vector-8-1thread":
        return _vector(env_id, max(1, steps // 8), "vector", render_threads=1, scene_pool=8)
    raise ValueError(f"Expected a mode in {MODES}, found {mode!r}")


class _Split:
    """Wall time inside the batched render and inside skinning (scene and agent Gaussians) of a
    native vector env, by wrapping those calls."""

    def __init__(self) -> None:
        self.render = self.skinning = 0.0

    def install(self) -> list:
        from morphosim_gym.envs import native_vector
        from morphosim_gym.envs.world import SceneWorld
        from morphosim_gym.rig.base import Rig

        undo = []

        def wrap(owner, name, field):
            orig = getattr(owner, name)

            def timed(*a, **k):
                t0 = time.perf_counter()
                try:
                    return orig(*a, **k)
                finally:
                    setattr(self, field, getattr(self, field) + time.perf_counter() - t0)

            setattr(owner, name, timed)
            undo.append((owner, name, orig))

        wrap(native_vector, "render_batch", "render")
        wrap(SceneWorld, "gaussians", "skinning")
        wrap(Rig, "gaussians", "skinning")
        return undo


def vector_split(env_id: str, steps: int, n: int = 8, render_threads=None) -> dict:
    """Per env-step microseconds of a native vector env of n envs: batched render, skinning, rest."""
    split = _Split()
    venv = make_vec(env_id, n, vectorization_mode="vector", scene_pool=8, render_threads=render_threads)
    venv.reset(seed=0)
    rng = np.random.default_rng(0)
    shape = venv.action_space.shape
    for _ in range(10):
        venv.step(rng.uniform(-1, 1, shape).astype(np.float32))
    undo = split.install()
    try:
        t0 = time.perf_counter()
        for _ in range(steps):
            venv.step(rng.uniform(-1, 1, shape).astype(np.float32))
        total = time.perf_counter() - t0
    finally:
        for owner, name, orig in undo:
            setattr(owner, name, orig)
    venv.close()
    per = 1e6 / (steps * n)
    return {"total_us": round(total * per, 1), "render_us": round(split.render * per, 1),
            "skinning_us": round(split.skinning * per, 1),
            "python_us": round((total - split.render - split.skinning) * per, 1)}


def ratios(env_id: str, steps: int, rounds: int) -> dict:
    """single, vector-8 and sync-8 measured alternately; per-round ratios and their medians."""
    runs: dict[str, list[float]] = {"single": [], "vector-8": [], "sync-8": [], "vector-8-1thread": []}
    for _ in range(rounds):
        for mode in runs:
            runs[mode].append(measure(env_id, mode, steps))
    vs_single = [v / s for v, s in zip(runs["vector-8"], runs["single"])]
    vs_sync = [v / s for v, s in zip(runs["vector-8"], runs["sync-8"])]
    one_single = [v / s for v, s in zip(runs["vector-8-1thread"], runs["single"])]
    one_sync = [v / s for v, s in zip(runs["vector-8-1thread"], runs["sync-8"])]
    splits = [vector_split(env_id, max(1, steps // 8)) for _ in range(rounds)]
    split = {k: round(statistics.median(s[k] for s in splits), 1) for k in splits[0]}
    splits1 = [vector_split(env_id, max(1, steps // 8), render_threads=1) for _ in range(rounds)]
    split1 = {k: round(statistics.median(s[k] for s in splits1), 1) for k in splits1[0]}
    return {"id": env_id, "runs": {k: [round(x, 1) for x in v] for k, v in runs.items()},
            "vector8_over_single": round(statistics.median(vs_single), 2),
            "vector8_over_sync8": round(statistics.median(vs_sync), 2),
            "round_ratios_single": [round(x, 2) for x in vs_single],
            "round_ratios_sync8": [round(x, 2) for x in vs_sync],
            "vector8_1thread_over_single": round(statistics.median(one_single), 2),
            "vector8_1thread_over_sync8": round(statistics.median(one_sync), 2),
            "vector8_split_us_per_env_step": split, "vector8_1thread_split_us_per_env_step": split1}


def breakdown(repeats: int = 300) -> dict:
    """Milliseconds per part of a Track step (median over `repeats` calls each), with one numba
    thread as the env uses by default."""
    import numba

    numba.set_num_threads(1)
    env = gym.make("MorphoSim/Track-v0", scene_pool=1)
    env.reset(seed=0)
    u = env.unwrapped
    scene = u.world.scene
    a = np.zeros(3, np.float32)
    for _ in range(10):
        env.step(a)

    def timed(fn) -> float:
        ts = []
        for i in range(repeats):
            t0 = time.perf_counter()
            fn(i)
            ts.append(time.perf_counter() - t0)
        return 1e3 * statistics.median(ts)

    times = np.linspace(0.0, scene.duration, repeats)
    out = {
        "gaussians": len(scene.gaussians),
        "skinning scene.at(t)": timed(lambda i: scene.at(float(times[i]) * 0.999 + 1e-6 * i)),
        "camera from MuJoCo": timed(lambda i: u.rig.camera("eye", 84, 84)),
        "rig kinematics (apply)": timed(lambda i: u.rig.apply(a, u.dt)),
    }
    cam = u.rig.camera("eye", 84, 84)
    g = scene.at(1.0)
    out["render 84x84 (ms.render)"] = timed(lambda i: ms.render(g, cam, background=scene.background))
    _, view = u._render(u.world.t)                     # the task camera's view, as a step hands it to the task
    out["task evaluate (reward)"] = timed(lambda i: u.task.measure(u.world, u.rig, view))
    out["env.step total"] = timed(lambda i: env.step(a) if u.world.t < u.world.duration - 0.2 else env.reset())
    env.close()
    return {k: (round(v, 3) if isinstance(v, float) else v) for k, v in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ids", nargs="*", default=list(ENV_IDS))
    ap.add_argument("--modes", nargs="*", default=list(MODES), choices=MODES)
    ap.add_argument("--steps", type=int, default=800, help="env steps per run (vector: total over all envs)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--breakdown", action="store_true")
    ap.add_argument("--ratios", action="store_true", help="only the same-run ratios (single / vector-8 / sync-8)")
    ap.add_argument("--json", type=Path, default=RESULTS / "envs.json")
    args = ap.parse_args()

    if args.ratios:
        return _main_ratios(args)
    rows = []
    for env_id in args.ids:
        for mode in args.modes:
            rates = [measure(env_id, mode, args.steps) for _ in range(args.repeats)]
            row = {"id": env_id, "mode": mode, "steps_per_s": round(statistics.median(rates), 1),
                   "min": round(min(rates), 1), "max": round(max(rates), 1), "runs": [round(r, 1) for r in rates]}
            rows.append(row)
            print(f"{env_id:22s} {mode:15s} {row['steps_per_s']:8.1f} steps/s  (runs {row['runs']})", flush=True)

    print("\n| id | mode | steps/s (median) | min | max |\n|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['id']} | {r['mode']} | {r['steps_per_s']:.0f} | {r['min']:.0f} | {r['max']:.0f} |")
    result = {"rows": rows, "settings": {"obs": "rgb 84x84 + proprio", "detail": 0.35, "control_hz": 10,
                                         "scene_pool": 8, "steps_per_run": args.steps, "repeats": args.repeats},
              "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                          "loadavg_at_end": [round(x, 2) for x in os.getloadavg()]}}
    if args.breakdown:
        result["track_step_breakdown_ms"] = breakdown()
        print("\nTrack step breakdown (ms, median):")
        for k, v in result["track_step_breakdown_ms"].items():
            print(f"  {k:32s} {v}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    print(f"\nwrote {args.json}")


def _main_ratios(args) -> None:
    out = []
    for env_id in args.ids:
        r = ratios(env_id, args.steps, args.repeats)
        out.append(r)
        print(f"{env_id:22s} vector-8/single {r['vector8_over_single']:.2f}  vector-8/sync-8 "
              f"{r['vector8_over_sync8']:.2f}  (1 thread: {r['vector8_1thread_over_single']:.2f}, "
              f"{r['vector8_1thread_over_sync8']:.2f})  runs {r['runs']}  split {r['vector8_split_us_per_env_step']}"
              f"  split 1 thread {r['vector8_1thread_split_us_per_env_step']}", flush=True)
    print("\n| id | threads | vector-8 / single | vector-8 / sync-8 | vector-8 us per env-step: total / render / "
          "skinning / Python |\n|---|---|---|---|---|")
    for r in out:
        for label, suffix in (("all", ""), ("1", "_1thread")):
            s = r[f"vector8{suffix}_split_us_per_env_step"]
            print(f"| {r['id']} | {label} | {r[f'vector8{suffix}_over_single']:.2f} | "
                  f"{r[f'vector8{suffix}_over_sync8']:.2f} | "
                  f"{s['total_us']} / {s['render_us']} / {s['skinning_us']} / {s['python_us']} |")
    path = args.json if args.json != RESULTS / "envs.json" else RESULTS / "envs_ratios.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"ratios": out, "steps_per_run": args.steps, "rounds": args.repeats,
                                "machine": {"cpus": os.cpu_count(),
                                            "loadavg_at_end": [round(x, 2) for x in os.getloadavg()]}},
                               indent=2) + "\n")
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
