"""A scene's sky: an equirectangular image seen along every camera ray that no Gaussian covers.

Convention (Blender's, z-up world, as `assets.sky`): the centre column looks along +x, u grows
as the azimuth turns from +x towards -y, row 0 is straight up, the last row straight down.
"""

from __future__ import annotations

import numpy as np

from .camera import Camera

__all__ = ["check_sky", "sky_background", "sky_colors", "texel_coords", "sky_rays", "composite_sky", "SKY_VISIBLE_BELOW"]

#: Pixels with alpha at or above this show no sky: (1 - alpha) x 1 is under half a uint8 step there.
SKY_VISIBLE_BELOW = 0.999


def check_sky(image: object) -> np.ndarray:
    """The sky image as read-only float32 [H, W, 3] in [0, 1] (`ValueError` naming the problem)."""
    a = np.asarray(image, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] != 3 or min(a.shape[:2]) < 2:
        raise ValueError(f"Expected a sky image of shape (H, W, 3) with H, W >= 2, found {a.shape}")
    if not np.all(np.isfinite(a)) or a.min() < 0 or a.max() > 1:
        raise ValueError("Expected sky colours in [0, 1]")
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


def texel_coords(directions: np.ndarray, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """Continuous texel coordinates (u, v) of world directions [N, 3] in a w x h sky image (the
    lookup of `sky_colors`; v clipped to the rows), in the directions' float precision."""
    d = directions / np.maximum(np.linalg.norm(directions, axis=1, keepdims=True), 1e-12)
    u = (np.float32(0.5) - np.arctan2(d[:, 1], d[:, 0]) * np.float32(1 / (2 * np.pi))) * w - np.float32(0.5)
    v = np.clip((np.float32(0.5) - np.arcsin(np.clip(d[:, 2], -1, 1)) * np.float32(1 / np.pi)) * h - np.float32(0.5),
                0, h - 1)
    return u, v


def sky_colors(image: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Bilinear sky colour along each world direction. [N, 3] -> float32 [N, 3]"""
    h, w = image.shape[:2]
    u, v = texel_coords(np.asarray(directions, dtype=np.float32), w, h)
    u0, v0 = np.floor(u), np.floor(v)
    fu, fv = (u - u0)[:, None], (v - v0)[:, None]
    u0 = u0.astype(np.int64) % w
    u1 = (u0 + 1) % w
    v0 = v0.astype(np.int64)
    v1 = np.minimum(v0 + 1, h - 1)
    top = image[v0, u0] * (1 - fu) + image[v0, u1] * fu
    bottom = image[v1, u0] * (1 - fu) + image[v1, u1] * fu
    return (top * (1 - fv) + bottom * fv).astype(np.float32)


def sky_rays(camera: Camera, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """World directions (not normalised) of the rays through pixel centres (rows, cols). -> [N, 3]"""
    K = camera.K
    x = (cols.astype(np.float64) + 0.5 - K[0, 2]) / K[0, 0]
    y = (rows.astype(np.float64) + 0.5 - K[1, 2]) / K[1, 1]
    d = np.stack([x, y, np.ones_like(x)], axis=1)         # OpenCV camera frame
    return d @ np.asarray(camera.world_to_camera)[:3, :3]  # R^T d for each ray


def sky_background(image: np.ndarray, camera: Camera) -> np.ndarray:
    """The sky behind every pixel of `camera`: float32 [H, W, 3]."""
    rows, cols = np.indices((camera.height, camera.width)).reshape(2, -1)
    return sky_colors(image, sky_rays(camera, rows, cols)).reshape(camera.height, camera.width, 3)


def composite_sky(rgb: np.ndarray, alpha: np.ndarray, image: np.ndarray, cameras: list[Camera]) -> np.ndarray:
    """Renders on black [C, H, W, 3] with the sky behind what the Gaussians leave uncovered (only
    the pixels with alpha below `SKY_VISIBLE_BELOW` look the sky up: a ground-filled view costs
    little)."""
    out = np.array(rgb, dtype=np.float32, copy=True)
    for c, camera in enumerate(cameras):
        rows, cols = np.nonzero(alpha[c] < SKY_VISIBLE_BELOW)
        if len(rows):
            behind = sky_colors(image, sky_rays(camera, rows, cols))
            out[c, rows, cols] += (1.0 - alpha[c, rows, cols, None]) * behind
    return out.astype(rgb.dtype, copy=False)
