"""Native vector env throughput on a CUDA GPU: env steps per second at 128 px for 64-1024 envs,
with the batched render on gsplat (`MorphoSimVectorEnv(backend="gsplat")`).

    python benchmarks/gpu_envs.py                          # 64 128 256 512 1024 envs, Track
    python benchmarks/gpu_envs.py --envs 64 256 --ids MorphoSim/Track-v0 MorphoSim/Find-v0

Needs gsplat and a CUDA GPU (exits with the backend's message otherwise); `--backend cpu`
runs the same sweep on the CPU kernels for a comparison. Every number is the median of
`--repeats` runs; it prints a table and writes benchmarks/results/gpu_envs.json, with the
split of a step between the batched render and the rest (skinning, kinematics, Python), which
stays on the CPU.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _envs_common import SCENES, CallTimer, machine, scene_kwargs, vector_rollout  # noqa: E402
from morphosim_gym.envs import make_vec  # noqa: E402
from morphosim_gym.errors import BackendUnavailableError  # noqa: E402
from morphosim_gym.render import backend_available  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"


def run(env_id: str, n: int, steps: int, backend: str, size: int, scenes: str = "procedural") -> dict:
    """Steps per second (all envs) and the batched render's share of one sweep of `steps` steps."""
    from morphosim_gym.envs import native_vector

    venv = make_vec(env_id, n, vectorization_mode="vector", backend=backend, width=size, height=size,
                    scene_pool=8, **scene_kwargs(scenes))
    timer = CallTimer({"render": [(native_vector, "render_batch")]})
    try:
        total = vector_rollout(venv, steps, warmup=3, on_start=timer.install)
    finally:
        timer.uninstall()
    venv.close()
    return {"steps_per_s": steps * n / total, "render_share": timer.seconds["render"] / total}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ids", nargs="*", default=["MorphoSim/Track-v0"])
    ap.add_argument("--envs", nargs="*", type=int, default=[64, 128, 256, 512, 1024])
    ap.add_argument("--steps", type=int, default=20, help="vector steps per run")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--size", type=int, default=128, help="image width and height")
    ap.add_argument("--backend", default="gsplat", choices=["gsplat", "cpu"])
    ap.add_argument("--scenes", default="real", choices=SCENES, help="real: the default assets=\"auto\"; procedural: assets=\"off\"")
    ap.add_argument("--json", type=Path, default=RESULTS / "gpu_envs.json")
    args = ap.parse_args()
    if args.backend == "gsplat" and not backend_available("gsplat"):
        try:
            from morphosim_gym.render.gsplat_backend import check_gsplat

            check_gsplat()
        except BackendUnavailableError as exc:
            sys.exit(f"benchmarks/gpu_envs.py: {exc} (or pass --backend cpu)")
    rows = []
    for env_id in args.ids:
        for n in args.envs:
            runs = [run(env_id, n, args.steps, args.backend, args.size, args.scenes) for _ in range(args.repeats)]
            rates = [r["steps_per_s"] for r in runs]
            row = {"id": env_id, "envs": n, "steps_per_s": round(statistics.median(rates), 1),
                   "runs": [round(x, 1) for x in rates],
                   "render_share": round(statistics.median(r["render_share"] for r in runs), 3)}
            rows.append(row)
            print(f"{env_id:22s} {n:5d} envs {row['steps_per_s']:10.1f} steps/s  render {row['render_share']:.0%}",
                  flush=True)
    print(f"\n| id | envs | steps/s ({args.size} px, {args.backend}) | render share |\n|---|---|---|---|")
    for r in rows:
        print(f"| {r['id']} | {r['envs']} | {r['steps_per_s']:.0f} | {r['render_share']:.0%} |")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"rows": rows, "settings": vars(args) | {"json": str(args.json)},
                                     "machine": machine()},
                                    indent=2, default=str) + "\n")
    print(f"\nwrote {args.json}")


if __name__ == "__main__":
    main()
