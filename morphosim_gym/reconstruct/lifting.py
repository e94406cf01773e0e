"""Lift a monocular clip's depth prior to 3D points, and estimate rigid motion from tracks.

Only the clip's frames, cameras and priors are read (never `clip.ground_truth`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..scene import Camera, GeneratedClip

__all__ = ["PointSet", "backproject", "kabsch", "lift_tracks", "robust_kabsch", "instance_motion", "mask_motion", "off_border", "voxel_downsample", "interior_mask",
           "estimate_background_color"]


@dataclass
class PointSet:
    """Coloured world points with the instance id they came from and a footprint (metres per pixel)."""

    points: np.ndarray      # [n, 3]
    colors: np.ndarray      # [n, 3] in [0, 1]
    ids: np.ndarray         # [n] int
    footprint: np.ndarray   # [n] pixel size at the point's depth, metres
    normals: np.ndarray     # [n, 3] estimated from the depth map, facing the camera

    def __len__(self) -> int:
        return len(self.points)

    def subset(self, sel: np.ndarray) -> "PointSet":
        return PointSet(self.points[sel], self.colors[sel], self.ids[sel], self.footprint[sel], self.normals[sel])

    @staticmethod
    def concat(sets: list["PointSet"]) -> "PointSet":
        sets = [s for s in sets if len(s)]
        if not sets:
            return PointSet(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, int), np.zeros(0), np.zeros((0, 3)))
        return PointSet(*(np.concatenate([getattr(s, k) for s in sets]) for k in
                          ("points", "colors", "ids", "footprint", "normals")))


def interior_mask(masks: np.ndarray, depth: np.ndarray, erode: int = 1) -> np.ndarray:
    """[H, W] pixels that are safely inside one instance (eroded) and have a depth."""
    valid = depth > 0
    if erode <= 0:
        return valid
    ids = masks.astype(np.int32)
    # a pixel is interior if all its neighbours within `erode` share its id
    same = np.ones_like(valid)
    for dy in range(-erode, erode + 1):
        for dx in range(-erode, erode + 1):
            if dx == 0 and dy == 0:
                continue
            shifted = np.roll(np.roll(ids, dy, axis=0), dx, axis=1)
            same &= shifted == ids
    # also reject depth discontinuities (mixed foreground/background pixels)
    d = depth.astype(np.float32)
    grad = np.maximum(np.abs(cv2.Sobel(d, cv2.CV_32F, 1, 0, ksize=3)), np.abs(cv2.Sobel(d, cv2.CV_32F, 0, 1, ksize=3)))
    smooth = grad <= 0.5 * np.maximum(d, 1e-6)
    return valid & same & smooth


def _normals(camera: Camera, pts_img: np.ndarray) -> np.ndarray:
    """Per-pixel normals [H, W, 3] (world) from a grid of world points, oriented towards the camera."""
    dx = np.zeros_like(pts_img)
    dy = np.zeros_like(pts_img)
    dx[:, 1:-1] = pts_img[:, 2:] - pts_img[:, :-2]
    dy[1:-1] = pts_img[2:] - pts_img[:-2]
    n = np.cross(dx, dy)
    norm = np.linalg.norm(n, axis=-1, keepdims=True)
    n = np.where(norm > 1e-12, n / np.maximum(norm, 1e-12), 0.0)
    to_cam = camera.position - pts_img
    flip = np.sum(n * to_cam, axis=-1, keepdims=True) < 0
    n = np.where(flip, -n, n)
    fallback = to_cam / np.maximum(np.linalg.norm(to_cam, axis=-1, keepdims=True), 1e-12)
    return np.where(norm > 1e-12, n, fallback)


def backproject(clip: GeneratedClip, frame: int, select: np.ndarray | None = None, stride: int = 1) -> PointSet:
    """World points of a frame's pixels (every `stride`-th), from the depth prior.

    `select` [H, W] bool limits the pixels (default: interior pixels with a depth)."""
    if clip.depth is None:
        raise ValueError("Expected a clip with a depth prior for reconstruction, found none")
    cam = clip.cameras[frame]
    depth = clip.depth[frame]
    masks = clip.masks[frame] if clip.masks is not None else np.zeros(depth.shape, np.int32)
    world = cam.unproject(cam.pixel_centres(), depth)
    normals = _normals(cam, world)
    sel = interior_mask(masks, depth) if select is None else (select & (depth > 0))
    if stride > 1:
        grid = np.zeros_like(sel)
        grid[::stride, ::stride] = True
        sel = sel & grid
    rows, cols = np.nonzero(sel)
    rgb = clip.frames[frame, rows, cols].astype(np.float64) / 255.0
    z = depth[rows, cols].astype(np.float64)
    return PointSet(world[rows, cols], rgb, masks[rows, cols].astype(int), z / cam.fx * stride, normals[rows, cols])


def voxel_downsample(ps: PointSet, voxel: float) -> PointSet:
    """Keep one point per voxel of this size (the first seen), per instance id."""
    if len(ps) == 0:
        return ps
    keys = np.floor(ps.points / voxel).astype(np.int64)
    keys = np.c_[keys, ps.ids]
    _, first = np.unique(keys, axis=0, return_index=True)
    return ps.subset(np.sort(first))


def kabsch(src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rigid (R, t) minimising sum w ||R src + t - dst||^2 (no scaling; proper rotation)."""
    w = np.ones(len(src)) if weights is None else np.asarray(weights, dtype=np.float64)
    w = w / w.sum()
    cs, cd = w @ src, w @ dst
    a = (src - cs) * w[:, None]
    cov = a.T @ (dst - cd)
    u, _, vt = np.linalg.svd(cov)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return rot, cd - rot @ cs


