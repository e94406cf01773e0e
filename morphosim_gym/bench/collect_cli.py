"""`morphosim collect`: expert (or any policy's) episodes of a suite or a task as a LeRobot dataset."""

from __future__ import annotations

import argparse
import sys

from ..extras import require_extra
from ..policies import POLICY_SPEC_HELP
from .cli import EXIT_NOT_RUN, exit_code
from .dataset.video import VCODECS

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `collect` subcommand."""
    p = sub.add_parser(
        "collect", help="record a policy's episodes (base and counterfactual) as a LeRobot v3.0 dataset",
        description="Run every episode of a suite (base and perturbed twins), or of a task, with each policy (the "
                    "scripted oracle is the expert) and write a LeRobot v3.0 dataset to --out: meta/info.json, "
                    "meta/stats.json, meta/tasks.parquet, meta/episodes/, data/ and one mp4 per camera per chunk "
                    "file in videos/. A rerun with the same --out resumes where it stopped. Exit status: the number "
                    "of failed episodes (not written; capped at 250); 255 when the run cannot start.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    src = p.add_mutually_exclusive_group()
    src.add_argument("suite", nargs="?", default=None, help="a built-in suite name or a suite YAML file")
    src.add_argument("--task", default=None, help="a task name or task YAML file instead of a suite (base episodes)")
    p.add_argument("--policy", action="append", default=None, metavar="SPEC",
                   help=f"{POLICY_SPEC_HELP} (repeatable; default: oracle)")
    p.add_argument("--out", default=None, help="dataset folder (default out/data/SUITE_or_TASK)")
    p.add_argument("--episodes", type=int, default=None, help="seeds per condition (default: the suite's; task: 10)")
    p.add_argument("--seed", type=int, default=0, help="first seed (with --task)")
    p.add_argument("--width", type=int, default=None, help="image width (with --task; default 84)")
    p.add_argument("--height", type=int, default=None, help="image height (with --task; default 84)")
    p.add_argument("--backend", choices=["local", "ray"], default="local", help="where episodes run")
    p.add_argument("--workers", type=int, default=1, help="worker processes or Ray actors")
    p.add_argument("--vcodec", choices=list(VCODECS), default="libsvtav1", help="video codec (LeRobot's default AV1)")
    p.add_argument("--crf", type=int, default=30, help="video quality (lower is better)")
    p.add_argument("--gop", type=int, default=2, help="keyframe interval, frames")
    p.add_argument("--cache-dir", default=None, help="scene cache shared by the workers")
    p.add_argument("--ray-address", default=None, help="join this Ray cluster instead of starting a local one")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_collect)


def _suite(args: argparse.Namespace):
    from .collect import task_suite
    from .suite import load_suite

    if args.task is not None:
        kw = {k: v for k, v in (("width", args.width), ("height", args.height)) if v is not None}
        return task_suite(args.task, args.episodes or 10, args.seed, kw)
    if args.suite is None:
        raise ValueError("Expected a suite name or file, or --task, found neither")
    if args.width is not None or args.height is not None:
        raise ValueError("Expected --width/--height only with --task (a suite sets its env_kwargs)")
    suite = load_suite(args.suite)
    return suite.with_episodes(args.episodes) if args.episodes is not None else suite


def _collect(args: argparse.Namespace) -> int:
    from .collect import run_collect
    from .dataset import VideoSettings

    if args.workers < 1:
        raise ValueError(f"Expected --workers >= 1, found {args.workers}")
    if args.backend == "ray":                                        # before the dataset folder is made
        require_extra("bench", "ray", "psutil", needed_for="morphosim collect --backend ray")
    try:
        suite = _suite(args)
        video = VideoSettings(vcodec=args.vcodec, crf=args.crf, g=args.gop)
        out = args.out or f"out/data/{suite.name}"
        result = run_collect(suite, args.policy or ["oracle"], out, backend=args.backend, workers=args.workers,
                             cache_dir=args.cache_dir, address=args.ray_address, progress=not args.no_progress,
                             video=video)
    except ValueError as exc:
        print(f"morphosim collect: error: {exc}", file=sys.stderr)
        return EXIT_NOT_RUN
    print(f"{suite.name}: {result.episodes} episodes, {result.frames} frames ({result.ran} run, {result.resumed} "
          f"resumed, {result.failed} failed), {result.wall_s:.1f} s -> {result.out}")
    return exit_code(result.failed)
