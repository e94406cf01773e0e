"""Wall time of a short Stable-Baselines3 PPO run on Track-v0 with each way of vectorising the envs:
SB3's `DummyVecEnv` (8 single envs in one process, the example's choice), SB3's `SubprocVecEnv`
(one process per env) and our native batch (`SB3VecEnv` over `MorphoSimVectorEnv`: one batched
render per step, serial by default; "native-pipelined" with its render pipeline, `pipeline=2`).

    python benchmarks/ppo_walltime.py                          # 8k steps, every mode, 1 round
    python benchmarks/ppo_walltime.py --timesteps 4096 --rounds 3 --modes dummy native
    python benchmarks/ppo_walltime.py --timesteps 256 --pool 2 --modes dummy native   # a quick check

Settings as examples/train_ppo_track.py: 64 px RGB only, 8 envs, frame stack 3, PPO CnnPolicy with
n_steps=128, batch 256, 4 epochs, on the CPU (torch on every core). Each run reports the time to
build the envs and the time of `learn` (env steps plus the CNN updates); with `--rounds` > 1 the
modes alternate (A B C A B C ...). The table gives per mode the medians over rounds of the learn
time, of the learn steps per second and of the build time, and the speed-up over DummyVecEnv (the
synchronous baseline): DummyVecEnv's learn time over the mode's, per round, then the median.
Writes benchmarks/results/ppo_walltime.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path
from typing import Callable

RESULTS = Path(__file__).resolve().parent / "results"
MODES = ("dummy", "subproc", "native", "native-pipelined")
ENV_ID = "MorphoSim/Track-v0"


def _single_thunk(size: int, pool: int) -> Callable:
    def thunk():
        import gymnasium as gym

        import morphosim_gym  # noqa: F401  (registers the ids)
        from morphosim_gym.envs import RGBObservation

        return RGBObservation(gym.make(ENV_ID, width=size, height=size, scene_pool=pool, pool_seed=0))

    return thunk


def build(mode: str, n: int, size: int, pool: int):
    """The SB3 VecEnv of one mode (before frame stacking)."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    if mode == "dummy":
        return DummyVecEnv([_single_thunk(size, pool) for _ in range(n)])
    if mode == "subproc":
        return SubprocVecEnv([_single_thunk(size, pool) for _ in range(n)], start_method="spawn")
    if mode in ("native", "native-pipelined"):
        from morphosim_gym.envs import make_vec
        from morphosim_gym.envs.sb3_vec import SB3VecEnv

        extra = {"pipeline": 2} if mode == "native-pipelined" else {}
        return SB3VecEnv(make_vec(ENV_ID, n, vectorization_mode="vector", width=size, height=size, scene_pool=pool,
                                  pool_seed=0, **extra), obs_key="rgb")
    raise ValueError(f"Expected a mode in {MODES}, found {mode!r}")


def run(mode: str, timesteps: int, n: int, size: int, pool: int, stack: int, seed: int) -> dict:
    """Seconds to build the envs and to `learn` `timesteps` steps."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecFrameStack, VecMonitor

    torch.set_num_threads(max(1, os.cpu_count() or 1))
    t0 = time.perf_counter()
    venv = VecMonitor(build(mode, n, size, pool), info_keywords=("success",))
    if stack > 1:
        venv = VecFrameStack(venv, stack)
    venv.seed(seed)
    built = time.perf_counter() - t0
    model = PPO("CnnPolicy", venv, n_steps=128, batch_size=256, n_epochs=4, learning_rate=3e-4, gamma=0.95,
                gae_lambda=0.9, clip_range=0.2, ent_coef=0.0, vf_coef=0.5, seed=seed, verbose=0, device="cpu")
    t1 = time.perf_counter()
    model.learn(total_timesteps=timesteps)
    learn = time.perf_counter() - t1
    steps = int(model.num_timesteps)
    venv.close()
    return {"mode": mode, "build_s": round(built, 2), "learn_s": round(learn, 2), "timesteps": steps,
            "steps_per_s": round(steps / learn, 1)}


def summarise(runs: dict[str, list[dict]]) -> dict[str, dict]:
    """Per mode: medians over rounds of learn seconds, learn steps/s and build seconds, and (with
    "dummy" among the modes) the median per-round speed-up over DummyVecEnv's learn time."""
    out = {}
    for m, rs in runs.items():
        out[m] = {"learn_s_median": round(statistics.median(r["learn_s"] for r in rs), 2),
                  "steps_per_s_median": round(statistics.median(r["steps_per_s"] for r in rs), 1),
                  "build_s_median": round(statistics.median(r["build_s"] for r in rs), 2), "rounds": len(rs)}
        if "dummy" in runs:
            per_round = [d["learn_s"] / r["learn_s"] for d, r in zip(runs["dummy"], rs)]
            out[m]["speedup_over_dummy"] = round(statistics.median(per_round), 2)
    return out


def table(summary: dict[str, dict]) -> str:
    """The summary as a Markdown table."""
    lines = ["| mode | learn s (median) | steps/s (median) | build s (median) | speed-up over DummyVecEnv | rounds |",
             "|---|---|---|---|---|---|"]
    for m, s in summary.items():
        speedup = f"{s['speedup_over_dummy']:.2f}x" if "speedup_over_dummy" in s else ""
        lines.append(f"| {m} | {s['learn_s_median']:.2f} | {s['steps_per_s_median']:.0f} | {s['build_s_median']:.2f} "
                     f"| {speedup} | {s['rounds']} |")
    return "\n" + "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--timesteps", type=int, default=8192)
    ap.add_argument("--modes", nargs="*", default=list(MODES), choices=MODES)
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--n-envs", type=int, default=8)
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--pool", type=int, default=64, help="scene pool per env (the example's 64)")
    ap.add_argument("--frame-stack", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", type=Path, default=RESULTS / "ppo_walltime.json")
    args = ap.parse_args()
    try:
        import stable_baselines3  # noqa: F401
    except ImportError as exc:  # pragma: no cover
        raise SystemExit("Expected stable-baselines3 for this benchmark, found it missing; "
                         "pip install 'morphosim-gym[train]'") from exc

    runs: dict[str, list[dict]] = {m: [] for m in args.modes}
    for _ in range(args.rounds):
        for mode in args.modes:
            r = run(mode, args.timesteps, args.n_envs, args.size, args.pool, args.frame_stack, args.seed)
            runs[mode].append(r)
            print(f"{mode:16s} build {r['build_s']:7.1f}s  learn {r['learn_s']:7.1f}s  ({r['steps_per_s']:.0f} steps/s)",
                  flush=True)
    summary = summarise(runs)
    print(table(summary))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"runs": runs, "summary": summary, "settings": {k: str(v) for k, v in vars(args).items()},
                                     "machine": {"cpus": os.cpu_count(),
                                                 "loadavg_at_end": [round(x, 2) for x in os.getloadavg()]}},
                                    indent=2) + "\n")
    print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