def robust_kabsch(src: np.ndarray, dst: np.ndarray, iterations: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`kabsch` reweighted `iterations` times by a Cauchy function of each pair's residual (scale:
    3x the median residual), so a few wrong correspondences barely move it: (R, t, weights [n])."""
    w = np.ones(len(src))
    for _ in range(iterations):
        rot, tv = kabsch(src, dst, w)
        res = np.linalg.norm(src @ rot.T + tv - dst, axis=1)
        scale = max(float(np.median(res)) * 3.0, 1e-4)
        w = 1.0 / (1.0 + (res / scale) ** 2)
    return rot, tv, w


def lift_tracks(clip: GeneratedClip, frame: int, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World points of track positions in a frame via the depth prior, and which ones had a depth."""
    H, W = clip.height, clip.width
    c = np.clip(np.floor(uv[:, 0]).astype(int), 0, W - 1)
    r = np.clip(np.floor(uv[:, 1]).astype(int), 0, H - 1)
    z = clip.depth[frame, r, c].astype(np.float64)
    return clip.cameras[frame].unproject(uv, z), z > 0


def instance_tracks(clip: GeneratedClip, instance: int, tolerance: float | None = None,
                    min_tracks: int = 8) -> np.ndarray:
    """Indices of the 2D tracks that belong to an instance: those landing on its mask in more
    than 80% of the frames where they are visible. A track counts as on the mask within
    `tolerance` pixels of it. By default (None) first exactly on it, and, when fewer than
    `min_tracks` tracks qualify so, within twice the clip's track noise (`track_noise`, rounded):
    1-2 px of noise must not take a small object's tracks away from it, while a large object
    keeps only the tracks really on it."""
    tr, vis = clip.tracks, clip.track_visible
    if tolerance is None:
        strict = instance_tracks(clip, instance, 0.0)
        if len(strict) >= min_tracks:
            return strict
        tolerance = 2.0 * track_noise(clip, np.arange(len(tr)))
        if int(round(tolerance)) == 0:
            return strict
    masks = clip.masks == instance
    r_px = int(round(tolerance))
    if r_px > 0:
        k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r_px + 1, 2 * r_px + 1))
        masks = np.stack([cv2.dilate(m.astype(np.uint8), k).astype(bool) for m in masks])
    own = np.zeros(len(tr), bool)
    for p in range(len(tr)):
        frames = np.flatnonzero(vis[p])
        if len(frames) == 0:
            continue
        uv = tr[p, frames]
        c = np.clip(np.floor(uv[:, 0]).astype(int), 0, clip.width - 1)
        r = np.clip(np.floor(uv[:, 1]).astype(int), 0, clip.height - 1)
        own[p] = masks[frames, r, c].mean() > 0.8
    return np.flatnonzero(own)


