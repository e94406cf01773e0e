"""The procedural clip backend (offline default): a generate plan -> a `GeneratedClip`.

It composes the ground-truth `Scene4D` (see `compose.py`), renders every frame from the
generation camera with our splatting renderer (rgb, depth and instance ids in one pass),
and tracks points of the scene through the clip. The frames are exactly renders of
`clip.ground_truth`, and the same plan and seed give a bit-identical clip.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..render import render
from ..scene import GeneratedClip, Scene4D
from .compose import ComposedScene, GenerationConfig, compose_scene

__all__ = ["ProceduralBackend", "track_points"]


class ProceduralBackend:
    """Builds clips from shaped, textured Gaussian primitives.

    Args:
        config: clip size and length, level of detail.
        render_backend: renderer for the frames ("cpu" default).
        tracks_per_object: points tracked on each object (the setting gets twice as many).
    """

    name = "procedural"

    def __init__(self, config: GenerationConfig | None = None, render_backend: str = "cpu",
                 tracks_per_object: int = 48) -> None:
        self.config = config or GenerationConfig()
        self.render_backend = render_backend
        self.tracks_per_object = int(tracks_per_object)

    def compose(self, plan: Any, seed: int, prompt: str | None = None) -> ComposedScene:
        """Only the ground-truth scene and trajectories (no frames)."""
        return compose_scene(plan, seed, self.config, prompt)

    def generate(self, plan: Any, seed: int, prompt: str | None = None) -> GeneratedClip:
        """A clip of this generate plan (frames, cameras, depth, instance masks, tracks, ground truth)."""
        start = time.perf_counter()
        comp = self.compose(plan, seed, prompt)
        scene, cams = comp.scene, comp.cameras
        cfg = self.config
        T, H, W = cfg.num_frames, cfg.height, cfg.width
        frames = np.empty((T, H, W, 3), np.uint8)
        depth = np.empty((T, H, W), np.float32)
        masks = np.empty((T, H, W), np.int32)
        for i in range(T):
            out = render(scene, cams[i], t=i / cfg.fps, backend=self.render_backend)
            frames[i] = out.rgb_uint8()
            depth[i] = out.depth
            masks[i] = out.instance
        rng = np.random.default_rng([int(seed), 3])
        tracks, visible, track_objects = track_points(scene, cams, depth, masks, rng, self.tracks_per_object)
        info = {
            "backend": self.name, "seed": int(seed), "plan": plan.to_dict() if hasattr(plan, "to_dict") else None,
            "setting": comp.setting.name,
            "trajectories": {name: tr.to_dict() for name, tr in comp.trajectories.items()},
            "track_objects": track_objects.tolist(),
            "seconds": round(time.perf_counter() - start, 4),
        }
        return GeneratedClip(frames=frames, cameras=tuple(cams), fps=cfg.fps, depth=depth, masks=masks,
                             labels=scene.id_to_name, tracks=tracks, track_visible=visible,
                             prompt=prompt if prompt is not None else getattr(plan, "text", ""),
                             ground_truth=scene, info=info)


def track_points(scene: Scene4D, cameras, depth: np.ndarray, masks: np.ndarray, rng: np.random.Generator,
                 per_object: int = 48) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2D tracks of Gaussian centres: positions [P, T, 2], visibility [P, T], object id [P].

    A point counts as visible in a frame when it projects inside the image, in front of the
    camera, onto a pixel of its own object whose rendered depth is within 5% of its own.
    """
    ids = scene.gaussians.object_ids
    picks = []
    for obj in scene.objects:
        members = np.flatnonzero(ids == obj.id)
        k = min(len(members), per_object * (2 if obj.role == "background" else 1))
        if k:
            picks.append(np.sort(rng.choice(members, size=k, replace=False)))
    idx = np.concatenate(picks) if picks else np.zeros(0, int)
    T, H, W = depth.shape
    tracks = np.zeros((len(idx), T, 2), np.float32)
    visible = np.zeros((len(idx), T), bool)
    for i in range(T):
        pts = scene.at(i / scene.fps).means[idx]
        uv, z = cameras[i].project(pts)
        tracks[:, i] = uv
        col = np.floor(uv[:, 0]).astype(np.int64)
        row = np.floor(uv[:, 1]).astype(np.int64)
        inside = (z > cameras[i].near) & (col >= 0) & (col < W) & (row >= 0) & (row < H)
        c, r = np.clip(col, 0, W - 1), np.clip(row, 0, H - 1)
        same = masks[i, r, c] == ids[idx]
        near_surface = np.abs(depth[i, r, c] - z) <= 0.05 * np.maximum(z, 1e-6)
        visible[:, i] = inside & same & near_surface
    return tracks, visible, ids[idx]
