#!/usr/bin/env python
"""Benchmark of the compiled CPU splatting renderer (issue #2), with yardsticks from the same run.

Run from the repository root:

    python benchmarks/render.py                  # full run (~5 min on 2 cores)
    python benchmarks/render.py --quick          # short run (~1.5 min)
    python benchmarks/render.py --json out.json  # also write the results as JSON
    python benchmarks/render.py --lod-only       # only the level-of-detail rows (~2 min)
    python benchmarks/render.py --lod-envs       # real-asset Track/Reach/Find, render_lod off vs on

What is measured (single process, numba on all cores, camera orbiting 0.5 degrees per frame
around the scene so every frame re-projects and re-sorts):

* forward FPS of `rasterize_numpy` (rgb + depth + alpha + instance, end to end: argument
  conversion, projection, binning, per-tile depth sort, compositing, Python overhead) and
  forward + backward iterations/s of `rasterize_cpu` + `.backward()` (float32, L1 loss on
  rgb, depth and alpha), for 64, 128 and 256 px squares with 10k, 50k and 200k Gaussians on the
  surface scene, plus a random-cloud stress case; per-stage times (project / bin / raster,
  backward raster / backward projection);
* yardsticks at the same resolutions, same run: MuJoCo's own `mujoco.Renderer` (offscreen,
  `MUJOCO_GL=egl`) drawing the same ground and objects as geoms, and the torch reference
  renderer `rasterize_torch` (slow: a few frames at the same N, no gradient);
* peak memory: tracemalloc peak of one forward frame (numpy buffers) and the process's
  ru_maxrss;
* level of detail: `render_batch(..., lod=True)` against full detail on the 200k surface
  scene at 128 px, alternating rounds (same-run ratios), its PSNR and instance-label agreement
  over 12 orbit views, for lod_tol 1 and 2 px;
* first-call JIT cost: a subprocess with NUMBA_CACHE_DIR pointed at an empty temp dir (cold),
  then a second subprocess with that cache (warm first frame).

Timings are medians of per-frame times split in blocks (the median of the block medians is
reported); the machine is shared and noisy, so repeat a run before concluding.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from morphosim_gym.scene import Camera  # noqa: E402

# ----------------------------------------------------------------------------- scenes
GROUND_HALF = 6.0          # the ground patch is 12 m x 12 m
CAM_DISTANCE = 4.0         # camera distance to the target, metres
CAM_PITCH_DEG = 45.0       # looking down
CAM_TARGET = (0.0, 0.0, 0.3)
DEG_PER_FRAME = 0.5


def scene_layout(seed: int = 0, n_objects: int = 8) -> list[tuple[str, np.ndarray, float, np.ndarray]]:
    """The ~8 objects of the surface scene: (kind, base centre, half size, rgb) per object."""
    rng = np.random.default_rng(seed)
    objs = []
    for k in range(n_objects):
        kind = ("sphere", "box", "cylinder")[k % 3]
        size = rng.uniform(0.25, 0.5)
        ang = 2.0 * math.pi * k / n_objects + rng.uniform(-0.2, 0.2)
        rad = rng.uniform(0.6, 1.8)
        objs.append((kind, np.array([rad * math.cos(ang), rad * math.sin(ang), 0.0]), size,
                     rng.uniform(0.1, 0.9, 3)))
    return objs


def _quat_z_to(normals: np.ndarray) -> np.ndarray:
    """[M, 4] quaternions (w, x, y, z) rotating +z onto the unit normals [M, 3]."""
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(np.broadcast_to(z, normals.shape), normals)
    s = np.linalg.norm(axis, axis=1)
    ang = np.arctan2(s, normals[:, 2])
    axis = np.where(s[:, None] > 1e-9, axis / np.maximum(s, 1e-12)[:, None], np.array([1.0, 0.0, 0.0]))
    return np.concatenate([np.cos(ang / 2)[:, None], axis * np.sin(ang / 2)[:, None]], axis=1)


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b.T
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=1)


def surface_scene(n: int, seed: int = 0) -> dict:
    """n Gaussians on the surfaces of a 12 m ground patch (checkered) and ~8 objects (spheres,
    boxes, cylinders), spread uniformly by area; flat discs tangent to the surface with a
    spacing-sized footprint, opacities 0.6-1.0, object ids (0 = ground)."""
    rng = np.random.default_rng(seed + 1)
    objs = scene_layout(seed)
    areas = [(2 * GROUND_HALF) ** 2]
    for kind, _, r, _ in objs:
        areas.append({"sphere": 4 * math.pi * r * r, "box": 5 * (2 * r) ** 2,
                      "cylinder": 2 * math.pi * r * 2 * r + math.pi * r * r}[kind])
    areas = np.array(areas)
    counts = np.floor(n * areas / areas.sum()).astype(int)
    counts[0] += n - counts.sum()
    pts, nrm, col, ids = [], [], [], []
    m = counts[0]
    p = np.stack([rng.uniform(-GROUND_HALF, GROUND_HALF, m), rng.uniform(-GROUND_HALF, GROUND_HALF, m),
                  np.zeros(m)], 1)
    checker = ((np.floor(p[:, 0] * 2) + np.floor(p[:, 1] * 2)) % 2)[:, None]
    pts.append(p)
    nrm.append(np.tile([0.0, 0.0, 1.0], (m, 1)))
    col.append(0.35 + 0.3 * checker + rng.normal(0, 0.03, (m, 3)))
    ids.append(np.zeros(m, np.int32))
    for oi, ((kind, c, r, rgb), m) in enumerate(zip(objs, counts[1:])):
        if kind == "sphere":
            d = rng.normal(size=(m, 3))
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            p, nn = c + np.array([0, 0, r]) + r * d, d
        elif kind == "box":
            face = rng.integers(0, 5, m)              # no bottom face
            uv = rng.uniform(-r, r, (m, 2))
            p, nn = np.zeros((m, 3)), np.zeros((m, 3))
            for f, (ax, sgn) in enumerate([(0, 1), (0, -1), (1, 1), (1, -1), (2, 1)]):
                sel = face == f
                o0, o1 = [a for a in range(3) if a != ax]
                p[sel, ax], p[sel, o0], p[sel, o1] = sgn * r, uv[sel, 0], uv[sel, 1]
                nn[sel, ax] = sgn
            p = p + c + np.array([0, 0, r])
        else:
            side = rng.uniform(size=m) < 4.0 / 5.0
            th = rng.uniform(0, 2 * math.pi, m)
            h = rng.uniform(0, 2 * r, m)
            rr = np.sqrt(rng.uniform(0, 1, m)) * r
            p = np.where(side[:, None], np.stack([r * np.cos(th), r * np.sin(th), h], 1),
                         np.stack([rr * np.cos(th), rr * np.sin(th), np.full(m, 2 * r)], 1)) + c
            nn = np.where(side[:, None], np.stack([np.cos(th), np.sin(th), np.zeros(m)], 1), np.array([0, 0, 1.0]))
        pts.append(p)
        nrm.append(nn)
        col.append(rgb + rng.normal(0, 0.05, (m, 3)))
        ids.append(np.full(m, oi + 1, np.int32))
    spacing = math.sqrt(areas.sum() / n)
    tang = spacing * rng.uniform(0.5, 0.8, n)
    scales = np.stack([tang, tang * rng.uniform(0.7, 1.0, n), 0.1 * tang], 1)
    spin = rng.uniform(0, math.pi, n)
    spin_q = np.stack([np.cos(spin / 2), 0 * spin, 0 * spin, np.sin(spin / 2)], 1)
    quats = _quat_mul(_quat_z_to(np.concatenate(nrm)), spin_q)
    return {"means": np.concatenate(pts).astype(np.float32), "quats": quats.astype(np.float32),
            "scales": scales.astype(np.float32), "opacities": rng.uniform(0.6, 1.0, n).astype(np.float32),
            "colors": np.clip(np.concatenate(col), 0, 1).astype(np.float32),
            "object_ids": np.concatenate(ids)}


def random_cloud(n: int, seed: int = 0) -> dict:
    """Stress case: n Gaussians uniform in a 3 m cube around the target, random orientation,
    log-uniform scales 1-10 cm, opacities 0.05-1 (little early termination, deep lists)."""
    rng = np.random.default_rng(seed)
    return {"means": (rng.uniform(-1.5, 1.5, (n, 3)) + np.array(CAM_TARGET)).astype(np.float32),
            "quats": rng.normal(size=(n, 4)).astype(np.float32),
            "scales": np.exp(rng.uniform(math.log(0.01), math.log(0.1), (n, 3))).astype(np.float32),
            "opacities": rng.uniform(0.05, 1.0, n).astype(np.float32),
            "colors": rng.uniform(0, 1, (n, 3)).astype(np.float32),
            "object_ids": rng.integers(0, 8, n).astype(np.int32)}


def orbit_camera(frame: int, res: int) -> Camera:
    """Camera ~4 m from the target, pitched down 45 deg, orbiting 0.5 deg per frame."""
    az = math.radians(-90.0 + frame * DEG_PER_FRAME)
    pitch = math.radians(CAM_PITCH_DEG)
    r = CAM_DISTANCE * math.cos(pitch)
    eye = (CAM_TARGET[0] + r * math.cos(az), CAM_TARGET[1] + r * math.sin(az),
           CAM_TARGET[2] + CAM_DISTANCE * math.sin(pitch))
    return Camera.look_at(eye=eye, target=CAM_TARGET, width=res, height=res, fov_y_deg=60.0)


def mujoco_xml(seed: int = 0) -> str:
    """The surface scene's ground and objects as MuJoCo geoms (for the MuJoCo yardstick)."""
    geoms = []
    for kind, c, r, rgb in scene_layout(seed):
        rgba = f"{rgb[0]:.3f} {rgb[1]:.3f} {rgb[2]:.3f} 1"
        if kind == "sphere":
            geoms.append(f'<geom type="sphere" size="{r}" pos="{c[0]} {c[1]} {r}" rgba="{rgba}"/>')
        elif kind == "box":
            geoms.append(f'<geom type="box" size="{r} {r} {r}" pos="{c[0]} {c[1]} {r}" rgba="{rgba}"/>')
        else:
            geoms.append(f'<geom type="cylinder" size="{r} {r}" pos="{c[0]} {c[1]} {r}" rgba="{rgba}"/>')
    return f"""<mujoco>
  <visual><global fovy="60" offwidth="512" offheight="512"/></visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1=".35 .35 .35" rgb2=".65 .65 .65" width="64" height="64"/>
    <material name="grid" texture="grid" texrepeat="12 12"/>
  </asset>
  <worldbody>
    <light pos="0 0 6" dir="0 0 -1"/>
    <geom type="plane" size="{GROUND_HALF} {GROUND_HALF} 0.1" material="grid"/>
    {chr(10).join(geoms)}
  </worldbody>
</mujoco>"""


