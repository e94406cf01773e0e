"""Train Stable-Baselines3 PPO (CnnPolicy, pixels only) on MorphoSim/Track-v0 and compare it with a
random policy on held-out scenes.

    pip install -e ".[train]"            # stable-baselines3
    python examples/train_ppo_track.py                       # 12-23 min on a 2-core CPU
    python examples/train_ppo_track.py --timesteps 20000 --budget-min 5   # a quick look

What it does:
  * training envs: Track-v0 at 64x64 rgb (smaller than the 84x84 default, to fit the CPU
    budget: the CNN update dominates the wall time), a pool of 64 pre-built scenes from the
    task's scene distribution (pool seed 0), the policy sees only the image;
  * PPO with the default Nature CNN on the last 3 frames (VecFrameStack, so the policy sees
    the motion), 8 envs x 128 steps per update; training stops at
    `--timesteps` or after `--budget-min` minutes of wall time, whichever comes first;
  * evaluation on 32 held-out scenes (a different pool seed, never trained on), 32 episodes
    each for the trained policy (deterministic actions) and the built-in `random` policy of
    `morphosim_gym.policies` (uniform actions drawn from each episode's reset seed), same reset
    seeds; both run as policy factories `factory(env, seed) -> act(obs, info)`, the protocol of
    `morphosim bench` and `morphosim view`; success = the task's episode-level success (target centred on >= 70% of
    the steps) at the end of the episode;
  * writes <out>/ppo_track.json (settings, wall times, success rates, returns) and
    <out>/ppo_track_curve.png (learning curve with the random baseline); with `--randomize` the
    files are ppo_track_randomized*; `--stem` names them otherwise;
  * saves the trained policy as <out>/<stem>_model.zip (SB3 `model.save`) with the observation
    settings beside it (<stem>_model.json: 64 px rgb, frame stack, zero padding), which
    `morphosim_gym.policies.sb3.sb3_policy(path)` turns back into a policy factory for
    `morphosim bench` (`benchmarks/ppo_axes.py` compares two of them on every axis);
    `--save-every N` also saves checkpoints every N steps.

The measured pair (README, "PPO trained with against without randomisation"):

    python examples/train_ppo_track.py --timesteps 100000 --budget-min 999 --threads 1 --out DIR_A
    python examples/train_ppo_track.py --randomize track --timesteps 100000 --budget-min 999 --threads 1 --out DIR_B
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).resolve().parent / "results"


def make_env(pool_seed: int, pool: int, size: int, randomize: str | None = None):
    import gymnasium as gym

    import morphosim_gym  # noqa: F401  (registers the ids)
    from morphosim_gym.envs import AxisRandomization, RGBObservation

    def thunk():
        env = gym.make("MorphoSim/Track-v0", width=size, height=size, scene_pool=pool, pool_seed=pool_seed)
        if randomize:                    # perturbation axes drawn per episode (tasks/randomization/NAME.yaml)
            env = AxisRandomization(env, randomize)
        return RGBObservation(env)

    return thunk


def evaluate(policy, pool_seed: int, pool: int, size: int, episodes: int, seed0: int, stack: int = 1) -> dict:
    """Run `episodes` episodes of a policy factory (a built-in name, "module:callable" or
    `factory(env, seed) -> act(obs, info)`, see `morphosim_gym.policies`), called once per episode
    with its reset seed; obs: the last `stack` frames along channels."""
    from morphosim_gym.policies import policy_for_episode, resolve_policy

    factory = resolve_policy(policy)
    env = make_env(pool_seed, pool, size)()
    if stack > 1:
        from gymnasium.wrappers import FrameStackObservation, TransformObservation

        env = FrameStackObservation(env, stack, padding_type="zero")  # [stack, H, W, 3], oldest first, zeros at reset as SB3
        h, w, c = env.observation_space.shape[1:]
        import gymnasium as gym

        space = gym.spaces.Box(0, 255, (h, w, c * stack), np.uint8)
        env = TransformObservation(env, lambda o: np.concatenate(list(o), axis=-1), space)
    succ, frac, ret = [], [], []
    for ep in range(episodes):
        obs, info = env.reset(seed=seed0 + ep)
        act = policy_for_episode(factory, env, seed0 + ep)
        total = 0.0
        while True:
            obs, r, term, trunc, info = env.step(act(obs, info))
            total += r
            if term or trunc:
                break
        succ.append(bool(info["success"]))
        frac.append(float(info["centred_fraction"]))
        ret.append(total)
    env.close()
    return {"success_rate": float(np.mean(succ)), "centred_fraction": float(np.mean(frac)),
            "mean_return": float(np.mean(ret)), "episodes": episodes}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--timesteps", type=int, default=200_000)
    ap.add_argument("--budget-min", type=float, default=21.0, help="wall-clock cap on training, minutes")
    ap.add_argument("--n-envs", type=int, default=8)
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--pool", type=int, default=64)
    ap.add_argument("--eval-episodes", type=int, default=32)
    ap.add_argument("--frame-stack", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=RESULTS)
    ap.add_argument("--replot", action="store_true", help="only redraw the plot from saved results")
    ap.add_argument("--randomize", default=None, metavar="NAME",
                    help="train under axis randomisation (a tasks/randomization name such as 'track', or a YAML path)")
    ap.add_argument("--threads", type=int, default=None, help="torch threads (default: all CPU cores)")
    ap.add_argument("--stem", default=None,
                    help="output file stem (default: ppo_track, or ppo_track_randomized with --randomize)")
    ap.add_argument("--save-every", type=int, default=0, metavar="STEPS",
                    help="also save the policy every STEPS env steps (a multiple of n_envs*128), as "
                         "<stem>_model_<steps>.zip; the learning rate and clip range are constant, so such a "
                         "checkpoint equals the policy of a run with --timesteps STEPS")
    args = ap.parse_args()
    args.stem = args.stem or ("ppo_track_randomized" if args.randomize else "ppo_track")
    if args.replot:
        replot(args.out)
        return

    try:
        import torch
        from stable_baselines3 import PPO
        from stable_baselines3.common.callbacks import BaseCallback
        from stable_baselines3.common.vec_env import DummyVecEnv, VecFrameStack, VecMonitor
    except ImportError as exc:  # pragma: no cover
        raise SystemExit("Expected stable-baselines3 for this example, found it missing; "
                         "pip install 'morphosim-gym[train]'") from exc

    torch.set_num_threads(args.threads or max(1, os.cpu_count() or 1))
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()

    venv = VecMonitor(DummyVecEnv([make_env(0, args.pool, args.size, args.randomize) for _ in range(args.n_envs)]),
                      info_keywords=("success", "centred_fraction"))
    if args.frame_stack > 1:
        venv = VecFrameStack(venv, args.frame_stack)          # the last frames, so the policy sees motion
    venv.seed(args.seed)
    built = time.perf_counter() - start
    print(f"envs ready in {built:.1f}s", flush=True)

    curve: list[dict] = []

    class Log(BaseCallback):
        def __init__(self, budget_s: float):
            super().__init__()
            self.budget_s = budget_s
            self.t0 = time.perf_counter()

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", []):
                ep = info.get("episode")
                if ep is not None:
                    curve.append({"timesteps": int(self.num_timesteps), "return": float(ep["r"]),
                                  "success": bool(info.get("success")),
                                  "centred_fraction": float(info.get("centred_fraction", 0.0)),
                                  "wall_s": round(time.perf_counter() - self.t0, 1)})
            return time.perf_counter() - self.t0 < self.budget_s

        def _on_rollout_start(self) -> None:   # after the previous update: a run's state at num_timesteps
            n = int(self.num_timesteps)
            if args.save_every and n and n % args.save_every == 0:
                save_policy(self.model, args, suffix=f"_{n}")

        def _on_rollout_end(self) -> None:
            recent = curve[-32:]
            if recent:
                print(f"t={self.num_timesteps:7d}  wall={time.perf_counter() - self.t0:6.0f}s  "
                      f"return={np.mean([c['return'] for c in recent]):6.2f}  "
                      f"success={np.mean([c['success'] for c in recent]):.2f}  "
                      f"centred={np.mean([c['centred_fraction'] for c in recent]):.2f}", flush=True)

    model = PPO("CnnPolicy", venv, n_steps=128, batch_size=256, n_epochs=4, learning_rate=3e-4, gamma=0.95,
                gae_lambda=0.9, clip_range=0.2, ent_coef=0.0, vf_coef=0.5, seed=args.seed, verbose=0,
                device="cpu")
    t_train = time.perf_counter()
    model.learn(total_timesteps=args.timesteps, callback=Log(args.budget_min * 60.0))
    train_s = time.perf_counter() - t_train
    trained_steps = int(model.num_timesteps)
    venv.close()
    print(f"trained {trained_steps} steps in {train_s:.0f}s", flush=True)
    model_path = save_policy(model, args)
    print(f"saved the policy to {model_path}", flush=True)

    t_eval = time.perf_counter()
    def trained_policy(env, seed):
        return lambda obs, info: model.predict(obs, deterministic=True)[0]

    trained = evaluate(trained_policy, 1, 32, args.size, args.eval_episodes, 10_000, args.frame_stack)
    random = evaluate("random", 1, 32, args.size, args.eval_episodes, 10_000)
    eval_s = time.perf_counter() - t_eval
    total_s = time.perf_counter() - start
    print(f"trained: {trained}\nrandom:  {random}\ntotal wall {total_s:.0f}s", flush=True)

    result = {
        "env": "MorphoSim/Track-v0", "obs": f"rgb {args.size}x{args.size} only (RGBObservation)",
        "randomize": args.randomize,
        "algo": "stable-baselines3 PPO CnnPolicy (NatureCNN)",
        "frame_stack": args.frame_stack,
        "ppo": {"n_envs": args.n_envs, "n_steps": 128, "batch_size": 256, "n_epochs": 4, "learning_rate": 3e-4,
                "gamma": 0.95, "gae_lambda": 0.9, "clip_range": 0.2, "ent_coef": 0.0},
        "train_scenes": {"scene_pool": args.pool, "pool_seed": 0},
        "eval_scenes": {"scene_pool": 32, "pool_seed": 1, "reset_seeds": f"10000..{10000 + args.eval_episodes - 1}"},
        "timesteps_trained": trained_steps, "timesteps_requested": args.timesteps,
        "wall_s": {"build_envs": round(built, 1), "train": round(train_s, 1), "eval": round(eval_s, 1),
                   "total": round(total_s, 1)},
        "trained": trained, "random": random,
        "success_definition": "target centred (within 0.15 half-image of the centre, visible) on >= 70% of steps",
        "machine": f"{os.cpu_count()} CPU cores, torch {torch.__version__}",
        "loadavg_at_end": [round(x, 2) for x in os.getloadavg()],
    }
    result["model"] = {"zip": model_path.name, "settings": model_path.with_suffix(".json").name}
    (args.out / f"{args.stem}.json").write_text(json.dumps(result, indent=2) + "\n")
    (args.out / f"{args.stem}_curve.json").write_text(json.dumps(curve) + "\n")
    plot(curve, random, trained, args.out / f"{args.stem}_curve.png")
    print(f"wrote {args.out / (args.stem + '.json')} and {args.out / (args.stem + '_curve.png')}")


def policy_settings(args) -> dict:
    """What `morphosim_gym.policies.sb3` needs to rebuild the policy's observations exactly."""
    return {"format": "morphosim-sb3-policy/1", "algo": "PPO", "env_id": "MorphoSim/Track-v0",
            "width": args.size, "height": args.size, "observation": "rgb",
            "frame_stack": args.frame_stack, "frame_stack_padding": "zero", "deterministic": True,
            "randomize": args.randomize, "seed": args.seed, "timesteps_requested": args.timesteps,
            "train_scenes": {"scene_pool": args.pool, "pool_seed": 0}}


