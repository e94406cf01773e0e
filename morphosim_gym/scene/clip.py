"""`GeneratedClip`: what a 2D world generator hands to reconstruction."""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .camera import Camera
from .scene4d import Scene4D

__all__ = ["GeneratedClip"]


@dataclass(eq=False)
class GeneratedClip:
    """A monocular clip with per-frame cameras and optional priors.

    Attributes:
        frames: [T, H, W, 3] uint8 RGB.
        cameras: T Cameras (one per frame), each H x W.
        fps: frames per second.
        depth: optional [T, H, W] float32 camera-z depth prior (0 where unknown).
        masks: optional [T, H, W] int32 instance ids (-1 background).
        labels: instance id -> label text for `masks`.
        tracks: optional [P, T, 2] float32 pixel positions of P tracked points.
        track_visible: optional [P, T] bool visibility of each track.
        prompt: the text the clip was generated from.
        ground_truth: the generator's own Scene4D (evaluation only; reconstruction never reads it).
        info: free-form JSON-friendly extras (backend, seed, trajectory boxes...); a clip prepared
            for reconstruction (`morphosim_gym.priors.prepare_priors`) has info["priors"]: each
            prior's origin ("estimated", "ground_truth", "corrupted" or what the clip carried).
    """

    frames: np.ndarray
    cameras: tuple[Camera, ...]
    fps: float
    depth: np.ndarray | None = None
    masks: np.ndarray | None = None
    labels: Mapping[int, str] = field(default_factory=dict)
    tracks: np.ndarray | None = None
    track_visible: np.ndarray | None = None
    prompt: str = ""
    ground_truth: Scene4D | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        f = np.asarray(self.frames)
        if f.ndim != 4 or f.shape[-1] != 3 or f.dtype != np.uint8:
            raise ValueError(f"Expected frames as uint8 [T, H, W, 3], found {f.dtype} {f.shape}")
        t, h, w = f.shape[:3]
        if t < 1:
            raise ValueError("Expected at least one frame, found 0")
        self.frames = f
        self.cameras = tuple(self.cameras)
        if len(self.cameras) != t:
            raise ValueError(f"Expected {t} cameras (one per frame), found {len(self.cameras)}")
        for i, c in enumerate(self.cameras):
            if not isinstance(c, Camera) or (c.width, c.height) != (w, h):
                raise ValueError(f"Expected cameras[{i}] as a {w}x{h} Camera, found {c!r}")
        if not (math.isfinite(float(self.fps)) and float(self.fps) > 0):
            raise ValueError(f"Expected fps > 0, found {self.fps}")
        self.fps = float(self.fps)
        if self.depth is not None:
            d = np.asarray(self.depth, dtype=np.float32)
            if d.shape != (t, h, w):
                raise ValueError(f"Expected depth of shape {(t, h, w)}, found {d.shape}")
            if not np.all(np.isfinite(d)):
                raise ValueError("Expected finite depth, found NaN or infinite values")
            self.depth = d
        if self.masks is not None:
            m = np.asarray(self.masks)
            if m.shape != (t, h, w) or m.dtype.kind not in "iu":
                raise ValueError(f"Expected masks as integer {(t, h, w)}, found {m.dtype} {m.shape}")
            self.masks = m.astype(np.int32, copy=False)
            missing = sorted(set(np.unique(m).tolist()) - set(self.labels) - {-1})
            if missing:
                raise ValueError(f"Expected a label for every mask id, found ids without labels: {missing}")
        self.labels = {int(k): str(v) for k, v in self.labels.items()}
        if self.tracks is not None:
            tr = np.asarray(self.tracks, dtype=np.float32)
            if tr.ndim != 3 or tr.shape[1:] != (t, 2):
                raise ValueError(f"Expected tracks of shape (P, {t}, 2), found {tr.shape}")
            self.tracks = tr
            vis = np.ones(tr.shape[:2], bool) if self.track_visible is None else np.asarray(self.track_visible, bool)
            if vis.shape != tr.shape[:2]:
                raise ValueError(f"Expected track_visible of shape {tr.shape[:2]}, found {vis.shape}")
            if not np.all(np.isfinite(tr[vis])):
                raise ValueError("Expected finite tracks where visible, found NaN or infinite positions")
            self.track_visible = vis
        if self.ground_truth is not None and not isinstance(self.ground_truth, Scene4D):
            raise ValueError(f"Expected ground_truth as a Scene4D, found {type(self.ground_truth).__name__}")

    @classmethod
    def from_video(cls, path: str | Path, fov_deg: float = 50.0, prompt: str | None = None, max_frames: int = 49,
                   size: int = 160, fps: float | None = None, camera: str = "auto", camera_height: float = 1.6,
                   pitch_deg: float = 20.0, shot: int | str = "longest", start: int = 0) -> "GeneratedClip":
        """A clip of a real video: an mp4/avi/mov/mkv/webm/gif file or a folder of frames of one size.

        Frames are read within the budget (`scene.video.read_frames`): the longer side shrunk to
        `size` px, an edited video split at its cuts and the `shot` kept ("longest" or an index),
        at most `max_frames` frames (every k-th, never sparser than 5 fps; what was done is in
        `info["video"]`). Cameras (`scene.camera_motion.video_cameras`): `camera="auto"` estimates
        the rotation of a panning camera from the frames and keeps one camera when it stays under
        0.5 deg ("still" / "pan" force either); the first frame's camera stands `camera_height` m
        above the ground plane z = 0, pitched down by `pitch_deg`, with a vertical field of view
        `fov_deg`. `start` skips that many source frames of the shot. The optional `prompt` names what the video shows ("people walking on a
        street"): reconstruction labels the moving regions with its first noun and the setting
        with its setting. No depth, masks or tracks: reconstruction estimates them. `ValueError`
        naming the file for a video that cannot be decoded, a single frame, frames of different
        sizes, or a clip shorter than 3 frames.

        Examples:
            >>> clip = GeneratedClip.from_video("walk.mp4", fov_deg=50, prompt="a person walks")  # doctest: +SKIP
        """
        from .video_clip import clip_from_video

        return clip_from_video(path, fov_deg, prompt, max_frames, size, fps, camera, camera_height, pitch_deg, shot,
                               start)

    @property
    def num_frames(self) -> int:
        """T."""
        return int(self.frames.shape[0])

    @property
    def height(self) -> int:
        """H."""
        return int(self.frames.shape[1])

    @property
    def width(self) -> int:
        """W."""
        return int(self.frames.shape[2])

    @property
    def duration(self) -> float:
        """(T - 1) / fps seconds."""
        return (self.num_frames - 1) / self.fps

    def content_hash(self) -> str:
        """SHA-256 (hex) of what reconstruction reads (frames, cameras, priors), never the ground truth."""
        h = hashlib.sha256()
        h.update(self.frames.tobytes())
        for c in self.cameras:
            h.update(repr(sorted(c.to_dict().items())).encode())
        h.update(repr(self.fps).encode())
        for arr in (self.depth, self.masks, self.tracks, self.track_visible):
            h.update(b"-" if arr is None else np.ascontiguousarray(arr).tobytes())
        h.update(repr(sorted(self.labels.items())).encode())
        return h.hexdigest()

    def __repr__(self) -> str:
        priors = [n for n in ("depth", "masks", "tracks") if getattr(self, n) is not None]
        return (f"GeneratedClip({self.num_frames} frames {self.width}x{self.height} @ {self.fps:g} fps, "
                f"priors={priors}, prompt={self.prompt!r})")
