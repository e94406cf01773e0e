"""Pluggable prior estimators for diffusion clips: depth, instance masks, point tracks.

A diffusion model gives only RGB frames; reconstruction also wants priors. Anything with the
three methods of `PriorEstimators` can supply them (a learned monocular depth model, a video
segmenter, a point tracker...). `DefaultPriorEstimators` works offline with no weights and is
HEURISTIC throughout:

- depth: a ground-plane prior. Every pixel whose ray hits the world plane z = `ground_height`
  in front of the camera gets that hit's camera depth; pixels at or above the horizon (or
  farther than `max_depth`) get 0, the clip's "unknown" value. Objects are ignored: it is a
  layout prior, not an estimate of the generated content.
- masks: per target, the guided motion-token attention map (latent grid, upsampled bilinearly
  to the frame size), normalised per frame by its maximum, thresholded at `mask_threshold`, and
  intersected with the target's box for that frame; when that leaves nothing, the box itself.
  Overlaps go to the target with the larger normalised attention. Labels are the target labels.
- tracks: OpenCV DIS optical flow (`cv2.DISOpticalFlow_create`) chained frame to frame from a
  regular grid of points on frame 0, with a forward-backward consistency check: a point whose
  round trip misses by more than `fb_threshold` pixels, or that leaves the image, is marked
  invisible from then on (its position stays at the last good estimate).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import cv2
import numpy as np

from ...scene.camera import Camera
from .targets import GuidanceTarget, latent_frame_groups

__all__ = ["PriorEstimators", "DefaultPriorEstimators", "ground_plane_depth", "flow_tracks"]


@runtime_checkable
class PriorEstimators(Protocol):
    """What the diffusion backend asks for each generated clip; return None to skip a prior."""

    def depth(self, frames: np.ndarray, camera: Camera) -> np.ndarray | None:
        """frames [T, H, W, 3] uint8 -> [T, H, W] float32 camera-z depth (0 where unknown)."""

    def masks(self, frames: np.ndarray, attention: np.ndarray | None,
              targets: Sequence[GuidanceTarget]) -> tuple[np.ndarray, dict[int, str]] | None:
        """frames [T, H, W, 3], attention [N_targets, T_lat, H_lat, W_lat] (or None) ->
        ([T, H, W] int32 instance ids, -1 background; {id: label})."""

    def tracks(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """frames [T, H, W, 3] -> (tracks [P, T, 2] float32 pixel x, y; visible [P, T] bool)."""


def ground_plane_depth(camera: Camera, ground_height: float = 0.0, max_depth: float = 50.0) -> np.ndarray:
    """[H, W] float32 camera-z depth of the world plane z = ground_height seen by `camera`
    (0 where the pixel ray misses the plane, hits it behind the camera or beyond `max_depth`)."""
    jj, ii = np.moveaxis(camera.pixel_centres(), -1, 0)
    dirs_cam = np.stack([(jj - camera.cx) / camera.fx, (ii - camera.cy) / camera.fy, np.ones_like(jj)], -1)
    c2w = camera.camera_to_world
    dirs = dirs_cam @ c2w[:3, :3].T  # world direction per unit camera depth
    origin_z = c2w[2, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (ground_height - origin_z) / dirs[..., 2]  # camera depth at which the ray meets the plane
    ok = np.isfinite(z) & (z > camera.near) & (z <= max_depth)
    return np.where(ok, z, 0.0).astype(np.float32)


def _sample(field: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Bilinear lookup of an [H, W, 2] field at float pixel positions [P, 2] (x, y; centres at +0.5)."""
    m = pts.astype(np.float32)[None] - 0.5  # cv2.remap uses integer-centred coordinates
    return cv2.remap(field, m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)[0]


def flow_tracks(frames: np.ndarray, spacing: int = 8, fb_threshold: float = 1.0,
                preset: int = cv2.DISOPTICAL_FLOW_PRESET_MEDIUM) -> tuple[np.ndarray, np.ndarray]:
    """Point tracks from chained DIS optical flow with a forward-backward check.

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
        nxt = cur + _sample(fwd, cur)
        back = nxt + _sample(bwd, nxt)
        inside = (nxt[:, 0] >= 0) & (nxt[:, 0] <= w) & (nxt[:, 1] >= 0) & (nxt[:, 1] <= h)
        alive &= inside & (np.linalg.norm(back - cur, axis=1) <= fb_threshold)
        cur = np.where(alive[:, None], nxt, cur)
        tracks[:, k + 1], vis[:, k + 1] = cur, alive
    return tracks, vis


@dataclass
class DefaultPriorEstimators:
    """Offline heuristic priors (see the module docstring for what each one assumes).

    Attributes:
        ground_height: world z of the ground plane for the depth prior (metres).
        max_depth: depths beyond this are reported as unknown (0).
        mask_threshold: fraction of the per-frame attention maximum kept in a mask.
        temporal_compression: video frames per latent frame of the VAE (CogVideoX: 4).
        track_spacing: pixel spacing of the tracked point grid.
        fb_threshold: forward-backward check tolerance in pixels.
    """

    ground_height: float = 0.0
    max_depth: float = 50.0
    mask_threshold: float = 0.5
    temporal_compression: int = 4
    track_spacing: int = 8
    fb_threshold: float = 1.0

    def depth(self, frames: np.ndarray, camera: Camera) -> np.ndarray:
        d = ground_plane_depth(camera, self.ground_height, self.max_depth)
        return np.broadcast_to(d, (len(frames),) + d.shape).copy()

    def masks(self, frames: np.ndarray, attention: np.ndarray | None,
              targets: Sequence[GuidanceTarget]) -> tuple[np.ndarray, dict[int, str]]:
        t, h, w = np.asarray(frames).shape[:3]
        out = np.full((t, h, w), -1, np.int32)
        best = np.zeros((t, h, w), np.float32)
        labels = {}
        groups = latent_frame_groups(t, self.temporal_compression) if attention is not None else None
        for k, tgt in enumerate(targets):
            labels[k] = tgt.label
            if tgt.num_frames != t:
                raise ValueError(f"Expected {t} boxes for target {tgt.label!r}, found {tgt.num_frames}")
            for i in range(t):
                x0, y0, x1, y1 = tgt.boxes[i]
                box = np.zeros((h, w), bool)
                box[int(np.floor(y0 * h)):int(np.ceil(y1 * h)), int(np.floor(x0 * w)):int(np.ceil(x1 * w))] = True
                score = box.astype(np.float32) * 0.5
                if attention is not None:
                    li = next(j for j, g in enumerate(groups) if i in g)
                    a = cv2.resize(np.asarray(attention[k, li], np.float32), (w, h), interpolation=cv2.INTER_LINEAR)
                    a = a / max(float(a.max()), 1e-12)
                    keep = box & (a >= self.mask_threshold)
                    if keep.any():
                        score = np.where(keep, a, 0.0).astype(np.float32)
                take = (score > 0) & (score > best[i])
                out[i][take], best[i][take] = k, score[take]
        return out, labels

    def tracks(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return flow_tracks(frames, self.track_spacing, self.fb_threshold)
