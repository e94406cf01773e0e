"""Depth from the camera and the ground plane: the ground itself, and objects standing on it."""

from __future__ import annotations

import numpy as np

from ..scene.camera import Camera

__all__ = ["below_lowest", "contact_depth", "ground_plane_depth", "wall_depth"]


def ground_plane_depth(camera: Camera, ground_height: float = 0.0, max_depth: float = 50.0) -> np.ndarray:
    """[H, W] float32 camera-z depth of the world plane z = ground_height seen by `camera`
    (0 where the pixel ray misses the plane, hits it behind the camera or beyond `max_depth`)."""
    dirs = _world_rays(camera)
    origin_z = camera.camera_to_world[2, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (ground_height - origin_z) / dirs[..., 2]  # camera depth at which the ray meets the plane
    ok = np.isfinite(z) & (z > camera.near) & (z <= max_depth)
    return np.where(ok, z, 0.0).astype(np.float32)


def contact_depth(mask: np.ndarray, ground: np.ndarray, fallback: float, blocked: np.ndarray | None = None,
                  percentile: float = 50.0) -> float:
    """Camera depth of an object from where its mask [H, W] meets the ground: the ground depth
    [H, W] under the mask's lowest pixels (the `percentile` over its bottom row's columns, taken
    one pixel below the mask: a low one takes the nearest contacts, the feet of a sheep rather
    than the ground seen under its belly). Columns where the pixel below is `blocked` [H, W] (another object in
    front hides the contact) are left out unless every column is. `fallback` when the mask
    touches no ground (a fish in the water, a bird in the sky) or is empty."""
    c, below = below_lowest(mask)
    if len(c) == 0:
        return float(fallback)
    if blocked is not None:
        free = ~blocked[below, c]
        if free.any():
            c, below = c[free], below[free]
    z = ground[below, c]
    z = z[z > 0]
    return float(np.percentile(z, percentile)) if z.size else float(fallback)


def below_lowest(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The columns a mask [H, W] covers, and in each the row just below its lowest pixel (its
    own last row at the image's bottom edge): where it meets what it stands on."""
    rows, cols = np.nonzero(mask)
    bottom = np.full(mask.shape[1], -1)
    np.maximum.at(bottom, cols, rows)
    c = np.flatnonzero(bottom >= 0)
    return c, np.minimum(bottom[c] + 1, mask.shape[0] - 1)


def _world_rays(camera: Camera) -> np.ndarray:
    """[H, W, 3] world direction of each pixel's ray per unit of camera depth."""
    jj, ii = np.moveaxis(camera.pixel_centres(), -1, 0)
    dirs_cam = np.stack([(jj - camera.cx) / camera.fx, (ii - camera.cy) / camera.fy, np.ones_like(jj)], -1)
    return dirs_cam @ camera.camera_to_world[:3, :3].T


def wall_depth(camera: Camera, seam: np.ndarray, ground: np.ndarray, window: int = 7) -> np.ndarray:
    """[H, W] float32 camera depth of a wall standing on the ground where a frame's setting changes
    colour from floor to wall: per column x, `seam[x]` is the first floor row below the wall and
    `ground` [H, W] the ground plane's depth (0 where it is not seen). The wall is vertical,
    facing the camera's horizontal viewing direction, at the distance of the floor point at the
    seam (a running median over `window` columns; columns where the seam meets no ground take the
    nearest columns' distance). 0 at and below the seam, and everywhere when no column meets the
    ground or the camera looks straight down."""
    h, w = ground.shape
    out = np.zeros((h, w), np.float32)
    forward = camera.camera_to_world[:3, 2].astype(np.float64)
    across = np.array([forward[0], forward[1], 0.0])
    if np.linalg.norm(across) < 1e-3:
        return out
    across /= np.linalg.norm(across)
    rays = _world_rays(camera)
    facing = rays @ across                                       # [H, W] along the wall's normal per unit depth
    cols = np.arange(w)
    rows = np.clip(np.asarray(seam, np.int64), 0, h - 1)
    contact = ground[rows, cols]
    ok = (np.asarray(seam) < h) & (contact > 0) & (facing[rows, cols] > 1e-6)
    if not ok.any():
        return out
    dist = (contact * facing[rows, cols])[ok]                    # the wall's distance along its normal
    if len(dist) >= window:
        pad = np.pad(dist, window // 2, mode="edge")
        dist = np.median(np.lib.stride_tricks.sliding_window_view(pad, window), axis=1)
    dist = np.interp(cols, cols[ok], dist)
    above = np.arange(h)[:, None] < np.asarray(seam)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = dist[None, :] / facing
    return np.where(above & (facing > 1e-6) & np.isfinite(z), z, 0.0).astype(np.float32)