def off_border(mask: np.ndarray) -> bool:
    """Whether a mask [H, W] stays off the image border (one cut by the border changes shape as
    the object moves, so its centroid and its pixels mislead)."""
    return not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())


def mask_motion(clip: GeneratedClip, instance: int, reference: int, min_pixels: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Track-free motion of an instance: per-frame world translations [T, 3] of the centroid of
    its lifted mask relative to the reference frame, and a [T] bool of frames where the mask
    (away from the image border) was seen. A fallback for instances with too few tracks (a
    small object under noisy tracks); robust to track noise since it reads masks and depth only."""
    T = clip.num_frames
    trans = np.zeros((T, 3))
    seen = np.zeros(T, bool)

    def centroid(t: int) -> np.ndarray | None:
        m = (clip.masks[t] == instance) & (clip.depth[t] > 0)
        if m.sum() < min_pixels or not off_border(m):
            return None
        rows, cols = np.nonzero(m)
        uv = np.stack([cols + 0.5, rows + 0.5], -1).astype(np.float64)
        z = np.median(clip.depth[t][m].astype(np.float64))
        return clip.cameras[t].unproject(uv.mean(0, keepdims=True), np.array([z]))[0]

    c_ref = centroid(reference)
    if c_ref is None:
        return trans, seen
    for t in range(T):
        c = c_ref if t == reference else centroid(t)
        if c is not None:
            trans[t], seen[t] = c - c_ref, True
    est = np.flatnonzero(seen)
    for t in np.flatnonzero(~seen):
        trans[t] = trans[est[np.argmin(np.abs(est - t))]]
    return trans, seen


def track_noise(clip: GeneratedClip, idx: np.ndarray) -> float:
    """Robust per-coordinate noise level (pixels) of the given tracks: the MAD of their second
    differences over consecutive visible frames, / sqrt(6) (white noise of std s has second
    differences of std s sqrt(6); smooth motion has almost none). 0 without enough data."""
    if clip.tracks is None or len(idx) == 0 or clip.num_frames < 3:
        return 0.0
    tr, vis = clip.tracks[idx].astype(np.float64), clip.track_visible[idx]
    d2 = tr[:, :-2] - 2 * tr[:, 1:-1] + tr[:, 2:]
    ok = vis[:, :-2] & vis[:, 1:-1] & vis[:, 2:]
    vals = np.abs(d2[ok]).ravel()
    if vals.size < 8:
        return 0.0
    return float(1.4826 * np.median(vals) / np.sqrt(6.0))


def _frame_errors(clip: GeneratedClip, idx: np.ndarray, reference: int, points: np.ndarray, ok: np.ndarray,
                  rots: np.ndarray | None = None, trans: np.ndarray | None = None, min_tracks: int = 4) -> list[float]:
    """Per frame (other than the reference, with `min_tracks` of tracks `idx` seen there and a
    depth in the reference, `ok`), the median image distance between the tracked positions and
    their reference-frame world `points`, moved by that frame's pose (rotations [T, 3, 3],
    translations [T, 3]; none: not moved) and projected with that frame's camera."""
    errors = []
    for t in range(clip.num_frames):
        use = clip.track_visible[idx, t] & ok
        if t == reference or use.sum() < min_tracks:
            continue
        pts = points[use] if rots is None else points[use] @ rots[t].T + trans[t]
        uv, _ = clip.cameras[t].project(pts)
        errors.append(float(np.median(np.linalg.norm(uv - clip.tracks[idx[use], t], axis=1))))
    return errors


def reprojection_residual(clip: GeneratedClip, instance: int, reference: int, rots: np.ndarray,
                          trans: np.ndarray, min_tracks: int = 4) -> float:
    """How well per-frame rigid poses (rotations [T, 3, 3], translations [T, 3], reference-frame
    world points to each frame) explain an instance's tracks in the image, in pixels: its tracks
    lifted by depth in the reference frame, moved by each frame's pose and projected with that
    frame's camera; the median over frames of the median distance to the tracked positions
    (nan when no frame has `min_tracks` of them). Depth errors move the lifted points along
    their rays, which the image barely sees."""
    if clip.tracks is None:
        return float("nan")
    idx = instance_tracks(clip, instance)
    idx = idx[clip.track_visible[idx, reference]]
    src, ok = lift_tracks(clip, reference, clip.tracks[idx, reference])
    errors = _frame_errors(clip, idx, reference, src, ok, rots, trans, min_tracks)
    return float(np.median(errors)) if errors else float("nan")


