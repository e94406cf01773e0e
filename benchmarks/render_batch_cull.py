"""Object-level culling in `render_batch` on 200k-Gaussian scenes at 128 px: cull=True vs
cull=False vs the single-camera `render`, alternated per round (medians of 12 rounds).

    python benchmarks/render_batch_cull.py [numba_threads]      # default 1

Scenes: the render benchmark's 200k surface scene (a ground object holding 87% of the
Gaussians, 8 objects) from its orbit camera and from a close-up, and a ring of 16 objects of
12.5k Gaussians seen from its centre (about a quarter in view). Also checks the images agree.
"""
import sys, time, statistics, numpy as np, numba
sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parent))
from render import surface_scene, orbit_camera  # noqa
import morphosim_gym as ms
from morphosim_gym.render.api import render_batch
s = surface_scene(200_000)
g = ms.Gaussians(means=s["means"], quats=s["quats"], scales=s["scales"], opacities=s["opacities"], colors=s["colors"],
                 object_ids=s["object_ids"])
print("objects", np.bincount(s["object_ids"]))
cams = {"orbit": orbit_camera(0, 128),
        "close-up": ms.Camera.look_at(eye=(0.3, -1.2, 1.0), target=(1.0, 0.3, 0.2), width=128, height=128, fov_y_deg=40)}
numba.set_num_threads(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
for name, cam in cams.items():
    a = render_batch([(g, cam)], cull=True)[0]; b = render_batch([(g, cam)], cull=False)[0]
    assert np.array_equal(a.rgb, b.rgb) and np.array_equal(a.instance, b.instance)
    t = {True: [], False: [], "single": []}
    for rep in range(12):
        for mode in (True, False, "single"):
            t0 = time.perf_counter()
            if mode == "single":
                ms.render(g, cam)
            else:
                render_batch([(g, cam)], cull=mode)
            t[mode].append(time.perf_counter() - t0)
    med = {k: 1e3 * statistics.median(v) for k, v in t.items()}
    ratios = [f / c for c, f in zip(t[True], t[False])]
    print(f"{name:9s} 128px 200k threads={numba.get_num_threads()}: cull {med[True]:.1f} ms, no cull {med[False]:.1f} ms, "
          f"single render {med['single']:.1f} ms; no-cull/cull per-round median {statistics.median(ratios):.2f}")
# 16 objects of 12.5k Gaussians on a ring of radius 3 m, camera at the centre looking outward
rng = np.random.default_rng(0)
k, m = 16, 12_500
ang = 2 * np.pi * np.arange(k) / k
centres = np.stack([3 * np.cos(ang), 3 * np.sin(ang), np.full(k, 0.5)], 1)
means = (np.repeat(centres, m, 0) + rng.normal(size=(k * m, 3)) * 0.3).astype(np.float32)
ring = ms.Gaussians(means=means, quats=rng.normal(size=(k * m, 4)).astype(np.float32),
                    scales=np.exp(rng.uniform(-4.5, -3.0, (k * m, 3))).astype(np.float32),
                    opacities=rng.uniform(0.3, 1.0, k * m).astype(np.float32),
                    colors=rng.uniform(0, 1, (k * m, 3)).astype(np.float32),
                    object_ids=np.repeat(np.arange(k), m).astype(np.int32))
cam = ms.Camera.look_at(eye=(0, 0, 0.5), target=(3, 0.2, 0.5), width=128, height=128, fov_y_deg=60)
a = render_batch([(ring, cam)], cull=True)[0]; b = render_batch([(ring, cam)], cull=False)[0]
assert np.array_equal(a.rgb, b.rgb) and np.array_equal(a.depth, b.depth) and np.array_equal(a.instance, b.instance)
t = {True: [], False: [], "single": []}
for rep in range(12):
    for mode in (True, False, "single"):
        t0 = time.perf_counter()
        ms.render(ring, cam) if mode == "single" else render_batch([(ring, cam)], cull=mode)
        t[mode].append(time.perf_counter() - t0)
med = {k_: 1e3 * statistics.median(v) for k_, v in t.items()}
ratios = [f / c for c, f in zip(t[True], t[False])]
print(f"ring-16   128px 200k threads={numba.get_num_threads()}: cull {med[True]:.1f} ms, no cull {med[False]:.1f} ms, "
      f"single render {med['single']:.1f} ms; no-cull/cull per-round median {statistics.median(ratios):.2f}")
