#!/usr/bin/env python
"""The sky composite of env views: the compiled kernel against the numpy definition, same run.

    python benchmarks/sky.py [--views 10] [--rounds 7] [--json benchmarks/results/sky.json]

Captures `--views` camera views of a Track env on the default scenes (real assets and an HDR
sky where the asset packages are installed; 84 px), one every 6 steps after 20 random steps,
renders each on black, then times `render.cpu.sky.composite_sky_compiled` (what every render
uses) and `scene.sky.composite_sky` (the numpy definition, the reference) on them, alternating,
`--rounds` rounds of 100 passes each; medians in microseconds a view, their ratio, and how many
uint8 observation values the two disagree on.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import morphosim_gym as ms  # noqa: F401  (registers the env ids)
from _bars import write_json
from morphosim_gym.render import render
from morphosim_gym.render.cpu.sky import composite_sky_compiled
from morphosim_gym.scene.sky import SKY_VISIBLE_BELOW, composite_sky

RESULTS = Path(__file__).resolve().parent / "results"


def capture(views: int, seed: int = 0) -> list[tuple]:
    """(rgb on black [1, H, W, 3], alpha [1, H, W], sky, [camera]) of `views` Track views with a sky."""
    env = gym.make("MorphoSim/Track-v0")
    env.reset(seed=seed)
    env.action_space.seed(seed)
    out: list[tuple] = []
    step = 0
    while len(out) < views and step < 20 + 60 * views:
        env.step(env.action_space.sample())
        step += 1
        if step < 20 or step % 6:
            continue
        sources, cams, _, sky = env.unwrapped._render_request(env.unwrapped.world.t)
        if sky is None:
            raise SystemExit("The env's scene has no sky here (no HDR sky installed): nothing to measure")
        o = render(sources, cams[0], background=(0.0, 0.0, 0.0))
        out.append((o.rgb[None], o.alpha[None], sky, [cams[0]]))
    env.close()
    return out


def per_view_us(fn, cases: list[tuple], passes: int) -> float:
    start = time.perf_counter()
    for _ in range(passes):
        for c in cases:
            fn(*c)
    return (time.perf_counter() - start) / (passes * len(cases)) * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--views", type=int, default=10)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--passes", type=int, default=100)
    ap.add_argument("--json", type=Path, default=RESULTS / "sky.json")
    args = ap.parse_args()
    cases = capture(args.views)
    for c in cases:                                   # compiled and warm
        composite_sky_compiled(*c)
    kernel, numpy_ref = [], []
    for _ in range(args.rounds):
        kernel.append(per_view_us(composite_sky_compiled, cases, args.passes))
        numpy_ref.append(per_view_us(composite_sky, cases, max(1, args.passes // 10)))
    differ = sum(int(np.sum(np.round(np.clip(composite_sky_compiled(*c), 0, 1) * 255)
                            != np.round(np.clip(composite_sky(*c), 0, 1) * 255))) for c in cases)
    values = sum(c[0].size for c in cases)
    uncovered = float(np.mean([(c[1] < SKY_VISIBLE_BELOW).sum() for c in cases]))
    k, n = float(np.median(kernel)), float(np.median(numpy_ref))
    print(f"{len(cases)} Track views, {cases[0][0].shape[2]}x{cases[0][0].shape[1]} px, "
          f"{uncovered:.0f} sky pixels a view on average")
    print(f"{'composite':28s} {'us / view (median)':>18s} {'rounds':>30s}")
    print(f"{'compiled (every render)':28s} {k:18.1f} {' '.join(f'{x:.0f}' for x in kernel):>30s}")
    print(f"{'numpy definition':28s} {n:18.1f} {' '.join(f'{x:.0f}' for x in numpy_ref):>30s}")
    print(f"ratio numpy / compiled {n / k:.2f}x; uint8 values that differ: {differ} of {values}")
    write_json(args.json, {"views": len(cases), "sky_pixels_per_view": uncovered, "compiled_us": k,
                           "numpy_us": n, "compiled_rounds": kernel, "numpy_rounds": numpy_ref,
                           "uint8_values_differing": differ, "uint8_values": values})


if __name__ == "__main__":
    main()
