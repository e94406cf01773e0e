"""Ground-truth worlds vs reconstructed ("fit") worlds on the Track suite, and the scene-pool build
time serial vs parallel.

    python benchmarks/fit_worlds.py                         # table + benchmarks/results/fit_worlds.json
    python benchmarks/fit_worlds.py --episodes 12 --pool 4 --workers 2

1. Pool build: the fit worlds of the first `--pool` episode seeds of the Track suite, built on a
   cold cache once serially (one process, one thread) and once with `--workers` processes
   (`envs.pool.build_scenes`), one after the other in this run; the scenes must be bit-identical.
2. Sim-to-sim gap: `morphosim bench`'s runner (policies `--policies`) on the Track suite (its base condition and the
   `--conditions` perturbations) with the same episode seeds, scene prompts and scene seeds in
   both worlds: the oracle worlds (the generator's ground truth, `reconstruction="oracle"`) and
   the fit worlds (`reconstruction="fit"`, preset `--preset`, reconstructed from the clips; the
   pool of step 1 is reused through the cache). Success and return with 95% bootstrap intervals,
   and the paired fit-minus-oracle difference (resampling seeds, so the pairing is kept).

Both worlds use the same smaller clips (`--frames` frames of `--size` px, detail 0.35; the
suite's own clips are 49 frames of 128 px) so the fits fit the time budget; the env observes
`--obs-size` px (default `--size`). The fits use the priors a procedural clip carries (`priors="auto"`: the generator's
rendered depth, masks and tracks, i.e. ground-truth priors, reported as such in the JSON);
`--priors estimated` estimates them from the frames instead. The oracle policy reads the target
position from the world it runs in (in a fit world: the fitted Gaussians of the target).

A saved SB3 policy (`--ppo MODEL.zip`, from examples/train_ppo_track.py) runs as the policy
`morphosim_gym.policies.sb3:policy_from_env` (shown as "ppo"); it needs the env at its training
size (`--obs-size 64`). Its episodes are 30 steps here (25-frame clips), half the 60 of its training
episodes. `--cache DIR` keeps the generated clips and fits between runs (default: a temporary folder),
and `--keep-rows` keeps the rows of other policies already in `--out` (with their own settings).

    python benchmarks/fit_worlds.py --episodes 12 --skip-pool --obs-size 64 --policies \
        --ppo DIR/ppo_track_model.zip --keep-rows --cache .cache/fit_worlds
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from dataclasses import replace
from pathlib import Path


RESULTS = Path(__file__).resolve().parent / "results"
PPO_SPEC = "morphosim_gym.policies.sb3:policy_from_env"
SHOWN = {PPO_SPEC: "ppo"}                      # policy spec -> the name in the table and the rows


def _suite(args: argparse.Namespace, world: dict):
    from morphosim_gym.bench import load_suite

    suite = load_suite("track")
    keep = [p for p in suite.perturbations if p.name in args.conditions]
    size = args.obs_size or args.size
    return replace(suite, perturbations=tuple(keep), env_kwargs={"width": size, "height": size},
                   frames=0, episodes=args.episodes).with_world(**world)


def _worlds(args: argparse.Namespace) -> dict[str, dict]:
    generation = {"num_frames": args.frames, "width": args.size, "height": args.size}
    fit_cfg = args.preset
    if args.priors != "auto":
        from morphosim_gym.reconstruct.presets import RECONSTRUCTION_PRESETS

        fit_cfg = replace(RECONSTRUCTION_PRESETS[args.preset], priors=args.priors)
    return {"oracle": {"reconstruction": "oracle", "generation": generation},
            "fit": {"reconstruction": "fit", "reconstruction_config": fit_cfg, "generation": generation}}


def pool_timing(args: argparse.Namespace, world: dict, cache_root: Path) -> dict:
    """Serial vs parallel build of the fit worlds of the first `args.pool` seeds (cold caches)."""
    from morphosim_gym.bench.episode import make_sim
    from morphosim_gym.bench.perturb import sample_episode
    from morphosim_gym.envs.pool import build_scenes

    suite = _suite(args, world)
    keys = [(ep.request.prompt, ep.scene_seed) for ep in (sample_episode(suite, s) for s in suite.seeds[:args.pool])]
    out: dict = {"scenes": len(keys), "workers": args.workers, "prompts": [k[0] for k in keys]}
    hashes = {}
    for label, workers in (("serial", 1), ("parallel", args.workers)):
        sim = make_sim(suite, str(cache_root / label))
        start = time.perf_counter()
        scenes = build_scenes(sim, keys, workers=workers, progress=True, timeout_s=3600)
        out[f"{label}_s"] = round(time.perf_counter() - start, 1)
        hashes[label] = [s.content_hash() for s in scenes]
        if label == "serial":
            out["priors"] = getattr(scenes[0], "_fit_log", {}).get("priors")
    out["speedup"] = round(out["serial_s"] / out["parallel_s"], 2)
    out["identical"] = hashes["serial"] == hashes["parallel"]
    return out


def sweep(args: argparse.Namespace, name: str, world: dict, cache_dir: Path, out_root: Path) -> dict:
    """One world's sweep; per-seed records and per-condition summaries."""
    from morphosim_gym.bench import run_sweep

    suite = _suite(args, world)
    start = time.perf_counter()
    result = run_sweep(suite, list(args.policies), out_root / name, workers=args.workers, cache_dir=str(cache_dir),
                       progress=True, report=False)
    return {"wall_s": round(time.perf_counter() - start, 1), "failed": result.failed,
            "errors": sorted({r["error"] for r in result.records if r["error"]})[:5],
            "records": [{k: r[k] for k in ("policy", "perturbation", "seed", "status", "success", "return", "prompt")}
                        for r in result.records]}


