"""Quick start: build a small dynamic Gaussian scene, render it from an orbiting camera,
save it, load it back, and export one frame as a .ply.

    python examples/quickstart.py [--out out] [--size 128] [--backend cpu]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import imageio.v2 as imageio
import numpy as np

import morphosim_gym as ms
from morphosim_gym.scene.rotations import axis_angle_to_quat, quat_to_matrix


def build_scene(seed: int = 0) -> ms.Scene4D:
    """A grey floor, a red ball rolling left to right and a blue cube spinning in place."""
    rng = np.random.default_rng(seed)

    def floor(n):
        xy = rng.uniform([-2.5, -1.5], [2.5, 3.0], (n, 2))
        return np.c_[xy, np.zeros(n)], np.full((n, 3), 0.05), 0.45 + 0.1 * rng.random((n, 3))

    def ball(n, r=0.35):
        d = rng.normal(size=(n, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        shade = 0.75 + 0.25 * d[:, 2:3]
        return d * r + [-1.5, 0.5, r], np.full((n, 3), 0.06), np.clip([0.9, 0.12, 0.1] * shade, 0, 1)

    def cube(n, h=0.3):
        face = rng.integers(0, 3, n)
        p = rng.uniform(-h, h, (n, 3))
        p[np.arange(n), face] = np.sign(rng.uniform(-1, 1, n)) * h
        shade = 0.7 + 0.3 * (p[:, 2:3] / h + 1) / 2
        return p + [1.2, 1.2, h], np.full((n, 3), 0.05), np.clip([0.15, 0.3, 0.9] * shade, 0, 1)

    parts = [floor(6000), ball(3000), cube(3000)]
    means = np.concatenate([p[0] for p in parts])
    n = len(means)
    ids = np.repeat([0, 1, 2], [len(p[0]) for p in parts])
    g = ms.Gaussians(means=means, quats=np.tile([1.0, 0, 0, 0], (n, 1)), scales=np.concatenate([p[1] for p in parts]),
                     opacities=np.full(n, 0.9), colors=np.concatenate([p[2] for p in parts]), object_ids=ids)
    frames = 33
    rot = np.zeros((frames, 2, 4))
    rot[:, 0] = axis_angle_to_quat(np.array([0, 1.0, 0]), np.linspace(0, 3 * 2.0 / 0.35, frames))  # rolling
    rot[:, 1] = axis_angle_to_quat(np.array([0, 0, 1.0]), np.linspace(0, np.pi, frames))           # spinning
    trans = np.zeros((frames, 2, 3))
    ball_c = np.array([-1.5, 0.5, 0.35])
    path = ball_c + np.linspace(0, 3.0, frames)[:, None] * [1, 0, 0]
    trans[:, 0] = path - np.einsum("tij,j->ti", quat_to_matrix(rot[:, 0]), ball_c)
    cube_c = np.array([1.2, 1.2, 0.3])
    trans[:, 1] = cube_c - np.einsum("tij,j->ti", quat_to_matrix(rot[:, 1]), cube_c)
    motion = ms.Motion.rigid(np.where(ids == 0, -1, ids - 1), rot, trans, node_objects=np.array([1, 2]))
    objects = [ms.SceneObject(0, "floor", "ground", role="background"),
               ms.SceneObject(1, "ball", "ball", color=(0.9, 0.12, 0.1), dynamic=True),
               ms.SceneObject(2, "cube", "cube", color=(0.15, 0.3, 0.9), dynamic=True)]
    cam = ms.Camera.look_at((0, -4.5, 2.2), (0, 0.6, 0.3), 128, 128, 60)
    return ms.Scene4D(g, motion, objects, fps=8.0, cameras=[cam], background=(0.62, 0.78, 0.95),
                      provenance=ms.Provenance("a red ball rolls from left to right past a spinning blue cube", seed,
                                               "quickstart"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--backend", default="cpu", choices=["cpu", "torch"])
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    scene = build_scene()
    print(scene)
    cam = scene.camera.resized(args.size, args.size)
    frames, start = [], time.perf_counter()
    for i, t in enumerate(np.linspace(0, scene.duration, 3 * scene.num_frames)):
        view = cam.orbit(40.0 * np.sin(2 * np.pi * i / (3 * scene.num_frames)), center=(0, 0.6, 0.3))
        frames.append(ms.render(scene, view, t=t, backend=args.backend).rgb_uint8())
    dt = time.perf_counter() - start
    print(f"rendered {len(frames)} frames at {args.size}x{args.size} in {dt:.2f} s "
          f"({len(frames) / dt:.0f} FPS incl. first-call compile) with backend {args.backend!r}")
    imageio.mimsave(out / "quickstart.mp4", frames, fps=24, macro_block_size=1)
    path = ms.save_scene(scene, out / "quickstart.msim")
    assert ms.load_scene(path).content_hash() == scene.content_hash()
    ms.export_ply(scene, out / "quickstart_t1.ply", t=1.0)
    print(f"wrote {out / 'quickstart.mp4'}, {path}, {out / 'quickstart_t1.ply'}")


if __name__ == "__main__":
    main()