def static_residual(clip: GeneratedClip, instance: int, reference: int, min_tracks: int = 4,
                    scales: np.ndarray = np.linspace(0.85, 1.15, 31), percentile: float = 75.0) -> float:
    """How badly "this instance does not move" explains its tracks, in pixels: the instance's
    tracks are lifted by depth in the reference frame and projected into every other frame with
    that frame's camera; each frame scores the median distance to the tracked positions, and the
    result is the `percentile` of those scores over all frames (robust to a few bad frames, where
    the largest score is not), minimised over one global depth scale (a depth prior off by a few
    percent makes a static object seem to slide as the camera moves; with a fixed camera the scale
    does not matter). 0 when too few tracks are seen."""
    if clip.tracks is None:
        return 0.0
    idx = instance_tracks(clip, instance)
    idx = idx[clip.track_visible[idx, reference]]
    if len(idx) < min_tracks:
        return 0.0
    cam_ref = clip.cameras[reference]
    src, ok = lift_tracks(clip, reference, clip.tracks[idx, reference])
    rays = src - cam_ref.position
    best = np.inf
    for s in scales:
        per_frame = _frame_errors(clip, idx, reference, cam_ref.position + s * rays, ok, min_tracks=min_tracks)
        if per_frame:
            best = min(best, float(np.percentile(per_frame, percentile)))
    return 0.0 if not np.isfinite(best) else float(best)


def instance_motion(clip: GeneratedClip, instance: int, reference: int, min_tracks: int = 4,
                    robust_iters: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-frame rigid poses of one instance relative to a reference frame, from its 2D tracks
    lifted by depth: rotations [T, 3, 3] and translations [T, 3] mapping reference-frame world
    points to each frame, plus a [T] bool of frames estimated from enough tracks (the others
    are interpolated or held)."""
    T = clip.num_frames
    rots = np.tile(np.eye(3), (T, 1, 1))
    trans = np.zeros((T, 3))
    good = np.zeros(T, bool)
    good[reference] = True
    if clip.tracks is None:
        return rots, trans, good
    tr = clip.tracks
    vis = clip.track_visible
    idx = instance_tracks(clip, instance)
    idx = idx[vis[idx, reference]]
    if len(idx) < min_tracks:
        return rots, trans, good
    src, ok_src = lift_tracks(clip, reference, tr[idx, reference])
    for t in range(T):
        if t == reference:
            continue
        use = vis[idx, t] & ok_src
        if use.sum() < min_tracks:
            continue
        dst, ok = lift_tracks(clip, t, tr[idx[use], t])
        s = src[use][ok]
        d = dst[ok]
        if len(s) < min_tracks:
            continue
        rot, tv, _ = robust_kabsch(s, d, robust_iters)
        rots[t], trans[t], good[t] = rot, tv, True
    # fill frames without an estimate: hold the nearest estimated frame
    est = np.flatnonzero(good)
    for t in np.flatnonzero(~good):
        k = est[np.argmin(np.abs(est - t))]
        rots[t], trans[t] = rots[k], trans[k]
    return rots, trans, good


def estimate_background_color(clip: GeneratedClip, far_share: float | None = None) -> tuple[float, float, float]:
    """Colour of the pixels with no depth (nothing drawn there: sky / backdrop), median over the clip.
    Where every pixel has a depth: with `far_share`, the colour of that share of the farthest
    pixels (a room's walls: what lies past them is most like the farthest thing seen), else
    mid-grey; mid-grey without depth."""
    if clip.depth is None:
        return (0.5, 0.5, 0.5)
    empty = clip.depth <= 0
    if not empty.any():
        if far_share is None:
            return (0.5, 0.5, 0.5)
        empty = clip.depth >= np.quantile(clip.depth, 1.0 - far_share)
    rgb = np.median(clip.frames[empty].astype(np.float64), axis=0) / 255.0
    return tuple(float(x) for x in np.clip(rgb, 0, 1))
