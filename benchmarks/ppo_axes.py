"""PPO trained with axis randomisation vs without, on every axis of the Track axis suite (paired).

    python examples/train_ppo_track.py --timesteps T --budget-min 999 --out DIR_A
    python examples/train_ppo_track.py --randomize track --timesteps T --budget-min 999 --out DIR_B
    python benchmarks/ppo_axes.py --baseline DIR_A/ppo_track_model.zip \\
        --randomized DIR_B/ppo_track_randomized_model.zip --episodes 32

What it runs: `morphosim bench`'s runner on `tasks/suites/axes_track.yaml` (every axis of
`tasks/axes.py`, each paired with the base episode of the same seed), once per policy, both with
`--policy morphosim_gym.policies.sb3:policy_from_env` (the saved model named by
MORPHOSIM_SB3_POLICY), on the same suite file: the same episode seeds, scene prompts, scene seeds and
edits for both policies. The suite is derived from axes_track: its envs render at the policies'
training size (from the models' settings JSON, 64 px; axes_track itself uses 48 px), no frame
strips, `--episodes` seeds from `--seed`.

Held-out scenes: the policies were trained on a pool of 64 scenes of the Track task's own scene
distribution (pool seed 0, prompts "a {color} {object} {motion}", no distractor); the suite draws its
scenes from its own template ("... next to {distractor}", one distractor each), so no evaluation scene
is a training scene (checked below: no (prompt, scene seed) in common with the training pool).

Report, per axis: success and return of each policy, and the paired difference randomised - baseline
(per seed, same episode) with 95% bootstrap intervals over seeds (`bench.stats.bootstrap_mean`), and the
difference of the drops (randomised (axis - base) - baseline (axis - base)); then the same pooled
over the axes trained on (those `tasks/randomization/track.yaml` draws), its four held-out axes, and
the suite axes it neither draws nor holds out (seed-level means over the group's axes, bootstrapped
over seeds). Output: benchmarks/results/ppo_axes.{json,md}; sweeps are resumable under --work.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
POLICY_SPEC = "morphosim_gym.policies.sb3:policy_from_env"
LABELS = ("baseline", "randomized")
GROUPS = ("trained", "held_out", "not_randomized")


def derived_suite(size: tuple[int, int], episodes: int, seed: int, axes: list[str] | None = None):
    """axes_track at the policies' image size, without frame strips (only `axes`, if given)."""
    from morphosim_gym.bench import load_suite

    suite = load_suite("axes_track")
    perts = suite.perturbations if axes is None else tuple(p for p in suite.perturbations if p.name in axes)
    return replace(suite, name="axes_track_ppo", env_kwargs={**suite.env_kwargs, "width": size[0], "height": size[1]},
                   frames=0, seed=seed, perturbations=perts).with_episodes(episodes)


def training_overlap(suite, pool: int = 64, pool_seed: int = 0) -> int:
    """How many of the suite's (prompt, scene seed) pairs are in the training pool (should be 0)."""
    from morphosim_gym.bench.perturb import sample_episode
    from morphosim_gym.envs.scenes import SceneChooser
    from morphosim_gym.tasks import make_task

    train = SceneChooser(make_task("track"), None, None, None, pool=pool, pool_seed=pool_seed)
    keys = {(r.prompt, s) for r, s in train.pool}
    return sum((ep.request.prompt, ep.scene_seed) in keys for ep in (sample_episode(suite, s) for s in suite.seeds))


def axis_groups(randomization: str) -> dict[str, str]:
    """Suite axis -> "trained" (drawn in training), "held_out" (declared held out) or "not_randomized"."""
    from morphosim_gym.tasks.axes import AXES
    from morphosim_gym.tasks.randomization import load_randomization

    spec = load_randomization(randomization)
    drawn = {a.name for a in spec.axes}
    held = set(spec.held_out)
    return {name: "trained" if name in drawn else "held_out" if name in held else "not_randomized" for name in AXES}


