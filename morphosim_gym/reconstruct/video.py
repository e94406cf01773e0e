"""A video to a scene file: `reconstruct_video(path, out_dir)` reads the clip (`GeneratedClip.from_video`),
fits a `Scene4D` with a feature field (`reconstruct`, priors estimated from the frames) and writes
`out_dir/scene.msim`, `out_dir/preview.png` (input frames over their renders) and
`out_dir/info.json` (how the video was read, the cameras, the objects, the time taken).

`fit_video(clip)` is the fit itself: `reconstruct`, then `video_layers.motion_layers` (for a still
camera the movers as per-frame layers moved between the fitted frames, over a median background
plate; for a moving camera every fitted frame as a layer, turned with the camera between frames).
On vtest.avi (still) and bikes.mp4 (panning) this lifts held-out-frame PSNR above holding the
previous frame (`benchmarks/video.py`)."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..scene import GeneratedClip, Scene4D, save_scene
from .pipeline import ReconstructionConfig, reconstruct
from .video_layers import LayerConfig, motion_layers

__all__ = ["LAYER_CHOICES", "VideoResult", "fit_video", "preview_strip", "reconstruct_video"]

SCENE_NAME, PREVIEW_NAME, INFO_NAME = "scene.msim", "preview.png", "info.json"


@dataclass(frozen=True, eq=False)
class VideoResult:
    """What `reconstruct_video` wrote and fitted."""

    clip: GeneratedClip
    scene: Scene4D
    scene_path: Path
    preview_path: Path
    info_path: Path
    seconds: float


def render_frame(scene: Scene4D, clip: GeneratedClip, i: int) -> np.ndarray:
    """[H, W, 3] uint8 render of `scene` from frame i's camera at frame i's time."""
    from ..render import render

    out = render(scene, clip.cameras[i], t=i / clip.fps)
    return (np.clip(np.asarray(out.rgb), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def preview_strip(clip: GeneratedClip, scene: Scene4D, count: int = 3) -> np.ndarray:
    """[2H, count * W, 3] uint8: `count` evenly spaced input frames (top) over their renders (bottom)."""
    idx = np.linspace(0, clip.num_frames - 1, count).round().astype(int)
    top = np.concatenate([clip.frames[i] for i in idx], axis=1)
    bottom = np.concatenate([render_frame(scene, clip, int(i)) for i in idx], axis=1)
    return np.concatenate([top, bottom], axis=0)


def fit_video(clip: GeneratedClip, config: ReconstructionConfig | None = None,
              layers: LayerConfig | None = LayerConfig()) -> Scene4D:
    """The scene of a video clip: `reconstruct(clip, config)`, then `motion_layers` with `layers`
    (None: the scaffold fit alone)."""
    scene = reconstruct(clip, config)
    if layers is None or clip.num_frames < 2:
        return scene
    layered = motion_layers(scene, clip, config=layers)
    if hasattr(scene, "_fit_log"):
        layered._fit_log = scene._fit_log          # for reports (not saved)
    return layered


def _summary(clip: GeneratedClip, scene: Scene4D, seconds: float) -> dict[str, Any]:
    return {"video": clip.info.get("video"), "camera": clip.info.get("camera"), "prompt": clip.prompt or None,
            "frames": clip.num_frames, "size": [clip.width, clip.height], "fps": clip.fps,
            "objects": [{"id": o.id, "name": o.name, "category": o.category, "dynamic": o.dynamic, "role": o.role}
                        for o in scene.objects],
            "gaussians": len(scene.gaussians), "motion_frames": scene.motion.num_frames, "seconds": round(seconds, 2),
            "priors": getattr(scene, "_fit_log", {}).get("priors")}


LAYER_CHOICES = {"auto": LayerConfig(), "movers": LayerConfig(frames=False), "none": None}


def reconstruct_video(path: str | Path, out_dir: str | Path, fov_deg: float = 50.0, prompt: str | None = None,
                      max_frames: int = 49, size: int = 160, camera: str = "auto",
                      config: ReconstructionConfig | None = None, layers: str = "auto", **video: Any) -> VideoResult:
    """Read `path`, fit, write the scene, the preview and the summary into `out_dir` (created).

    `layers` (`LAYER_CHOICES`): "auto" (`LayerConfig()`: a moving camera's frames as layers, a still
    one's movers over a plate), "movers" (no frame layers: a panning video's scene file ~2.5x
    smaller, its held-out frames ~2 dB worse on bikes.mp4) or "none" (the scaffold fit alone). Extra keyword arguments go to `GeneratedClip.from_video` (fps, camera_height,
    pitch_deg, shot)."""
    if layers not in LAYER_CHOICES:
        raise ValueError(f"Expected layers in {sorted(LAYER_CHOICES)}, found {layers!r}")
    import imageio.v3 as iio

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"Expected --out as a directory for scene.msim and preview.png, found a file: {out}")
    clip = GeneratedClip.from_video(path, fov_deg=fov_deg, prompt=prompt, max_frames=max_frames, size=size,
                                    camera=camera, **video)
    cfg = config or ReconstructionConfig()
    if cfg.priors == "ground_truth":
        raise ValueError("Expected priors 'auto' or 'estimated' for a video (it carries no ground truth), "
                         "found 'ground_truth'")
    start = time.perf_counter()
    scene = fit_video(clip, cfg, layers=LAYER_CHOICES[layers])
    seconds = time.perf_counter() - start
    out.mkdir(parents=True, exist_ok=True)
    scene_path, preview_path, info_path = out / SCENE_NAME, out / PREVIEW_NAME, out / INFO_NAME
    save_scene(scene, scene_path)
    iio.imwrite(preview_path, preview_strip(clip, scene))
    info_path.write_text(json.dumps(_summary(clip, scene, seconds), indent=2, default=str))
    return VideoResult(clip, scene, scene_path, preview_path, info_path, seconds)
