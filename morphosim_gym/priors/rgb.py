"""`RGBPriorEstimators`: the offline default (CPU, no weights) for clips that come without priors."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..scene.camera import Camera
from .depth import contact_depth, ground_plane_depth
from .masks import label_regions, motion_foreground
from .protocol import BoxTrack
from .tracks import flow_tracks

__all__ = ["SETTING_ID", "RGBPriorEstimators"]

SETTING_ID = 0      # the setting (ground, road, water...) in estimated masks; objects are 1..


@dataclass(frozen=True)
class RGBPriorEstimators:
    """Priors from the frames and cameras alone.

    - masks: moving regions (`masks.motion_foreground`) labelled with the plan's moving objects
      (`masks.label_regions`); the other pixels are the setting (id 0, label `setting_label`;
      above the horizon only with `backdrop`, else -1). Attention maps are not used. Static objects
      other than the setting are not found (they join the setting).
    - depth: the ground plane z = `ground_height` for the setting; each object region gets the
      ground depth where its lowest pixels meet the ground (objects stand on the ground), or the
      median ground depth when they touch none.
    - tracks: chained DIS optical flow with a forward-backward check (`tracks.flow_tracks`).

    Attributes:
        ground_height: world z of the ground plane (metres).
        max_depth: ground farther than this is unknown (0).
        track_spacing: pixel spacing of the tracked point grid.
        fb_threshold: forward-backward check tolerance in pixels.
        box_margin: planned boxes grow by this fraction of their size before labelling.
        setting_label: label of id 0.
        backdrop: pixels above the horizon are part of the setting, at the depth of the farthest
            ground seen (a backdrop: a generated frame draws something there); False leaves them
            unknown (depth 0, mask -1).
    """

    ground_height: float = 0.0
    max_depth: float = 50.0
    track_spacing: int = 4
    fb_threshold: float = 1.0
    box_margin: float = 0.25
    setting_label: str = "ground"
    backdrop: bool = True

    def _cameras(self, camera: Camera | Sequence[Camera], t: int) -> list[Camera]:
        cams = [camera] * t if isinstance(camera, Camera) else list(camera)
        if len(cams) != t:
            raise ValueError(f"Expected one camera or {t} cameras, found {len(cams)}")
        return cams

    def depth(self, frames: np.ndarray, camera: Camera | Sequence[Camera],
              masks: np.ndarray | None = None) -> np.ndarray:
        t = len(frames)
        cams = self._cameras(camera, t)
        out = np.stack([ground_plane_depth(c, self.ground_height, self.max_depth) for c in cams])
        if self.backdrop:
            # above the horizon: a backdrop as far as the farthest ground seen
            far = float(out.max()) if np.any(out > 0) else self.max_depth
            out = np.where(out > 0, out, far).astype(np.float32)
        if masks is None:
            return out
        valid = out[out > 0]
        fallback = float(np.median(valid)) if valid.size else 1.0
        for i in range(t):
            ground = out[i].copy()
            for inst in np.unique(masks[i]):
                if inst <= SETTING_ID:
                    continue
                sel = masks[i] == inst
                others = (masks[i] > SETTING_ID) & ~sel          # an object in front hides the contact
                out[i][sel] = contact_depth(sel, ground, fallback, blocked=others)
        return out.astype(np.float32)

    def masks(self, frames: np.ndarray, attention: np.ndarray | None, targets: Sequence[BoxTrack],
              cameras: Sequence[Camera] | None = None) -> tuple[np.ndarray, dict[int, str]]:
        f = np.asarray(frames)
        t, h, w = f.shape[:3]
        fg = motion_foreground(f, cameras, targets, self.ground_height, self.box_margin)
        ids, labels = label_regions(fg, targets, self.box_margin, frames=f)
        ids = ids.copy()
        if cameras is not None and not self.backdrop:
            below = np.stack([ground_plane_depth(c, self.ground_height, self.max_depth) > 0
                              for c in self._cameras(cameras, t)])
        else:
            below = np.ones((t, h, w), bool)
        setting = (ids == 0) & below
        ids[ids == 0] = -1
        ids[setting] = SETTING_ID
        if setting.any():
            labels = {SETTING_ID: self.setting_label, **labels}
        present = set(np.unique(ids).tolist())
        return ids, {k: v for k, v in labels.items() if k in present}

    def tracks(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return flow_tracks(frames, self.track_spacing, self.fb_threshold)
