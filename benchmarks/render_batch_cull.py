"""Object-level culling in `render_batch` on 200k-Gaussian scenes at 128 px: cull=True vs
cull=False vs the single-camera `render`, alternated per round (medians of 12 rounds).

    python benchmarks/render_batch_cull.py [--threads 1]

Scenes: the render benchmark's 200k surface scene (a ground object holding 87% of the
Gaussians, 8 objects) from its orbit camera and from a close-up, and a ring of 16 objects of
12.5k Gaussians seen from its centre (about a quarter in view). Checks that the images agree.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numba
import numpy as np

import morphosim_gym as ms
from morphosim_gym.render.api import render_batch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from render import orbit_camera, surface_scene  # noqa: E402


def ring_scene(k: int = 16, m: int = 12_500, seed: int = 0) -> ms.Gaussians:
    """k objects of m Gaussians on a ring of radius 3 m around the origin."""
    rng = np.random.default_rng(seed)
    ang = 2 * np.pi * np.arange(k) / k
    centres = np.stack([3 * np.cos(ang), 3 * np.sin(ang), np.full(k, 0.5)], 1)
    n = k * m
    return ms.Gaussians(means=(np.repeat(centres, m, 0) + rng.normal(size=(n, 3)) * 0.3).astype(np.float32),
                        quats=rng.normal(size=(n, 4)).astype(np.float32),
                        scales=np.exp(rng.uniform(-4.5, -3.0, (n, 3))).astype(np.float32),
                        opacities=rng.uniform(0.3, 1.0, n).astype(np.float32),
                        colors=rng.uniform(0, 1, (n, 3)).astype(np.float32),
                        object_ids=np.repeat(np.arange(k), m).astype(np.int32))


def compare(name: str, g: ms.Gaussians, cam: ms.Camera, rounds: int = 12) -> dict:
    a, b = render_batch([(g, cam)], cull=True)[0], render_batch([(g, cam)])[0]
    assert all(np.array_equal(getattr(a, f), getattr(b, f)) for f in ("rgb", "depth", "alpha", "instance"))
    times: dict[str, list[float]] = {"cull": [], "no cull": [], "render": []}
    calls = {"cull": lambda: render_batch([(g, cam)], cull=True), "no cull": lambda: render_batch([(g, cam)]),
             "render": lambda: ms.render(g, cam)}
    for _ in range(rounds):
        for mode, fn in calls.items():
            t0 = time.perf_counter()
            fn()
            times[mode].append(time.perf_counter() - t0)
    ratio = statistics.median(n / c for c, n in zip(times["cull"], times["no cull"]))
    row = {"scene": name, **{k: round(1e3 * statistics.median(v), 1) for k, v in times.items()},
           "no_cull_over_cull": round(ratio, 2)}
    print(f"{name:9s} 200k 128 px, {numba.get_num_threads()} thread(s): cull {row['cull']} ms, no cull "
          f"{row['no cull']} ms, render {row['render']} ms; no-cull / cull (per round, median) {ratio:.2f}", flush=True)
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    numba.set_num_threads(args.threads)
    s = surface_scene(200_000)
    surface = ms.Gaussians(**{k: s[k] for k in ("means", "quats", "scales", "opacities", "colors", "object_ids")})
    close = ms.Camera.look_at(eye=(0.3, -1.2, 1.0), target=(1.0, 0.3, 0.2), width=128, height=128, fov_y_deg=40)
    compare("orbit", surface, orbit_camera(0, 128))
    compare("close-up", surface, close)
    compare("ring-16", ring_scene(),
            ms.Camera.look_at(eye=(0, 0, 0.5), target=(3, 0.2, 0.5), width=128, height=128, fov_y_deg=60))


if __name__ == "__main__":
    main()