# ----------------------------------------------------------------------------- machine load
def _cpu_ticks() -> tuple[int, int, float] | None:
    """(total, idle, own) CPU ticks from /proc/stat and os.times (Linux), or None."""
    try:
        with open("/proc/stat") as f:
            vals = [int(v) for v in f.readline().split()[1:9]]
        t = os.times()
        return sum(vals), vals[3] + vals[4], (t.user + t.system + t.children_user + t.children_system) \
            * os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError):
        return None


def _other_load(a, b) -> float | None:
    """Share of all cores used by other processes between two `_cpu_ticks` snapshots."""
    if a is None or b is None or b[0] <= a[0]:
        return None
    busy = (b[0] - a[0]) - (b[1] - a[1])
    return max(0.0, (busy - (b[2] - a[2])) / (b[0] - a[0]))


def wait_quiet(max_wait_s: float, need_s: float = 2.0, threshold: float = 0.08) -> float:
    """Wait (at most max_wait_s) until other processes used < threshold of the CPUs for need_s
    seconds in a row; returns the seconds waited. The machine is shared: a parallel frame waits
    for its slowest thread, so one busy core from another process can halve a measurement."""
    t0 = time.perf_counter()
    quiet_since = None
    while time.perf_counter() - t0 < max_wait_s:
        a = _cpu_ticks()
        time.sleep(0.5)
        load = _other_load(a, _cpu_ticks())
        if load is None:
            return 0.0
        if load < threshold:
            quiet_since = quiet_since or time.perf_counter()
            if time.perf_counter() - quiet_since >= need_s:
                break
        else:
            quiet_since = None
    return time.perf_counter() - t0