def save_policy(model, args, suffix: str = "") -> Path:
    """Save the SB3 model as <out>/<stem>_model<suffix>.zip with its observation settings next to it (.json)."""
    path = args.out / f"{args.stem}_model{suffix}.zip"
    model.save(path)
    settings = {**policy_settings(args), "timesteps_trained": int(model.num_timesteps)}
    path.with_suffix(".json").write_text(json.dumps(settings, indent=2) + "\n")
    return path


def plot(curve: list[dict], random: dict, trained: dict, path: Path) -> None:
    """Learning curve: training episodes' return and centred fraction, with the held-out evaluation
    of the trained and the random policy (returns, centred fractions and success rates)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if not curve:
        return
    t = np.array([c["timesteps"] for c in curve])
    ret = np.array([c["return"] for c in curve])
    frac = np.array([c["centred_fraction"] for c in curve])
    k = max(1, min(32, len(curve) // 5))
    kernel = np.ones(k) / k
    smooth = lambda x: np.convolve(x, kernel, mode="valid")  # noqa: E731
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    axes[0].plot(t, ret, ".", alpha=0.2, color="tab:blue")
    axes[0].plot(t[k - 1:], smooth(ret), color="tab:blue", label=f"PPO training (mean of {k} episodes)")
    axes[0].axhline(trained["mean_return"], color="tab:green", ls=":", label="trained, held-out eval")
    axes[0].axhline(random["mean_return"], color="tab:red", ls="--", label="random, held-out eval")
    axes[0].set_xlabel("env steps")
    axes[0].set_ylabel("episode return (60 steps)")
    axes[0].legend(fontsize=8)
    axes[1].plot(t[k - 1:], smooth(frac), color="tab:blue", label="PPO training: centred fraction")
    axes[1].axhline(trained["centred_fraction"], color="tab:green", ls=":", label="trained, eval: centred fraction")
    axes[1].axhline(random["centred_fraction"], color="tab:red", ls="--", label="random, eval: centred fraction")
    axes[1].bar([t[-1] * 1.04], [trained["success_rate"]], width=t[-1] * 0.03, color="tab:green", alpha=0.6,
                label=f"trained, eval: success rate {trained['success_rate']:.2f}")
    axes[1].bar([t[-1] * 1.08], [max(random["success_rate"], 0.005)], width=t[-1] * 0.03, color="tab:red",
                alpha=0.6, label=f"random, eval: success rate {random['success_rate']:.2f}")
    axes[1].set_xlabel("env steps")
    axes[1].set_ylabel("fraction of steps centred / success rate")
    axes[1].set_ylim(-0.02, 1.02)
    axes[1].legend(fontsize=8, loc="upper left")
    from matplotlib.ticker import FuncFormatter

    for ax in axes:
        ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x / 1000:.0f}k"))
    fig.suptitle("MorphoSim/Track-v0, PPO CnnPolicy from pixels (success: centred on >= 70% of steps)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def replot(out: Path) -> None:
    """Redraw the plot from the saved results (no training)."""
    for stem in ("ppo_track", "ppo_track_randomized"):
        if (out / f"{stem}.json").exists():
            result = json.loads((out / f"{stem}.json").read_text())
            curve = json.loads((out / f"{stem}_curve.json").read_text())
            plot(curve, result["random"], result["trained"], out / f"{stem}_curve.png")


if __name__ == "__main__":
    main()