def gap(worlds: dict[str, dict], conditions: list[str], policies: list[str]) -> list[dict]:
    """Per policy and condition: success and return in each world, and the paired fit - oracle difference."""
    from morphosim_gym.bench.stats import bootstrap_mean

    rows = []
    for policy, cond in ((p, c) for p in policies for c in conditions):
        by = {w: {r["seed"]: r for r in worlds[w]["records"]
                  if r["policy"] == policy and r["perturbation"] == cond and r["status"] == "ok"} for w in worlds}
        row: dict = {"policy": SHOWN.get(policy, policy), "condition": cond}
        for w, recs in by.items():
            row[w] = {"success": bootstrap_mean([float(r["success"]) for r in recs.values()]).as_dict(),
                      "return": bootstrap_mean([float(r["return"]) for r in recs.values()]).as_dict()}
        seeds = sorted(set(by["oracle"]) & set(by["fit"]))
        row["paired"] = {m: bootstrap_mean([float(by["fit"][s][m]) - float(by["oracle"][s][m]) for s in seeds]).as_dict()
                         for m in ("success", "return")}
        rows.append(row)
    return rows


def _fmt(i: dict, pct: bool = False) -> str:
    if i["mean"] is None:
        return "n/a"
    k = 100.0 if pct else 1.0
    return f"{i['mean'] * k:.0f}% [{i['low'] * k:.0f}, {i['high'] * k:.0f}]" if pct else \
        f"{i['mean']:.1f} [{i['low']:.1f}, {i['high']:.1f}]"


def _run_name(args: argparse.Namespace) -> str:
    """The sweep folder of these settings (the runner refuses to resume another suite's folder)."""
    return f"obs{args.obs_size or args.size}_" + "_".join(sorted(SHOWN.get(p, p) for p in args.policies))


def _merge(out: Path, result: dict) -> dict:
    """`result` with the rows of the other policies of an earlier `out` (their run kept under `earlier_runs`)."""
    if not out.is_file():
        return result
    old = json.loads(out.read_text())
    mine = {r["policy"] for r in result["gap"]}
    kept = [dict(r, run=r.get("run", "earlier")) for r in old.get("gap", []) if r["policy"] not in mine]
    earlier = old.pop("earlier_runs", [])
    old.pop("gap", None)
    if kept:
        earlier = earlier + [old]
    return dict(result, gap=kept + [dict(r, run="this") for r in result["gap"]], earlier_runs=earlier)


