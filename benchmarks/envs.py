"""Env steps per second for every MorphoSim id: single env and 8-env vector envs, on today's
procedural scenes and on real-asset scenes.

    python benchmarks/envs.py                      # table + benchmarks/results/envs.json
    python benchmarks/envs.py --ids MorphoSim/Track-v0 --repeats 5 --breakdown
    python benchmarks/envs.py --scenes real --modes single vector-8 vector-32

Every number is the median of `--repeats` runs (the machine is shared and noisy; the
spread is reported too). Settings: default env arguments (84x84 rgb, detail 0.35, 10 Hz)
plus `scene_pool=8`, random actions, autoreset included (episodes are 60 steps, or shorter
for Reach/Find when they succeed). Scenes (`--scenes`): "procedural" (`assets="off"`, no sky: the
light scenes, as `MORPHOSIM_ASSET_SOURCES=""`) and "real" (the default `assets="auto"`: real
assets and an HDR sky where the asset packages are installed). Modes:

  single           one env (default `render_threads=1`)
  single-2threads  one env, `render_threads=None` (numba's default: both cores)
  single-fresh     one env without a pool: every reset composes a new scene (~30-60 ms)
  sync-8           SyncVectorEnv of 8 envs in one process
  async-8          AsyncVectorEnv of 8 envs, one process each (spawn)
  vector-8         the native MorphoSimVectorEnv of 8 envs: one process, one batched render of
                   all 8 cameras per step on all cores (the default scheduler "views": this
                   thread and a helper thread claim whole views, each rendered in one GIL-free
                   call; this thread finishes env i as soon as its view is done)
  vector-8-1thread the same with its batched render on one thread (no helper)
  vector-8-pipelined the same in two chunks (`pipeline=2`: the helper starts on the first half
                   while this thread prepares the second)
  vector-8-numba   the same with scheduler="numba" (one numba parallel region per stage over all
                   views: the default before 2026-12-02)
  vector-8-numba-pipelined  scheduler="numba", pipeline=2 (a worker thread renders each half)
  vector-32        the same with 32 envs

The table's "x single" column is each mode's median over the single env's median of the same id
and scene kind, from this run (the issue-#23 check: `--modes single sync-8 vector-8 vector-32`).
`--steps` counts all envs' steps together by default, so a vector env of 8 runs 1/8 of the
single env's steps per env and most of its window is every env's first episode, which is slower
(the pooled scenes' poses are not cached yet); `--per-env` gives every env `--steps` steps in
every mode, as a training run sees them past its first episode.

`--breakdown` times the parts of a Track step (skinning, rendering, kinematics, reward,
observation) by calling them directly. `--ratios` measures single, vector-8, sync-8,
vector-8-1thread, vector-8-pipelined, vector-8-numba and vector-32 alternately in one run (A B C A B C ...) and
reports per-round ratios (median) and the vector-8 cost split (batched render, skinning, the
rest: Python; measured serially) for each id and scene kind; on a shared machine only these
same-run ratios mean much.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import morphosim_gym as ms  # noqa: E402
from _envs_common import (SCENES, machine, render_and_skinning_timer, scene_kwargs, single_rollout,  # noqa: E402
                          vector_rollout)
from morphosim_gym.envs import ENV_IDS, make_vec  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
MODES = ("single", "single-2threads", "single-fresh", "sync-8", "async-8", "vector-8", "vector-8-1thread",
         "vector-8-pipelined", "vector-8-numba", "vector-8-numba-pipelined", "vector-32")


def _single(env_id: str, steps: int, **kw) -> float:
    env = gym.make(env_id, **kw)
    rate = steps / single_rollout(env, steps)
    env.close()
    return rate


def _vector(env_id: str, steps: int, mode: str, n: int = 8, **kw) -> float:
    venv = make_vec(env_id, n, vectorization_mode=mode, **kw)
    rate = steps * n / vector_rollout(venv, steps)
    venv.close()
    return rate


#: mode -> (vectorisation, number of envs or None for a single env, extra env arguments)
_MODE_TABLE = {
    "single": (None, None, {"scene_pool": 8}),
    "single-2threads": (None, None, {"scene_pool": 8, "render_threads": None}),
    "single-fresh": (None, None, {}),
    "sync-8": ("sync", 8, {"scene_pool": 8}),
    "async-8": ("async", 8, {"scene_pool": 8}),
    "vector-8": ("vector", 8, {"scene_pool": 8}),
    "vector-8-1thread": ("vector", 8, {"scene_pool": 8, "render_threads": 1}),
    "vector-8-pipelined": ("vector", 8, {"scene_pool": 8, "pipeline": 2}),
    "vector-8-numba": ("vector", 8, {"scene_pool": 8, "scheduler": "numba"}),
    "vector-8-numba-pipelined": ("vector", 8, {"scene_pool": 8, "scheduler": "numba", "pipeline": 2}),
    "vector-32": ("vector", 32, {"scene_pool": 8}),
}


def measure(env_id: str, mode: str, steps: int, scenes: str = "procedural", per_env: bool = False) -> float:
    """Env steps per second of one mode (`MODES`) on one scene kind (`SCENES`): over `steps` env
    steps in all, or with `per_env` over `steps` steps of every env (a vector env of n runs
    `steps` vector steps: each env sees as many episodes as the single env does)."""
    if mode not in _MODE_TABLE:
        raise ValueError(f"Expected a mode in {MODES}, found {mode!r}")
    how, n, kw = _MODE_TABLE[mode]
    kw = {**kw, **scene_kwargs(scenes)}
    if how is None:
        return _single(env_id, steps, **kw)
    return _vector(env_id, steps if per_env else max(1, steps // n), how, n=n, **kw)


def vector_split(env_id: str, steps: int, n: int = 8, render_threads=None, scenes: str = "procedural") -> dict:
    """Per env-step microseconds of a native vector env of n envs: batched render, skinning, rest
    (measured with scheduler="numba" and no pipeline, where the render is a phase of its own and
    the parts add up to the total; the default "views" scheduler overlaps them)."""
    timer = render_and_skinning_timer()
    venv = make_vec(env_id, n, vectorization_mode="vector", scene_pool=8, render_threads=render_threads,
                    pipeline=1, scheduler="numba", **scene_kwargs(scenes))   # the render does not overlap the rest
    try:
        total = vector_rollout(venv, steps, on_start=timer.install)
    finally:
        timer.uninstall()
    venv.close()
    per = 1e6 / (steps * n)
    render, skinning = timer.seconds["render"], timer.seconds["skinning"]
    return {"total_us": round(total * per, 1), "render_us": round(render * per, 1),
            "skinning_us": round(skinning * per, 1),
            "python_us": round((total - render - skinning) * per, 1)}


def ratios(env_id: str, steps: int, rounds: int, scenes: str = "procedural") -> dict:
    """The `RATIO_MODES` measured alternately (A B C ... A B C
    ...); per-round ratios and their medians, and the vector-8 cost splits."""
    runs: dict[str, list[float]] = {m: [] for m in RATIO_MODES}
    for _ in range(rounds):
        for mode in runs:
            runs[mode].append(measure(env_id, mode, steps, scenes))

    def ratio(a: str, b: str) -> list[float]:
        return [x / y for x, y in zip(runs[a], runs[b])]

    def split_of(render_threads) -> dict:
        splits = [vector_split(env_id, max(1, steps // 8), render_threads=render_threads, scenes=scenes)
                  for _ in range(rounds)]
        return {k: round(statistics.median(s[k] for s in splits), 1) for k in splits[0]}

    out = {"id": env_id, "scenes": scenes, "runs": {k: [round(x, 1) for x in v] for k, v in runs.items()},
           "round_ratios_single": [round(x, 2) for x in ratio("vector-8", "single")],
           "round_ratios_sync8": [round(x, 2) for x in ratio("vector-8", "sync-8")]}
    for key, (a, b) in _RATIOS.items():
        out[key] = round(statistics.median(ratio(a, b)), 2)
    out["vector8_split_us_per_env_step"] = split_of(None)
    out["vector8_1thread_split_us_per_env_step"] = split_of(1)
    return out


RATIO_MODES = ("single", "vector-8", "sync-8", "vector-8-1thread", "vector-8-pipelined", "vector-8-numba", "vector-32")
_RATIOS = {"vector8_over_single": ("vector-8", "single"), "vector8_over_sync8": ("vector-8", "sync-8"),
           "vector8_1thread_over_single": ("vector-8-1thread", "single"),
           "vector8_1thread_over_sync8": ("vector-8-1thread", "sync-8"),
           "vector8_pipelined_over_vector8": ("vector-8-pipelined", "vector-8"),
           "vector8_over_vector8_numba": ("vector-8", "vector-8-numba"),
           "vector8_numba_over_single": ("vector-8-numba", "single"),
           "vector32_over_single": ("vector-32", "single")}


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


def add_ratios_to_single(rows: list[dict]) -> None:
    """Set each row's "ratio_to_single": its median over the "single" row of the same id and scene
    kind (medians of runs taken in this process; None without a single row)."""
    single = {(r["id"], r["scenes"]): r["steps_per_s"] for r in rows if r["mode"] == "single"}
    for r in rows:
        base = single.get((r["id"], r["scenes"]))
        r["ratio_to_single"] = round(r["steps_per_s"] / base, 2) if base else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ids", nargs="*", default=list(ENV_IDS))
    ap.add_argument("--modes", nargs="*", default=list(MODES), choices=MODES)
    ap.add_argument("--scenes", nargs="*", default=list(SCENES), choices=SCENES)
    ap.add_argument("--steps", type=int, default=800, help="env steps per run (vector: total over all envs)")
    ap.add_argument("--per-env", action="store_true",
                    help="--steps counts each env's steps (vector envs run that many vector steps): every env "
                         "sees as many episodes as the single env, past its first, cold episode, as in a long run")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--breakdown", action="store_true")
    ap.add_argument("--ratios", action="store_true",
                    help="only the same-run ratios of RATIO_MODES (single, vector-8, sync-8, ...)")
    ap.add_argument("--json", type=Path, default=RESULTS / "envs.json")
    args = ap.parse_args()

    if args.ratios:
        return _main_ratios(args)
    rows = []
    for scenes in args.scenes:
        for env_id in args.ids:
            for mode in args.modes:
                rates = [measure(env_id, mode, args.steps, scenes, args.per_env) for _ in range(args.repeats)]
                row = {"id": env_id, "scenes": scenes, "mode": mode, "steps_per_s": round(statistics.median(rates), 1),
                       "min": round(min(rates), 1), "max": round(max(rates), 1), "runs": [round(r, 1) for r in rates]}
                rows.append(row)
                print(f"{env_id:22s} {scenes:10s} {mode:16s} {row['steps_per_s']:8.1f} steps/s  (runs {row['runs']})",
                      flush=True)

    add_ratios_to_single(rows)
    print("\n| id | scenes | mode | steps/s (median) | min | max | x single |\n|---|---|---|---|---|---|---|")
    for r in rows:
        ratio = "" if r["ratio_to_single"] is None else f"{r['ratio_to_single']:.2f}"
        print(f"| {r['id']} | {r['scenes']} | {r['mode']} | {r['steps_per_s']:.0f} | {r['min']:.0f} | {r['max']:.0f} "
              f"| {ratio} |")
    result = {"rows": rows, "settings": {"obs": "rgb 84x84 + proprio", "detail": 0.35, "control_hz": 10,
                                         "scene_pool": 8, "steps_per_run": args.steps, "steps_per_env": args.per_env,
                                         "repeats": args.repeats},
              "machine": machine()}
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
    for scenes in args.scenes:
        for env_id in args.ids:
            r = ratios(env_id, args.steps, args.repeats, scenes)
            out.append(r)
            print(f"{env_id:22s} {scenes:10s} vector-8/single {r['vector8_over_single']:.2f}  vector-8/sync-8 "
                  f"{r['vector8_over_sync8']:.2f}  vector-8-pipelined/vector-8 {r['vector8_pipelined_over_vector8']:.2f}  "
                  f"vector-32/single {r['vector32_over_single']:.2f}  vector-8/vector-8-numba "
                  f"{r['vector8_over_vector8_numba']:.2f} (numba/single {r['vector8_numba_over_single']:.2f})  "
                  f"(1 thread: {r['vector8_1thread_over_single']:.2f}, {r['vector8_1thread_over_sync8']:.2f})  "
                  f"runs {r['runs']}  split {r['vector8_split_us_per_env_step']}"
                  f"  split 1 thread {r['vector8_1thread_split_us_per_env_step']}", flush=True)
    print("\n| id | scenes | threads | vector-8 / single | vector-8 / sync-8 | vector-32 / single | vector-8 us per "
          "env-step: total / render / skinning / Python |\n|---|---|---|---|---|---|---|")
    for r in out:
        for label, suffix in (("all", ""), ("1", "_1thread")):
            s = r[f"vector8{suffix}_split_us_per_env_step"]
            v32 = f"{r['vector32_over_single']:.2f}" if not suffix else ""
            print(f"| {r['id']} | {r['scenes']} | {label} | {r[f'vector8{suffix}_over_single']:.2f} | "
                  f"{r[f'vector8{suffix}_over_sync8']:.2f} | {v32} | "
                  f"{s['total_us']} / {s['render_us']} / {s['skinning_us']} / {s['python_us']} |")
    path = args.json if args.json != RESULTS / "envs.json" else RESULTS / "envs_ratios.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"ratios": out, "steps_per_run": args.steps, "rounds": args.repeats,
                                "machine": machine()}, indent=2) + "\n")
    print(f"\nwrote {path}")


if __name__ == "__main__":
    main()