def run_policy(suite, label: str, model: Path, work: Path, workers: int) -> dict:
    """One policy's sweep (resumable); its records by (perturbation, seed)."""
    from morphosim_gym.bench import run_sweep

    os.environ["MORPHOSIM_SB3_POLICY"] = str(model)       # read by policy_from_env, here and in the workers
    start = time.perf_counter()
    result = run_sweep(suite, [POLICY_SPEC], work / label, workers=workers, cache_dir=str(work / "cache"),
                       progress=True, report=False)
    return {"wall_s": round(time.perf_counter() - start, 1), "ran": result.ran, "resumed": result.resumed,
            "failed": result.failed, "records": result.records}


def _ok(records: list[dict]) -> dict[tuple[str, int], dict]:
    return {(r["perturbation"], r["seed"]): r for r in records if r["status"] == "ok"}


def _iv(values) -> dict:
    from morphosim_gym.bench.stats import bootstrap_mean

    return bootstrap_mean(list(values)).as_dict()


def per_axis(runs: dict[str, dict], conditions: list[str], seeds: list[int], groups: dict[str, str]) -> list[dict]:
    """Rows per condition: each policy's success/return, and the paired randomised - baseline differences."""
    ok = {k: _ok(v["records"]) for k, v in runs.items()}
    b, r = ok["baseline"], ok["randomized"]
    rows = []
    for cond in conditions:
        both = [s for s in seeds if (cond, s) in b and (cond, s) in r]
        row: dict = {"axis": cond, "group": groups.get(cond, "base"), "pairs": len(both),
                     "failed": {k: sum((cond, s) not in ok[k] for s in seeds) for k in LABELS}}
        for label in LABELS:
            recs = [ok[label][(cond, s)] for s in both]
            row[label] = {m: _iv(float(x[m]) for x in recs) for m in ("success", "return")}
        row["diff"] = {m: _iv(float(r[(cond, s)][m]) - float(b[(cond, s)][m]) for s in both)
                       for m in ("success", "return")}
        if cond != "base":
            drop = [s for s in both if ("base", s) in b and ("base", s) in r]
            row["diff_of_drops"] = {m: _iv((float(r[(cond, s)][m]) - float(r[("base", s)][m]))
                                           - (float(b[(cond, s)][m]) - float(b[("base", s)][m])) for s in drop)
                                    for m in ("success", "return")}
        rows.append(row)
    return rows


def per_group(runs: dict[str, dict], groups: dict[str, str], seeds: list[int]) -> dict[str, dict]:
    """Per axis group: each seed's mean over the group's axes (pairs where both ran), bootstrapped over seeds."""
    b, r = _ok(runs["baseline"]["records"]), _ok(runs["randomized"]["records"])
    out = {}
    for group in GROUPS:
        axes = sorted(a for a, g in groups.items() if g == group)
        stats: dict = {"axes": axes}
        for m in ("success", "return"):
            per_seed = {"baseline": [], "randomized": [], "diff": [], "diff_of_drops": []}
            for s in seeds:
                pairs = [a for a in axes if (a, s) in b and (a, s) in r]
                if not pairs:
                    continue
                per_seed["baseline"].append(np.mean([float(b[(a, s)][m]) for a in pairs]))
                per_seed["randomized"].append(np.mean([float(r[(a, s)][m]) for a in pairs]))
                per_seed["diff"].append(np.mean([float(r[(a, s)][m]) - float(b[(a, s)][m]) for a in pairs]))
                if ("base", s) in b and ("base", s) in r:
                    per_seed["diff_of_drops"].append(np.mean(
                        [(float(r[(a, s)][m]) - float(r[("base", s)][m])) - (float(b[(a, s)][m])
                                                                             - float(b[("base", s)][m]))
                         for a in pairs]))
            stats[m] = {k: _iv(v) for k, v in per_seed.items()}
        out[group] = stats
    return out


def _f(i: dict | None, pct: bool) -> str:
    if not i or i["mean"] is None:
        return "n/a"
    if pct:
        return f"{100 * i['mean']:.0f}% [{100 * i['low']:.0f}, {100 * i['high']:.0f}]"
    return f"{i['mean']:.1f} [{i['low']:.1f}, {i['high']:.1f}]"


