"""The diffusion backend's attention-guided prior estimator (depth, instance masks, point tracks).

The `PriorEstimators` protocol, `ground_plane_depth` and `flow_tracks` live in
`morphosim_gym.priors` (shared by every clip source and by reconstruction) and are re-exported
here. `morphosim_gym.priors.RGBPriorEstimators` estimates from the pixels alone.

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

import cv2
import numpy as np

from ...priors import PriorEstimators, flow_tracks, ground_plane_depth
from ...scene.camera import Camera
from .targets import GuidanceTarget, latent_frame_groups

__all__ = ["DefaultPriorEstimators", "PriorEstimators", "flow_tracks", "ground_plane_depth"]


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

    def depth(self, frames: np.ndarray, camera: Camera, masks: np.ndarray | None = None) -> np.ndarray:
        d = ground_plane_depth(camera, self.ground_height, self.max_depth)
        return np.broadcast_to(d, (len(frames),) + d.shape).copy()

    def masks(self, frames: np.ndarray, attention: np.ndarray | None, targets: Sequence[GuidanceTarget],
              cameras: Sequence[Camera] | None = None) -> tuple[np.ndarray, dict[int, str]]:
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
