"""`morphosim info` and `morphosim export-ply`: look into scene files."""

from __future__ import annotations

import argparse
import json

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the scene-file subcommands."""
    p = sub.add_parser("info", help="describe a scene (.msim) or clip (.mclip) file")
    p.add_argument("path")
    p.set_defaults(func=_info)
    p = sub.add_parser("export-ply", help="write one frame of a scene as a standard 3DGS .ply")
    p.add_argument("scene")
    p.add_argument("--t", type=float, default=0.0, help="time in seconds (default 0)")
    p.add_argument("--out", required=True, help="output .ply path")
    p.set_defaults(func=_export)


def _scene_summary(path: str) -> dict:
    from .io import load_scene

    scene = load_scene(path)
    return {"kind": "scene", "gaussians": len(scene.gaussians), "frames": scene.num_frames, "fps": scene.fps,
            "duration_s": scene.duration, "objects": [o.to_dict() for o in scene.objects],
            "feature_dim": scene.gaussians.feature_dim, "decoders": sorted(scene.decoders),
            "provenance": scene.provenance.to_dict(), "content_hash": scene.content_hash()}


def _clip_summary(path: str) -> dict:
    from .io import load_clip

    clip = load_clip(path)
    return {"kind": "clip", "frames": clip.num_frames, "size": [clip.width, clip.height], "fps": clip.fps,
            "prompt": clip.prompt, "labels": clip.labels,
            "priors": [n for n in ("depth", "masks", "tracks") if getattr(clip, n) is not None],
            "has_ground_truth": clip.ground_truth is not None}


_SUMMARIES = {"scene": _scene_summary, "clip": _clip_summary}


def _info(args: argparse.Namespace) -> int:
    """Print a file's summary; a damaged file is a `SceneFileError` (the caller prints it, exit 2)."""
    from .io import SceneFileError, peek_kind

    kind = peek_kind(args.path)
    if kind not in _SUMMARIES:
        raise SceneFileError(f"{args.path}: holds a {kind!r}, expected one of {sorted(_SUMMARIES)}")
    print(json.dumps(_SUMMARIES[kind](args.path), indent=2))
    return 0


def _export(args: argparse.Namespace) -> int:
    from .io import export_ply, load_scene

    path = export_ply(load_scene(args.scene), args.out, t=args.t)
    print(path)
    return 0