def table(rows: list[dict]) -> str:
    head = ("| policy | condition | success, oracle worlds | success, fit worlds | fit - oracle (paired) | return, oracle worlds "
            "| return, fit worlds | fit - oracle (paired) | n |\n|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in rows:
        lines.append(f"| {r['policy']} | {r['condition']} | {_fmt(r['oracle']['success'], True)} | {_fmt(r['fit']['success'], True)} | "
                     f"{_fmt(r['paired']['success'], True)} | {_fmt(r['oracle']['return'])} | "
                     f"{_fmt(r['fit']['return'])} | {_fmt(r['paired']['return'])} | {r['paired']['success']['n']} |")
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--episodes", type=int, default=6, help="episode seeds per condition and world")
    p.add_argument("--pool", type=int, default=2, help="scenes in the serial-vs-parallel pool build")
    p.add_argument("--workers", type=int, default=2, help="worker processes (pool build and sweeps)")
    p.add_argument("--frames", type=int, default=25, help="clip frames of both worlds (8 fps)")
    p.add_argument("--size", type=int, default=48, help="clip and observation size, pixels")
    p.add_argument("--preset", default="fast", choices=["fast", "full"], help="reconstruction preset")
    p.add_argument("--priors", default="auto", choices=["auto", "estimated"],
                   help="reconstruction priors: the clip's (ground truth for procedural clips) or estimated")
    p.add_argument("--conditions", nargs="*", default=["recolor_target", "remove_distractor", "camera_shift"],
                   help="Track-suite perturbations besides the base")
    p.add_argument("--policies", nargs="*", default=["oracle", "color"],
                   help="policy specs (morphosim_gym.policies): oracle reads the world's target position, color "
                        "finds the target's colour in the image")
    p.add_argument("--skip-pool", action="store_true", help="skip the serial-vs-parallel build")
    p.add_argument("--obs-size", type=int, default=None, help="observation size, pixels (default: --size)")
    p.add_argument("--ppo", default=None, metavar="MODEL.zip",
                   help="also run this saved SB3 policy (examples/train_ppo_track.py) as 'ppo'")
    p.add_argument("--cache", default=None, help="keep clips and fits in this folder (default: a temporary one)")
    p.add_argument("--keep-rows", action="store_true",
                   help="keep the rows of other policies already in --out (and their run's settings)")
    p.add_argument("--out", default=str(RESULTS / "fit_worlds.json"))
    args = p.parse_args()
    os.environ.setdefault("MORPHOSIM_ASSET_SOURCES", "")      # the procedural generator, as the test suite
    if args.ppo:
        os.environ["MORPHOSIM_SB3_POLICY"] = str(Path(args.ppo).resolve())   # read by policy_from_env (workers too)
        args.policies = list(args.policies) + [PPO_SPEC]
    if not args.policies:
        p.error("expected at least one policy (--policies or --ppo)")
    start = time.perf_counter()
    worlds = _worlds(args)
    with tempfile.TemporaryDirectory(prefix="fit_worlds_") as tmp:
        root = Path(args.cache) if args.cache else Path(tmp)
        pool = None if args.skip_pool else pool_timing(args, worlds["fit"], root / "pool")
        cache = root / "pool" / "parallel"                    # the parallel pool's fits are reused
        runs = {name: sweep(args, name, w, cache, root / "out" / _run_name(args)) for name, w in worlds.items()}
    rows = gap(runs, ["base"] + list(args.conditions), list(args.policies))
    worlds_json = {k: {kk: (vv if isinstance(vv, (str, dict)) else repr(vv)) for kk, vv in v.items()}
                   for k, v in worlds.items()}
    result = {"machine": f"{platform.machine()}, {os.cpu_count()} cores, shared with other jobs (loaded)",
              "load_avg_start": os.getloadavg()[0], "settings": vars(args), "worlds": worlds_json,
              "pool_build": pool, "gap": rows, "sweeps": runs, "total_s": round(time.perf_counter() - start, 1)}
    if args.keep_rows:
        result = _merge(Path(args.out), result)
        rows = result["gap"]
    print(table(rows))
    if pool:
        print(f"\npool build of {pool['scenes']} fit scenes: serial {pool['serial_s']} s, {pool['workers']} workers "
              f"{pool['parallel_s']} s (x{pool['speedup']}; identical scenes: {pool['identical']}); priors "
              f"{pool.get('priors')}")
    for name, r in runs.items():
        print(f"{name} worlds sweep: {r['wall_s']} s, {r['failed']} failed {r['errors']}")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2, default=str) + "\n")
    print(f"-> {args.out}")


if __name__ == "__main__":
    main()
