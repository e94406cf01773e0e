"""`morphosim reconstruct CLIP [--report] [--out SCENE]`: fit a 4D scene to a clip file."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the reconstruction subcommand."""
    p = sub.add_parser("reconstruct", help="fit dynamic Gaussians with a feature field to a clip (.mclip)")
    p.add_argument("clip", help="a clip file written by `morphosim generate` (clip.mclip)")
    p.add_argument("--out", default=None, help="where to write the scene (default: next to the clip, scene_fit.msim)")
    p.add_argument("--report", action="store_true", help="print PSNR/SSIM on input and novel views, IoU, time")
    p.add_argument("--json", default=None, help="also write the report as JSON here")
    p.add_argument("--iterations", type=int, default=None, help="fit iterations (default: the config's)")
    p.add_argument("--feature-iterations", type=int, default=None, help="feature-field iterations (default: the config's)")
    p.add_argument("--no-cache", action="store_true", help="fit again even if a cached result exists")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=_reconstruct)


def _reconstruct(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from ..scene import load_clip, save_scene
    from .pipeline import ReconstructionConfig, reconstruct
    from .report import format_report, quality_report

    clip = load_clip(args.clip)
    cfg = ReconstructionConfig(seed=args.seed, cache=not args.no_cache)
    if args.iterations is not None:
        cfg = replace(cfg, fit=replace(cfg.fit, iterations=args.iterations))
    if args.feature_iterations is not None:
        cfg = replace(cfg, features=replace(cfg.features, iterations=args.feature_iterations))
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