def tables(rows: list[dict], groups: dict[str, dict]) -> str:
    """Markdown: per group, then per axis."""
    out = ["| axes | n axes | success, baseline | success, randomised | randomised - baseline | "
           "difference of drops | return, baseline | return, randomised | randomised - baseline |",
           "|---|---|---|---|---|---|---|---|---|"]
    for g, st in groups.items():
        s, r = st["success"], st["return"]
        out.append(f"| {g} | {len(st['axes'])} | {_f(s['baseline'], True)} | {_f(s['randomized'], True)} | "
                   f"{_f(s['diff'], True)} | {_f(s['diff_of_drops'], True)} | {_f(r['baseline'], False)} | "
                   f"{_f(r['randomized'], False)} | {_f(r['diff'], False)} |")
    out += ["", "| axis | group | pairs | success, baseline | success, randomised | randomised - baseline | "
                "difference of drops | return, baseline | return, randomised | randomised - baseline | "
                "difference of drops |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        d = row.get("diff_of_drops") or {"success": None, "return": None}
        out.append(f"| {row['axis']} | {row['group']} | {row['pairs']} | {_f(row['baseline']['success'], True)} | "
                   f"{_f(row['randomized']['success'], True)} | {_f(row['diff']['success'], True)} | "
                   f"{_f(d['success'], True)} | {_f(row['baseline']['return'], False)} | "
                   f"{_f(row['randomized']['return'], False)} | {_f(row['diff']['return'], False)} | "
                   f"{_f(d['return'], False)} |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--baseline", type=Path, required=True, help="the model trained without randomisation (.zip)")
    ap.add_argument("--randomized", type=Path, required=True, help="the model trained with randomisation (.zip)")
    ap.add_argument("--randomization", default="track", help="the randomisation the second model was trained with")
    ap.add_argument("--episodes", type=int, default=32, help="episode seeds per axis")
    ap.add_argument("--seed", type=int, default=0, help="first episode seed")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--axes", nargs="*", default=None, help="only these axes (default: every axis of the suite)")
    ap.add_argument("--work", type=Path, default=ROOT / ".cache" / "ppo_axes", help="sweeps and scene cache (resumable)")
    ap.add_argument("--out", type=Path, default=RESULTS / "ppo_axes.json")
    args = ap.parse_args()
    from morphosim_gym.policies.sb3 import load_settings

    settings = {label: load_settings(path) for label, path in zip(LABELS, (args.baseline, args.randomized))}
    sizes = {(s.width, s.height) for s in settings.values()}
    if len(sizes) != 1:
        raise SystemExit(f"Expected both policies trained at one image size, found {sorted(sizes)}")
    start = time.perf_counter()
    suite = derived_suite(sizes.pop(), args.episodes, args.seed, args.axes)
    overlap = training_overlap(suite)
    groups = axis_groups(args.randomization)
    models = dict(zip(LABELS, (args.baseline, args.randomized)))
    runs = {label: run_policy(suite, label, models[label], args.work, args.workers) for label in LABELS}
    conditions = [c.name for c in suite.conditions]
    rows = per_axis(runs, conditions, suite.seeds, groups)
    pooled = per_group(runs, groups, suite.seeds)
    text = tables(rows, pooled)
    result = {"suite": {"source": suite.source, "name": suite.name, "digest": suite.digest(),
                        "env_kwargs": dict(suite.env_kwargs), "seeds": [suite.seeds[0], suite.seeds[-1]],
                        "episodes": suite.episodes, "scenes_in_training_pool": overlap},
              "models": {k: {"path": str(v), "settings": vars(settings[k])} for k, v in models.items()},
              "randomization": args.randomization, "groups": groups, "pooled": pooled, "axes": rows,
              "wall_s": {k: v["wall_s"] for k, v in runs.items()} | {"total": round(time.perf_counter() - start, 1)},
              "failed": {k: v["failed"] for k, v in runs.items()},
              "errors": sorted({f"{r['perturbation']}: {r['error']}" for v in runs.values() for r in v["records"]
                                if r["error"]})[:10],
              "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared with other jobs (loaded)",
              "loadavg_at_end": [round(x, 2) for x in os.getloadavg()]}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2, default=str) + "\n")
    args.out.with_suffix(".md").write_text(text + "\n")
    print(text)
    print(f"scenes in the training pool: {overlap}; wall {result['wall_s']}; failed {result['failed']}")
    print(f"-> {args.out} and {args.out.with_suffix('.md')}")


if __name__ == "__main__":
    main()
