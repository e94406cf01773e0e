"""`morphosim reconstruct CLIP [--report] [--out SCENE]`: fit a 4D scene to a clip file, or
`morphosim reconstruct VIDEO [--fov DEG] [--prompt TEXT] --out DIR`: to a video (mp4/avi/gif/... or a
folder of frames), writing DIR/scene.msim, DIR/preview.png and DIR/info.json."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from ..scene.camera_motion import CAMERA_MODES
from ..scene.video import VIDEO_SUFFIXES

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the reconstruction subcommand."""
    p = sub.add_parser("reconstruct", help="fit dynamic Gaussians with a feature field to a clip (.mclip) or a video")
    p.add_argument("clip", help="a clip file written by `morphosim generate` (clip.mclip), or a video "
                                f"({', '.join(VIDEO_SUFFIXES)}) or a folder of frames")
    p.add_argument("--out", default=None, help="clip: where to write the scene (default: next to the clip, "
                                               "scene_fit.msim); video: a directory for scene.msim, preview.png "
                                               "and info.json (default: VIDEO's name + _scene, beside it)")
    video = p.add_argument_group("video input")
    video.add_argument("--fov", type=float, default=50.0, help="vertical field of view of the video, degrees (50)")
    video.add_argument("--prompt", default=None, help="what the video shows, e.g. 'people walking on a street': "
                                                      "its first noun labels the moving regions")
    video.add_argument("--max-frames", type=int, default=49, help="frame budget (every k-th frame beyond it; 49)")
    video.add_argument("--size", type=int, default=160, help="longer side of the frames in pixels (160)")
    video.add_argument("--layers", choices=("auto", "movers", "none"), default="auto",
                       help="what is drawn over the fit: auto (a panning video's frames as layers, a still "
                            "one's movers over a background plate), movers (no frame layers: a smaller "
                            "scene file for a pan), none (the fit alone)")
    video.add_argument("--camera", choices=CAMERA_MODES, default="auto",
                       help="auto: estimate a pan from the frames, still if it stays under 0.5 deg")
    p.add_argument("--report", action="store_true", help="print PSNR/SSIM on input and novel views, IoU, time")
    p.add_argument("--json", default=None, help="also write the report as JSON here")
    p.add_argument("--iterations", type=int, default=None, help="fit iterations (default: the config's)")
    p.add_argument("--feature-iterations", type=int, default=None, help="feature-field iterations (default: the config's)")
    p.add_argument("--no-cache", action="store_true", help="fit again even if a cached result exists")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=_reconstruct)


def _config(args: argparse.Namespace):  # -> ReconstructionConfig
    from dataclasses import replace

    from .pipeline import ReconstructionConfig

    cfg = ReconstructionConfig(seed=args.seed, cache=not args.no_cache)
    if args.iterations is not None:
        cfg = replace(cfg, fit=replace(cfg.fit, iterations=args.iterations))
    if args.feature_iterations is not None:
        cfg = replace(cfg, features=replace(cfg.features, iterations=args.feature_iterations))
    return cfg


def _is_video(path: Path) -> bool:
    return path.is_dir() or path.suffix.lower() in VIDEO_SUFFIXES


def _reconstruct(args: argparse.Namespace) -> int:
    if _is_video(Path(args.clip)):
        return _reconstruct_video(args)
    from ..scene import load_clip, save_scene
    from .pipeline import reconstruct
    from .report import format_report, quality_report

    clip = load_clip(args.clip)
    cfg = _config(args)
    start = time.perf_counter()
    scene = reconstruct(clip, cfg)
    seconds = time.perf_counter() - start
    out = Path(args.out) if args.out else Path(args.clip).with_name("scene_fit.msim")
    save_scene(scene, out)
    print(f"wrote {out} ({len(scene.gaussians)} Gaussians, {seconds:.1f} s)")
    if args.report or args.json:
        report = quality_report(clip, scene, seconds=seconds)
        print(format_report(report))
        if args.json:
            Path(args.json).write_text(json.dumps(report, indent=2))
    return 0


def _reconstruct_video(args: argparse.Namespace) -> int:
    from .video import reconstruct_video

    if args.report or args.json:
        raise ValueError("Expected no --report/--json for a video (it has no ground truth to score against); "
                         "see benchmarks/video.py for held-out-frame PSNR")
    src = Path(args.clip)
    out = Path(args.out) if args.out else src.with_name(f"{src.stem or src.name}_scene")
    result = reconstruct_video(src, out, fov_deg=args.fov, prompt=args.prompt, max_frames=args.max_frames,
                               size=args.size, camera=args.camera, config=_config(args), layers=args.layers)
    clip, scene = result.clip, result.scene
    cam = clip.info["camera"]
    objects = ", ".join(f"{o.name}{' (moving)' if o.dynamic else ''}" for o in scene.objects)
    print(f"read {src}: {clip.num_frames} frames {clip.width}x{clip.height} @ {clip.fps:g} fps "
          f"(frames {clip.info['video']['window'][0]}-{clip.info['video']['window'][1] - 1} of "
          f"{clip.info['video']['source_frames']}, every {clip.info['video']['stride']}), camera {cam['motion']}")
    print(f"wrote {result.scene_path} ({len(scene.gaussians)} Gaussians; objects: {objects}; "
          f"{result.seconds:.1f} s), {result.preview_path}, {result.info_path}")
    print(f"open it: morphosim view {result.scene_path}")
    return 0
