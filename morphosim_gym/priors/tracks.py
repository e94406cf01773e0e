"""Long point tracks from chained DIS optical flow with a forward-backward consistency check.

Points are seeded on a grid at a few anchor frames spread over the clip and followed both
forward and backward from there, so that an object that enters the view after the first frame
(a bus driving in from the edge) gets tracks too; a later anchor seeds only where no track
seeded earlier is still followed.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["flow_tracks", "sample_field"]


def sample_field(field: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Bilinear lookup of an [H, W, 2] field at float pixel positions [P, 2] (x, y; centres at +0.5)."""
    m = pts.astype(np.float32)[None] - 0.5  # cv2.remap uses integer-centred coordinates
    return cv2.remap(field, m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)[0]


def _follow(pts: np.ndarray, steps: list[tuple[np.ndarray, np.ndarray]], w: int, h: int,
            fb_threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Chain points [P, 2] through (flow there, flow back) pairs; -> positions and alive [S, P]."""
    out, alive_out = [], []
    alive = np.ones(len(pts), bool)
    cur = pts.copy()
    for there, back in steps:
        nxt = cur + sample_field(there, cur)
        ret = nxt + sample_field(back, nxt)
        inside = (nxt[:, 0] >= 0) & (nxt[:, 0] <= w) & (nxt[:, 1] >= 0) & (nxt[:, 1] <= h)
        alive &= inside & (np.linalg.norm(ret - cur, axis=1) <= fb_threshold)
        cur = np.where(alive[:, None], nxt, cur)
        out.append(cur.copy())
        alive_out.append(alive.copy())
    return np.asarray(out).reshape(len(steps), len(pts), 2), np.asarray(alive_out).reshape(len(steps), len(pts))


def _free(grid: np.ndarray, tracked: np.ndarray, spacing: float) -> np.ndarray:
    """[G] bool: grid points with no tracked point [P, 2] within half a grid spacing."""
    if len(tracked) == 0:
        return np.ones(len(grid), bool)
    cell = np.floor(tracked / spacing).astype(np.int64)
    taken = set(map(tuple, cell.tolist()))
    g = np.floor(grid / spacing).astype(np.int64)
    return np.array([tuple(c) not in taken for c in g.tolist()], bool)


def flow_tracks(frames: np.ndarray, spacing: int = 8, fb_threshold: float = 1.0,
                preset: int = cv2.DISOPTICAL_FLOW_PRESET_ULTRAFAST, anchors: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Point tracks from chained DIS optical flow with a forward-backward check.

    A point whose round trip misses by more than `fb_threshold` pixels, or that leaves the
    image, is marked invisible from then on in that direction (its position stays at the last
    good estimate).

    Args:
        frames: [T, H, W, 3] uint8.
        spacing: grid spacing in pixels of the seeded points.
        fb_threshold: maximum forward-backward round-trip error in pixels.
        anchors: frames (spread evenly, the first and last included) that seed points.

    Returns:
        tracks [P, T, 2] float32 pixel (x, y) (centre of pixel (i, j) at (j + 0.5, i + 0.5));
        visible [P, T] bool. The points of frame 0 come first, in grid order.
    """
    f = np.asarray(frames)
    t, h, w = f.shape[:3]
    s = max(1, int(spacing))
    ys, xs = np.meshgrid(np.arange(s / 2, h, s), np.arange(s / 2, w, s), indexing="ij")
    grid = np.stack([xs.ravel(), ys.ravel()], -1).astype(np.float32)
    if t == 1:
        return grid[:, None].copy(), np.ones((len(grid), 1), bool)
    dis = cv2.DISOpticalFlow_create(preset)
    gray = [cv2.cvtColor(np.ascontiguousarray(fr), cv2.COLOR_RGB2GRAY) for fr in f]
    fwd = [dis.calc(gray[k], gray[k + 1], None) for k in range(t - 1)]     # k -> k + 1
    bwd = [dis.calc(gray[k + 1], gray[k], None) for k in range(t - 1)]     # k + 1 -> k
    all_tracks, all_vis = [], []
    for a in sorted(set(np.linspace(0, t - 1, max(1, int(anchors))).round().astype(int).tolist())):
        if all_tracks:
            tr, vi = np.concatenate(all_tracks), np.concatenate(all_vis)
            pts = grid[_free(grid, tr[vi[:, a], a], s)]
        else:
            pts = grid
        if len(pts) == 0:
            continue
        tracks = np.zeros((len(pts), t, 2), np.float32)
        vis = np.zeros((len(pts), t), bool)
        tracks[:, a], vis[:, a] = pts, True
        if a < t - 1:
            pos, alive = _follow(pts, [(fwd[k], bwd[k]) for k in range(a, t - 1)], w, h, fb_threshold)
            tracks[:, a + 1:], vis[:, a + 1:] = pos.transpose(1, 0, 2), alive.T
        if a > 0:
            pos, alive = _follow(pts, [(bwd[k], fwd[k]) for k in range(a - 1, -1, -1)], w, h, fb_threshold)
            tracks[:, :a], vis[:, :a] = pos[::-1].transpose(1, 0, 2), alive[::-1].T
        all_tracks.append(tracks)
        all_vis.append(vis)
    return np.concatenate(all_tracks), np.concatenate(all_vis)
