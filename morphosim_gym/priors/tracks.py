"""Long point tracks from chained DIS optical flow with a forward-backward consistency check."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["flow_tracks", "sample_field"]


def sample_field(field: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Bilinear lookup of an [H, W, 2] field at float pixel positions [P, 2] (x, y; centres at +0.5)."""
    m = pts.astype(np.float32)[None] - 0.5  # cv2.remap uses integer-centred coordinates
    return cv2.remap(field, m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)[0]


def flow_tracks(frames: np.ndarray, spacing: int = 8, fb_threshold: float = 1.0,
                preset: int = cv2.DISOPTICAL_FLOW_PRESET_MEDIUM) -> tuple[np.ndarray, np.ndarray]:
    """Point tracks from chained DIS optical flow with a forward-backward check.

    A point whose round trip misses by more than `fb_threshold` pixels, or that leaves the
    image, is marked invisible from then on (its position stays at the last good estimate).

    Args:
        frames: [T, H, W, 3] uint8.
        spacing: grid spacing in pixels of the points seeded on frame 0.
        fb_threshold: maximum forward-backward round-trip error in pixels.

    Returns:
        tracks [P, T, 2] float32 pixel (x, y) (centre of pixel (i, j) at (j + 0.5, i + 0.5));
        visible [P, T] bool.
    """
    f = np.asarray(frames)
    t, h, w = f.shape[:3]
    s = max(1, int(spacing))
    ys, xs = np.meshgrid(np.arange(s / 2, h, s), np.arange(s / 2, w, s), indexing="ij")
    pts = np.stack([xs.ravel(), ys.ravel()], -1).astype(np.float32)
    tracks = np.zeros((len(pts), t, 2), np.float32)
    vis = np.zeros((len(pts), t), bool)
    tracks[:, 0], vis[:, 0] = pts, True
    if t == 1:
        return tracks, vis
    dis = cv2.DISOpticalFlow_create(preset)
    gray = [cv2.cvtColor(np.ascontiguousarray(fr), cv2.COLOR_RGB2GRAY) for fr in f]
    alive = np.ones(len(pts), bool)
    cur = pts.copy()
    for k in range(t - 1):
        fwd = dis.calc(gray[k], gray[k + 1], None)
        bwd = dis.calc(gray[k + 1], gray[k], None)
        nxt = cur + sample_field(fwd, cur)
        back = nxt + sample_field(bwd, nxt)
        inside = (nxt[:, 0] >= 0) & (nxt[:, 0] <= w) & (nxt[:, 1] >= 0) & (nxt[:, 1] <= h)
        alive &= inside & (np.linalg.norm(back - cur, axis=1) <= fb_threshold)
        cur = np.where(alive[:, None], nxt, cur)
        tracks[:, k + 1], vis[:, k + 1] = cur, alive
    return tracks, vis