# ----------------------------------------------------------------------------- timing helpers
def _block_median(times: list[float], blocks: int = 3) -> tuple[float, float, float]:
    """(median of block medians, min, max of block medians) in seconds."""
    t = np.asarray(times)
    parts = [p for p in np.array_split(t, min(blocks, len(t))) if len(p)]
    meds = np.array([np.median(p) for p in parts])
    return float(np.median(meds)), float(meds.min()), float(meds.max())


def _cam_arrays(frame: int, res: int):
    cam = orbit_camera(frame, res)
    return cam.world_to_camera[None], cam.K[None]


def bench_forward(scene: dict, res: int, frames: int, warmup: int = 5) -> dict:
    from morphosim_gym.render.cpu import rasterize_numpy
    from morphosim_gym.render.cpu.pipeline import StageTimer

    args = [scene[k] for k in ("means", "quats", "scales", "opacities", "colors")]
    ids = scene["object_ids"]
    for k in range(warmup):
        vm, K = _cam_arrays(k, res)
        rasterize_numpy(*args, vm, K, res, res, object_ids=ids)
    times = []
    a = _cpu_ticks()
    for k in range(frames):
        vm, K = _cam_arrays(warmup + k, res)
        t = time.perf_counter()
        rasterize_numpy(*args, vm, K, res, res, object_ids=ids)
        times.append(time.perf_counter() - t)
    load = _other_load(a, _cpu_ticks())
    med, lo, hi = _block_median(times)
    timer = StageTimer()                                   # stage split, on separate frames
    nstage = max(3, frames // 4)
    for k in range(nstage):
        vm, K = _cam_arrays(k, res)
        rasterize_numpy(*args, vm, K, res, res, object_ids=ids, timer=timer)
    vm, K = _cam_arrays(0, res)
    tracemalloc.start()
    out = rasterize_numpy(*args, vm, K, res, res, object_ids=ids)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    from morphosim_gym.render.cpu.pipeline import thread_workspace

    ws_mb = sum(b.nbytes for b in thread_workspace()._bufs.values()) / 2 ** 20
    return {"ms": med * 1e3, "fps": 1.0 / med, "fps_block_range": [1.0 / hi, 1.0 / lo], "frames": frames,
            "stages_ms": {k: v / nstage * 1e3 for k, v in timer.totals.items()},
            "alloc_peak_mb": peak / 2 ** 20, "workspace_mb": ws_mb, "other_load": load,
            "alpha_mean": float(out["alpha"].mean())}


def bench_forward_backward(scene: dict, res: int, iters: int, warmup: int = 3) -> dict:
    import torch

    from morphosim_gym.render.cpu import autograd as cpu_autograd
    from morphosim_gym.render.cpu import rasterize_cpu
    from morphosim_gym.render.cpu.pipeline import StageTimer

    params = {k: torch.from_numpy(scene[k].copy()).requires_grad_(True)
              for k in ("means", "quats", "scales", "opacities", "colors")}
    ids = torch.from_numpy(scene["object_ids"])
    vm0, K0 = _cam_arrays(0, res)
    with torch.no_grad():
        target = rasterize_cpu(*params.values(), torch.tensor(vm0), torch.tensor(K0), res, res)
    t_rgb, t_depth, t_alpha = target["rgb"], target["depth"], target["alpha"]

    def step(k):
        vm, K = _cam_arrays(k, res)
        out = rasterize_cpu(*params.values(), torch.tensor(vm), torch.tensor(K), res, res, object_ids=ids)
        loss = ((out["rgb"] - t_rgb).abs().mean() + 0.1 * (out["depth"] - t_depth).abs().mean()
                + (out["alpha"] - t_alpha).abs().mean())
        loss.backward()
        for p in params.values():
            p.grad = None

    for k in range(warmup):
        step(k)
    times = []
    tracemalloc.start()
    a = _cpu_ticks()
    for k in range(iters):
        t = time.perf_counter()
        step(warmup + k)
        times.append(time.perf_counter() - t)
    load = _other_load(a, _cpu_ticks())
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    med, lo, hi = _block_median(times)
    timer = StageTimer()
    cpu_autograd._STAGE_TIMER = timer
    nstage = max(3, iters // 4)
    try:
        for k in range(nstage):
            step(k)
    finally:
        cpu_autograd._STAGE_TIMER = None
    return {"ms": med * 1e3, "its": 1.0 / med, "its_block_range": [1.0 / hi, 1.0 / lo], "iters": iters,
            "stages_ms": {k: v / nstage * 1e3 for k, v in timer.totals.items()}, "other_load": load,
            "alloc_peak_mb": peak / 2 ** 20}


def bench_torch_reference(scene: dict, res: int, frames: int) -> dict:
    import torch

    from morphosim_gym.render.reference import rasterize_torch

    t = {k: torch.from_numpy(scene[k]) for k in scene}
    times = []
    a = _cpu_ticks()
    with torch.no_grad():
        for k in range(frames):
            vm, K = _cam_arrays(k, res)
            s = time.perf_counter()
            rasterize_torch(t["means"], t["quats"], t["scales"], t["opacities"], t["colors"],
                            torch.tensor(vm, dtype=torch.float32), torch.tensor(K, dtype=torch.float32), res, res,
                            object_ids=t["object_ids"])
            times.append(time.perf_counter() - s)
    med = float(np.median(times))
    return {"ms": med * 1e3, "fps": 1.0 / med, "frames": frames, "other_load": _other_load(a, _cpu_ticks())}


def bench_mujoco(res: int, frames: int, warmup: int = 3) -> dict:
    import mujoco

    model = mujoco.MjModel.from_xml_string(mujoco_xml())
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    renderer = mujoco.Renderer(model, height=res, width=res)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = CAM_TARGET
    cam.distance = CAM_DISTANCE
    cam.elevation = -CAM_PITCH_DEG
    a = _cpu_ticks()
    try:
        times = []
        for k in range(warmup + frames):
            cam.azimuth = -90.0 + k * DEG_PER_FRAME + 180.0
            s = time.perf_counter()
            renderer.update_scene(data, camera=cam)
            renderer.render()
            if k >= warmup:
                times.append(time.perf_counter() - s)
    finally:
        renderer.close()
    med, lo, hi = _block_median(times)
    return {"ms": med * 1e3, "fps": 1.0 / med, "frames": frames, "other_load": _other_load(a, _cpu_ticks())}


_JIT_PROBE = r"""
import json, sys, time
t0 = time.perf_counter()
sys.path.insert(0, {root!r})
sys.path.insert(0, {bench_dir!r})
import numpy as np
from render import surface_scene, orbit_camera
from morphosim_gym.render.cpu import rasterize_numpy
t_import = time.perf_counter() - t0
s = surface_scene(10000)
cam = orbit_camera(0, 128)
args = [s[k] for k in ("means", "quats", "scales", "opacities", "colors")]
t = time.perf_counter()
rasterize_numpy(*args, cam.world_to_camera[None], cam.K[None], 128, 128, object_ids=s["object_ids"])
t_first = time.perf_counter() - t
t = time.perf_counter()
rasterize_numpy(*args, cam.world_to_camera[None], cam.K[None], 128, 128, object_ids=s["object_ids"])
t_second = time.perf_counter() - t
res = {{"import_s": t_import, "first_frame_s": t_first, "second_frame_s": t_second}}
if {with_grad}:
    import torch
    from morphosim_gym.render.cpu import rasterize_cpu
    p = [torch.from_numpy(a).requires_grad_(True) for a in args]
    t = time.perf_counter()
    out = rasterize_cpu(*p, torch.tensor(cam.world_to_camera[None]), torch.tensor(cam.K[None]), 128, 128)
    (out["rgb"].mean() + out["depth"].mean() + out["alpha"].mean()).backward()
    res["first_fwd_bwd_s"] = time.perf_counter() - t
print("JSON" + json.dumps(res))
"""


def bench_lod(scene: dict, res: int, frames: int, rounds: int = 5, tols=(1.0, 2.0)) -> dict:
    """Level of detail (`render_batch(..., lod=True)`) against full detail on one scene: FPS of
    both measured alternately in `rounds` rounds of `frames` orbiting frames each (per-round
    ratio, median), the one-off ladder build time, and the error (PSNR of rgb, share of equal
    instance labels) over 12 orbit views, per tolerance in `tols` (pixels)."""
    from morphosim_gym.render.api import render_batch
    from morphosim_gym.render.lod import clear_lod_cache
    from morphosim_gym.scene.gaussians import Gaussians

    arrays = {k: np.array(v) for k, v in scene.items()}
    for a in arrays.values():
        a.setflags(write=False)                  # LOD caches ladders only for read-only arrays
    g = Gaussians._trusted(**arrays)
    render_batch([(g, orbit_camera(0, res))])     # compile
    clear_lod_cache()
    t0 = time.perf_counter()
    render_batch([(g, orbit_camera(0, res))], lod=True)
    build_s = time.perf_counter() - t0
    out = {"res": res, "n": len(arrays["means"]), "build_s": build_s, "tols": []}
    for tol in tols:
        psnr, agree = [], []
        for f in range(0, 720, 60):
            cam = orbit_camera(f, res)
            a = render_batch([(g, cam)])[0]
            b = render_batch([(g, cam)], lod=True, lod_tol=tol)[0]
            psnr.append(10 * math.log10(1.0 / max(float(np.mean((a.rgb - b.rgb) ** 2)), 1e-12)))
            agree.append(float((a.instance == b.instance).mean()))
        fps = {False: [], True: []}
        for _ in range(rounds):
            for lod in (False, True):
                t0 = time.perf_counter()
                for f in range(frames):
                    render_batch([(g, orbit_camera(f, res))], lod=lod, lod_tol=tol)
                fps[lod].append(frames / (time.perf_counter() - t0))
        ratios = [b / a for a, b in zip(fps[False], fps[True])]
        out["tols"].append({"tol_px": tol, "fps_full": float(np.median(fps[False])),
                            "fps_lod": float(np.median(fps[True])), "ratio_median": float(np.median(ratios)),
                            "ratios": ratios, "psnr_min_db": min(psnr), "psnr_median_db": float(np.median(psnr)),
                            "instance_agree_min": min(agree)})
    return out


def bench_lod_envs(env_ids=("MorphoSim/Track-v0", "MorphoSim/Reach-v0", "MorphoSim/Find-v0"),
                   modes=("single", "vector-8"), steps: int = 300, rounds: int = 3) -> list[dict]:
    """Env steps/s with `render_lod` off and on, on the real-asset scenes (default env arguments,
    84 px, scene_pool=8, random actions): both envs built once, rollouts alternated in `rounds`
    rounds; per-round ratios (lod / full), median."""
    import gymnasium as gym

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _envs_common import scene_kwargs, single_rollout, vector_rollout

    from morphosim_gym.envs import make_vec

    rows = []
    for env_id in env_ids:
        for mode in modes:
            envs = {}
            for lod in (False, True):
                kw = dict(scene_pool=8, render_lod=lod, **scene_kwargs("real"))
                envs[lod] = gym.make(env_id, **kw) if mode == "single" else make_vec(env_id, 8, "vector", **kw)
            rates = {False: [], True: []}
            for _ in range(rounds):
                for lod, env in envs.items():
                    if mode == "single":
                        rates[lod].append(steps / single_rollout(env, steps))
                    else:
                        rates[lod].append(8 * (steps // 8) / vector_rollout(env, steps // 8))
            for env in envs.values():
                env.close()
            ratios = [b / a for a, b in zip(rates[False], rates[True])]
            rows.append({"id": env_id, "mode": mode, "full_steps_s": float(np.median(rates[False])),
                         "lod_steps_s": float(np.median(rates[True])), "ratio_median": float(np.median(ratios)),
                         "ratios": ratios})
            r = rows[-1]
            print(f"{env_id:22s} {mode:9s} full {r['full_steps_s']:7.1f} steps/s, lod {r['lod_steps_s']:7.1f}, "
                  f"ratio {r['ratio_median']:.2f}x (rounds {', '.join(f'{x:.2f}' for x in ratios)})", flush=True)
    return rows


def jit_times(with_grad: bool) -> dict:
    """Cold (empty NUMBA_CACHE_DIR) and warm (same cache, new process) first-frame times."""
    code = _JIT_PROBE.format(root=str(ROOT), bench_dir=str(Path(__file__).resolve().parent), with_grad=with_grad)
    out = {}
    with tempfile.TemporaryDirectory(prefix="numba-cold-") as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for label in ("cold", "warm"):
            t = time.perf_counter()
            r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            wall = time.perf_counter() - t
            line = next(ln for ln in r.stdout.splitlines() if ln.startswith("JSON"))
            out[label] = dict(json.loads(line[4:]), process_wall_s=wall)
    return out


# ----------------------------------------------------------------------------- main
BARS = {  # (N, res): forward FPS bar
    (50_000, 128): 150, (50_000, 64): 170, (50_000, 256): 100, (10_000, 64): 600,
}
FWD_BWD_BAR = {(50_000, 128): 40}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer frames; no 200k forward+backward; JIT probe forward only")
    ap.add_argument("--json", type=Path, default=None, help="write results to this JSON file")
    ap.add_argument("--no-jit", action="store_true", help="skip the cold/warm JIT subprocess probes")
    ap.add_argument("--no-yardsticks", action="store_true", help="skip MuJoCo and the torch reference")
    ap.add_argument("--lod-only", action="store_true",
                    help="only the level-of-detail rows (200k surface scene, 128 px, alternating rounds)")
    ap.add_argument("--lod-envs", action="store_true",
                    help="only (or with --lod-only: also) Track/Reach/Find on real-asset scenes, single and "
                         "vector-8, render_lod off vs on")
    ap.add_argument("--max-wait", type=float, default=60.0,
                    help="before each case wait up to this many seconds for other processes to go idle "
                         "(0: never wait); the load seen during each case is reported either way")
    args = ap.parse_args(argv)
    waited = []

    def settle():
        if args.max_wait > 0:
            waited.append(wait_quiet(args.max_wait))

    import numba

    quick = args.quick
    resolutions = (64, 128, 256)
    sizes = (10_000, 50_000, 200_000)
    fwd_frames = 40 if quick else 150
    fb_iters = 8 if quick else 30
    results: dict = {
        "machine": {"cpu_count": os.cpu_count(), "numba_threads": numba.get_num_threads(),
                    "threading_layer": None, "platform": platform.platform(), "python": platform.python_version(),
                    "numba": numba.__version__},
        "settings": {"quick": quick, "deg_per_frame": DEG_PER_FRAME, "camera_distance_m": CAM_DISTANCE,
                     "fwd_frames": fwd_frames, "fwd_bwd_iters": fb_iters},
        "forward": [], "forward_backward": [], "torch_reference": [], "mujoco": [], "speedups": [],
    }
    if not args.no_jit and not args.lod_only:
        print("JIT probe (subprocesses, cold then warm numba cache) ...", flush=True)
        results["jit"] = jit_times(with_grad=not quick)

    if args.lod_only or args.lod_envs:
        if args.lod_only:
            settle()
            results["lod"] = [bench_lod(surface_scene(200_000), 128, 20 if quick else 40)]
            _print_lod(results["lod"])
        if args.lod_envs:
            results["lod_envs"] = bench_lod_envs(steps=150 if quick else 300)
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(results, indent=2, default=float))
        return results

    scenes = {}
    for n in sizes:
        scenes[("surface", n)] = surface_scene(n)
    scenes[("random_cloud", 50_000)] = random_cloud(50_000)

    for (kind, n), scene in scenes.items():
        for res in resolutions:
            settle()
            r = bench_forward(scene, res, fwd_frames)
            results["forward"].append(dict(scene=kind, n=n, res=res, **r))
            print(f"forward  {kind:12s} N={n:>7,d} {res:>3d}px  {r['fps']:7.1f} FPS  ({r['ms']:.2f} ms; "
                  + ", ".join(f"{k} {v:.2f}" for k, v in r["stages_ms"].items()) + ")", flush=True)
            if results["machine"]["threading_layer"] is None:
                results["machine"]["threading_layer"] = numba.threading_layer()
            if quick and n == 200_000:
                continue
            settle()
            r = bench_forward_backward(scene, res, fb_iters if n < 200_000 else max(fb_iters // 2, 5))
            results["forward_backward"].append(dict(scene=kind, n=n, res=res, **r))
            print(f"fwd+bwd  {kind:12s} N={n:>7,d} {res:>3d}px  {r['its']:7.1f} it/s ({r['ms']:.2f} ms; "
                  + ", ".join(f"{k} {v:.2f}" for k, v in r["stages_ms"].items()) + ")", flush=True)

    settle()
    results["lod"] = [bench_lod(scenes[("surface", 200_000)], 128, 20 if quick else 40)]

    if not args.no_yardsticks:
        for res in resolutions:
            try:
                settle()
                r = bench_mujoco(res, 20 if quick else 60)
                results["mujoco"].append(dict(res=res, **r))
                print(f"mujoco.Renderer        {res:>3d}px  {r['fps']:7.1f} FPS", flush=True)
            except Exception as e:  # no EGL here: report it, keep the rest
                results["mujoco"].append(dict(res=res, error=f"{type(e).__name__}: {e}"))
                print(f"mujoco.Renderer        {res:>3d}px  unavailable: {type(e).__name__}: {e}", flush=True)
        for n in (10_000, 50_000):
            for res in resolutions:
                settle()
                r = bench_torch_reference(scenes[("surface", n)], res, 2 if quick else 3)
                results["torch_reference"].append(dict(scene="surface", n=n, res=res, **r))
                print(f"torch reference surface N={n:>7,d} {res:>3d}px  {r['fps']:7.3f} FPS ({r['frames']} frames)",
                      flush=True)

    fwd = {(r["scene"], r["n"], r["res"]): r for r in results["forward"]}
    fb = {(r["scene"], r["n"], r["res"]): r for r in results["forward_backward"]}
    muj = {r["res"]: r for r in results["mujoco"] if "fps" in r}
    ref = {(r["n"], r["res"]): r for r in results["torch_reference"]}
    for res in resolutions:
        for n in (10_000, 50_000):
            row = {"n": n, "res": res, "cpu_fps": fwd[("surface", n, res)]["fps"]}
            if res in muj:
                row["vs_mujoco"] = row["cpu_fps"] / muj[res]["fps"]
            if (n, res) in ref:
                row["vs_torch_reference"] = row["cpu_fps"] / ref[(n, res)]["fps"]
            results["speedups"].append(row)
    bars = []
    for (n, res), bar in BARS.items():
        got = fwd[("surface", n, res)]["fps"]
        bars.append({"what": f"forward surface {n // 1000}k {res}px", "bar": bar, "got": got, "met": got >= bar})
    for (n, res), bar in FWD_BWD_BAR.items():
        if ("surface", n, res) in fb:
            got = fb[("surface", n, res)]["its"]
            bars.append({"what": f"fwd+bwd surface {n // 1000}k {res}px (it/s)", "bar": bar, "got": got,
                         "met": got >= bar})
    for row in results["speedups"]:
        if row["n"] == 50_000 and "vs_mujoco" in row:
            bars.append({"what": f"vs mujoco.Renderer {row['res']}px (x)", "bar": 8, "got": row["vs_mujoco"],
                         "met": row["vs_mujoco"] >= 8})
        if "vs_torch_reference" in row:
            bars.append({"what": f"vs torch reference {row['n'] // 1000}k {row['res']}px (x)", "bar": 30,
                         "got": row["vs_torch_reference"], "met": row["vs_torch_reference"] >= 30})
    results["bars"] = bars
    results["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    results["settings"]["waited_for_quiet_s"] = float(sum(waited))

    _print_tables(results)
    _print_lod(results["lod"])
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=2, default=float))
        print(f"\nwrote {args.json}")
    return results


def _print_lod(rows: list) -> None:
    print("\n== level of detail (render_batch lod=True vs full detail, same run, alternating rounds) ==")
    for r in rows:
        print(f"surface N={r['n']:,d} {r['res']}px  ladder build {r['build_s']:.1f} s (once per scene)")
        for t in r["tols"]:
            print(f"  lod_tol {t['tol_px']:.1f} px: full {t['fps_full']:6.1f} FPS, lod {t['fps_lod']:6.1f} FPS, "
                  f"ratio {t['ratio_median']:.2f}x (rounds {', '.join(f'{x:.2f}' for x in t['ratios'])}); "
                  f"PSNR min {t['psnr_min_db']:.1f} dB (median {t['psnr_median_db']:.1f}), "
                  f"instance labels equal >= {100 * t['instance_agree_min']:.2f}%")


def _busy(r: dict) -> str:
    load = r.get("other_load")
    return "*" if load is not None and load > 0.1 else " "


def _print_tables(results: dict) -> None:
    print("\n(* = other processes used > 10% of the CPUs during that measurement: treat as a lower bound)")
    print("\n== forward (rasterize_numpy: rgb + depth + alpha + instance), FPS  [block range] ==")
    print(f"{'scene':14s} {'N':>8s} " + " ".join(f"{r:>22d}px" for r in (64, 128, 256)))
    rows: dict = {}
    for r in results["forward"]:
        rows.setdefault((r["scene"], r["n"]), {})[r["res"]] = r
    for (scene, n), by in rows.items():
        cells = [f"{by[res]['fps']:7.1f} [{by[res]['fps_block_range'][0]:6.1f},{by[res]['fps_block_range'][1]:6.1f}]"
                 + _busy(by[res]) if res in by else "-" for res in (64, 128, 256)]
        print(f"{scene:14s} {n:>8,d} " + " ".join(f"{c:>25s}" for c in cells))
    print("\n== per-stage forward ms (project / bin / raster incl. sort) ==")
    for (scene, n), by in rows.items():
        print(f"{scene:14s} {n:>8,d} " + "  ".join(
            f"{res}px: " + "/".join(f"{v:.2f}" for v in by[res]["stages_ms"].values()) for res in sorted(by)))
    if results["forward_backward"]:
        print("\n== forward + backward (rasterize_cpu + .backward(), float32), it/s ==")
        rows = {}
        for r in results["forward_backward"]:
            rows.setdefault((r["scene"], r["n"]), {})[r["res"]] = r
        for (scene, n), by in rows.items():
            cells = [f"{by[res]['its']:7.1f}" + _busy(by[res]) if res in by else "-" for res in (64, 128, 256)]
            stages = "  ".join(f"{res}px: " + ", ".join(f"{k} {v:.2f}" for k, v in by[res]["stages_ms"].items())
                               for res in sorted(by))
            print(f"{scene:14s} {n:>8,d} " + " ".join(f"{c:>10s}" for c in cells) + f"   [{stages}]")
    if results["mujoco"] or results["torch_reference"]:
        print("\n== yardsticks (same run) ==")
        for r in results["mujoco"]:
            print(f"mujoco.Renderer (EGL)  {r['res']:>3d}px  "
                  + (f"{r['fps']:7.1f} FPS" + _busy(r) if "fps" in r else r.get("error", "")))
        for r in results["torch_reference"]:
            print(f"torch reference        {r['res']:>3d}px N={r['n']:>7,d}  {r['fps']:7.3f} FPS{_busy(r)}"
                  f"(median of {r['frames']} frames)")
        print("\n== speedups of the CPU kernels (forward, surface scene) ==")
        for r in results["speedups"]:
            print(f"N={r['n']:>7,d} {r['res']:>3d}px  cpu {r['cpu_fps']:7.1f} FPS"
                  + (f"   x{r['vs_mujoco']:.1f} mujoco" if "vs_mujoco" in r else "")
                  + (f"   x{r['vs_torch_reference']:.0f} torch reference" if "vs_torch_reference" in r else ""))
    if "jit" in results:
        j = results["jit"]
        print("\n== first call (subprocess, 10k surface, 128 px) ==")
        for label in ("cold", "warm"):
            r = j[label]
            print(f"{label:4s} cache: import {r['import_s']:.2f} s, first frame {r['first_frame_s']:.2f} s, "
                  f"second frame {r['second_frame_s'] * 1e3:.1f} ms"
                  + (f", first fwd+bwd {r['first_fwd_bwd_s']:.2f} s" if "first_fwd_bwd_s" in r else ""))
    print("\n== memory ==")
    for r in results["forward"]:
        if r["res"] == 128:
            print(f"forward {r['scene']:12s} N={r['n']:>7,d} 128px: scratch workspace {r['workspace_mb']:.1f} MB "
                  f"(reused across frames), per-frame numpy allocation peak {r['alloc_peak_mb']:.1f} MB")
    for r in results["forward_backward"]:
        if r["res"] == 128:
            print(f"fwd+bwd {r['scene']:12s} N={r['n']:>7,d} 128px: numpy allocation peak {r['alloc_peak_mb']:.1f} MB")
    print(f"process peak RSS {results['peak_rss_mb']:.0f} MB (includes torch, MuJoCo and all scenes)")
    print("\n== bars (issue #2) ==")
    for b in results["bars"]:
        print(f"{'MET ' if b['met'] else 'MISS'}  {b['what']:40s} bar {b['bar']:>6}  got {b['got']:8.1f}")


if __name__ == "__main__":
    main()
