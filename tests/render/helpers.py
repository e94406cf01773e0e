"""Builders shared by the renderer tests: seeded random Gaussians and a few cameras."""

from __future__ import annotations

import numpy as np

from morphosim_gym.scene import Camera


def random_scene(seed: int, n: int, d: int = 0, spread: float = 0.6, log_scale=(-3.0, -1.5),
                 opacity=(0.05, 1.0), n_ids: int = 6) -> dict:
    """n random Gaussians around the origin (numpy float32, float64 where noted by the caller)."""
    rng = np.random.default_rng(seed)
    scene = {
        "means": (rng.normal(size=(n, 3)) * spread).astype(np.float32),
        "quats": rng.normal(size=(n, 4)).astype(np.float32),
        "scales": np.exp(rng.uniform(*log_scale, size=(n, 3))).astype(np.float32),
        "opacities": rng.uniform(*opacity, size=n).astype(np.float32),
        "colors": rng.uniform(0.0, 1.0, size=(n, 3)).astype(np.float32),
        "object_ids": rng.integers(-1, n_ids, size=n).astype(np.int32),
    }
    if d:
        scene["features"] = rng.normal(size=(n, d)).astype(np.float32)
    return scene


def cameras(width: int, height: int, count: int = 1) -> list:
    """Up to 4 cameras looking at the origin from different sides; the last one has an
    off-centre principal point (exercises the asymmetric Jacobian clamp)."""
    cams = [
        Camera.look_at(eye=(0.0, -3.0, 1.5), target=(0.0, 0.0, 0.0), width=width, height=height),
        Camera.look_at(eye=(2.5, -1.0, 1.0), target=(0.1, 0.0, 0.0), width=width, height=height, fov_y_deg=45),
        Camera.look_at(eye=(-1.0, 2.0, 2.5), target=(0.0, 0.0, 0.2), width=width, height=height, fov_y_deg=70),
    ]
    base = Camera.look_at(eye=(0.5, -2.5, -1.0), target=(0.0, 0.0, 0.0), width=width, height=height)
    cams.append(Camera(width, height, base.fx * 1.1, base.fy, base.cx * 0.6, base.cy * 1.3,
                       base.world_to_camera, near=0.05))
    return cams[:count] if count < 4 else cams


def camera_arrays(cams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return (np.stack([c.world_to_camera for c in cams]), np.stack([c.K for c in cams]),
            np.array([c.near for c in cams]))
