#!/usr/bin/env python
"""Realism and cost of real-asset scenes against procedural ones on the same prompts (issue #19).

    .venv/bin/python benchmarks/realism.py                    # table + benchmarks/results/realism.json
    .venv/bin/python benchmarks/realism.py --gallery examples/results/gallery_assets.png

Realism: `morphosim quality`'s scorer (`bench.quality.score_prompts`) with `assets="off"` and
`assets="auto"`: NIQE and BRISQUE (lower is better) of the generation view and of novel views
orbited about the scene centre, at a few instants of each clip. Both metrics were fitted to
natural photographs; they read large flat areas (a plain sky, a procedural ground) as unnatural.

Cost (machine load shown in the output): cached generation of a 49-frame clip at 128 px (the
conversion cache warmed by one run first, median of 3), `env.reset` of Track with a prompt it has
not seen, and Gaussians per scene.

Gallery: the generation view at mid-clip of every prompt, procedural above real assets.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

PROMPTS = (
    "a red chair moves to the right",
    "a dog runs to the left on the grass",
    "a car drives along the road",
    "a horse walks across the field",
    "a teapot on the table",
    "a bus moves to the left in the city",
    "a cat walks past a lamp in the room",
    "a bicycle moves to the right on the road",
    "a bowl and a bottle on the table",
    "a truck drives to the left on the road",
    "a fire hydrant and a bench",
    "a tree and a rock on the grass",
)
MODES = ("off", "auto")   # procedural, real assets
LABEL = {"off": "procedural", "auto": "real assets"}


def realism(prompts: tuple[str, ...], size: int, times: int, yaws: tuple[float, ...]) -> dict:
    """Per mode: every scored image, and means per view group."""
    from morphosim_gym.bench.quality import QualityConfig, score_prompts

    out = {}
    for mode in MODES:
        data = score_prompts(prompts, QualityConfig(size=size, times=times, yaws=yaws, assets=mode), progress=False)
        groups: dict[str, dict[str, list[float]]] = {}
        for row in data["images"]:
            g = groups.setdefault("novel views" if row["yaw"] else "generation view", {"niqe": [], "brisque": []})
            for k in ("niqe", "brisque"):
                if row[k] is not None and np.isfinite(row[k]):
                    g[k].append(float(row[k]))
        out[mode] = {"images": data["images"], "wall_s": data["wall_s"],
                     "means": {g: {k: round(statistics.mean(v), 3) for k, v in m.items() if v}
                               for g, m in groups.items()},
                     "per_prompt_niqe": {p: round(statistics.mean(r["niqe"] for r in data["images"] if r["prompt"] == p), 3)
                                         for p in prompts}}
    return out


def generation_cost(prompts: tuple[str, ...]) -> list[dict]:
    """Cached generation of a 49-frame clip at 128 px per prompt (median of 3) and its Gaussians."""
    from morphosim_gym.generate.compose import GenerationConfig
    from morphosim_gym.generate.procedural import ProceduralBackend
    from morphosim_gym.language import parse

    rows = []
    for mode in MODES:
        backend = ProceduralBackend(GenerationConfig(num_frames=49, width=128, height=128, assets=mode))
        for prompt in prompts:
            plan = parse(prompt)
            backend.generate(plan, 0, prompt)        # warms the conversion cache
            times = []
            for _ in range(3):
                t = time.perf_counter()
                clip = backend.generate(plan, 0, prompt)
                times.append(time.perf_counter() - t)
            scene = clip.ground_truth
            rows.append({"mode": mode, "prompt": prompt, "median_s": round(statistics.median(times), 3),
                         "gaussians": len(scene.gaussians),
                         "assets": {o.name: o.asset for o in scene.objects if o.role != "background"}})
    return rows


def reset_cost(prompts: tuple[str, ...]) -> list[dict]:
    """Track-v0 `reset` with a prompt the env has not seen (first and second time)."""
    import gymnasium as gym

    import morphosim_gym  # noqa: F401  (registers the envs)

    env = gym.make("MorphoSim/Track-v0")
    env.reset(seed=0)
    rows = []
    try:
        for prompt in prompts:
            t0 = time.perf_counter()
            env.reset(seed=1, options={"prompt": prompt})
            t1 = time.perf_counter()
            env.reset(seed=1, options={"prompt": prompt})
            t2 = time.perf_counter()
            rows.append({"prompt": prompt, "new_prompt_s": round(t1 - t0, 3), "same_prompt_s": round(t2 - t1, 3)})
    finally:
        env.close()
    return rows


def gallery(prompts: tuple[str, ...], path: Path, width: int = 192, height: int = 144, columns: int = 6) -> None:
    """Procedural (upper) and real-asset (lower) generation views at mid-clip, labelled, as a PNG."""
    import cv2

    from morphosim_gym.generate.compose import GenerationConfig
    from morphosim_gym.pipeline import MorphoSim
    from morphosim_gym.render import render

    tiles = {}
    for mode in MODES:
        sim = MorphoSim(reconstruction="oracle", generation=GenerationConfig(assets=mode))
        for prompt in prompts:
            scene = sim.generate(prompt, seed=0)
            t = scene.duration / 2
            cam = scene.camera_at(t).resized(width, height)
            img = np.ascontiguousarray(render(scene, cam, t).rgb_uint8())
            cv2.putText(img, LABEL[mode], (4, height - 6), cv2.FONT_HERSHEY_SIMPLEX, 0.38, (255, 255, 255), 1,
                        cv2.LINE_AA)
            tiles[mode, prompt] = img
    bands = []
    for start in range(0, len(prompts), columns):
        chunk = prompts[start:start + columns]
        caption = np.zeros((18, width * columns, 3), np.uint8)
        for k, prompt in enumerate(chunk):
            cv2.putText(caption, prompt[:34], (k * width + 3, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.33, (255, 255, 255),
                        1, cv2.LINE_AA)
        blank = np.zeros((height, width, 3), np.uint8)
        rows = [np.concatenate([tiles[mode, p] for p in chunk] + [blank] * (columns - len(chunk)), axis=1)
                for mode in MODES]
        bands += [caption, *rows]
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), np.concatenate(bands, axis=0)[..., ::-1], [cv2.IMWRITE_PNG_COMPRESSION, 9])


def _print(result: dict) -> None:
    print(f"machine load average at start: {result['loadavg']} (2 cores shared: timings are 'loaded')")
    print("\nNIQE / BRISQUE (lower is better), mean over images:")
    print(f"{'view':18s} " + " ".join(f"{LABEL[m] + ' NIQE':>18s} {LABEL[m] + ' BRISQUE':>21s}" for m in MODES))
    for group in ("generation view", "novel views"):
        cells = [f"{result['realism'][m]['means'][group]['niqe']:18.3f} {result['realism'][m]['means'][group]['brisque']:21.3f}"
                 for m in MODES]
        print(f"{group:18s} " + " ".join(cells))
    print("\nper prompt NIQE (all views): procedural -> real assets")
    for p in PROMPTS:
        print(f"  {result['realism']['off']['per_prompt_niqe'][p]:7.3f} -> "
              f"{result['realism']['auto']['per_prompt_niqe'][p]:7.3f}  {p}")
    print("\ncached generation, 49 frames at 128 px (median of 3) and Gaussians per scene:")
    for row in result["generation"]:
        print(f"  {LABEL[row['mode']]:12s} {row['median_s']:6.2f} s {row['gaussians']:7d}  {row['prompt']}  "
              f"{row['assets'] if row['mode'] == 'auto' else ''}")
    for m in MODES:
        rows = [r for r in result["generation"] if r["mode"] == m]
        print(f"  {LABEL[m]}: median {statistics.median(r['median_s'] for r in rows):.2f} s, max "
              f"{max(r['median_s'] for r in rows):.2f} s, Gaussians median "
              f"{statistics.median(r['gaussians'] for r in rows):.0f}")
    print("\nTrack-v0 reset with a new prompt (real assets, conversions cached):")
    for row in result["reset"]:
        print(f"  new {row['new_prompt_s']:6.2f} s  again {row['same_prompt_s']:6.2f} s  {row['prompt']}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=192)
    ap.add_argument("--times", type=int, default=2)
    ap.add_argument("--yaws", default="-30,30")
    ap.add_argument("--json", type=Path, default=Path("benchmarks/results/realism.json"))
    ap.add_argument("--gallery", type=Path, default=None)
    args = ap.parse_args()
    os.environ.pop("MORPHOSIM_ASSET_SOURCES", None)
    yaws = tuple(float(y) for y in args.yaws.split(","))
    result = {"loadavg": [round(x, 2) for x in os.getloadavg()], "prompts": list(PROMPTS),
              "config": {"size": args.size, "times": args.times, "yaws": yaws}}
    if args.gallery:
        gallery(PROMPTS, args.gallery)
        result["gallery"] = str(args.gallery)
    result["generation"] = generation_cost(PROMPTS)
    result["reset"] = reset_cost(tuple(PROMPTS[i] for i in (0, 1, 2, 3, 5, 7, 9)))
    result["realism"] = realism(PROMPTS, args.size, args.times, yaws)
    result["loadavg_end"] = [round(x, 2) for x in os.getloadavg()]
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=1) + "\n")
    _print(result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
