"""`morphosim bench` (counterfactual robustness sweeps) and `morphosim quality` (scene-quality report)."""

from __future__ import annotations

import argparse
import sys

from ..extras import EXIT_MISSING_EXTRA, install_line, require_extra
from ..language.grounding_cli import add_grounding_flags, grounding_from_args
from ..policies import POLICY_SPEC_HELP

__all__ = ["register", "exit_code", "MAX_EXIT_FAILED", "EXIT_NOT_RUN"]

MAX_EXIT_FAILED = 250      # exit status = failed episodes, capped here (statuses wrap at 256)
EXIT_NOT_RUN = 255         # the sweep could not start or finish (bad suite file, unknown policy, ...)


def exit_code(failed: int) -> int:
    """The exit status of a sweep with `failed` failed episodes."""
    return min(int(failed), MAX_EXIT_FAILED)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the `bench` and `quality` subcommands."""
    p = sub.add_parser(
        "bench", help="run a counterfactual robustness suite on a policy",
        description="Run every episode of a suite (base and perturbed twins on the same scene, reset and policy "
                    "seeds) for each policy; write results.jsonl/json/csv, report.md and plots to --out. A rerun "
                    "with the same --out resumes where it stopped. Exit status: the number of failed episodes "
                    f"(capped at {MAX_EXIT_FAILED}); {EXIT_NOT_RUN} when the sweep cannot run at all (bad suite, "
                    "unknown policy); 2 for a command-line usage error; "
                    f"{EXIT_MISSING_EXTRA} when a package of the bench extra is missing ({install_line('bench')}).",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("suite", nargs="?", default=None,
                   help="a built-in suite name (see --list) or a suite YAML file")
    p.add_argument("--policy", action="append", default=None, metavar="SPEC",
                   help=f"{POLICY_SPEC_HELP} (repeatable; default: oracle)")
    p.add_argument("--backend", choices=["local", "ray"], default="local", help="where episodes run")
    p.add_argument("--workers", type=int, default=1,
                   help="worker processes (local: a process pool when > 1; ray: actors on the cluster)")
    p.add_argument("--out", default=None, help="output folder (default out/bench/SUITE)")
    p.add_argument("--episodes", type=int, default=None, help="override the suite's episode count")
    p.add_argument("--cache-dir", default=None,
                   help="scene cache shared by the workers (default $MORPHOSIM_CACHE or ~/.cache/morphosim_gym)")
    p.add_argument("--ray-address", default=None, help="join this Ray cluster instead of starting a local one")
    p.add_argument("--reconstruction", choices=["oracle", "fit"], default=None,
                   help="the worlds: the generator's ground truth, or scenes reconstructed from its clips (with a "
                        "feature field; edits select through it); default: the suite's 'world' (else oracle)")
    p.add_argument("--reconstruction-preset", choices=["fast", "full"], default=None,
                   help="reconstruction settings of fit worlds (morphosim_gym.reconstruct.presets); default: the "
                        "suite's, else full")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_grounding_flags(p)     # --grounding exact (old: --strict): a substituted prompt word fails its episodes
    p.add_argument("--list", action="store_true", help="list the built-in suites and exit")
    p.set_defaults(func=_bench)

    q = sub.add_parser(
        "quality", help="BRISQUE / NIQE (and CLIP, Q-Align when available) of generated scenes",
        description="Generate each prompt's scene, render it from the generation view and from novel views "
                    "(yaw orbits), and write the no-reference quality table in the paper's form.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    q.add_argument("prompts", nargs="+",
                   help="prompts, or a text file with one prompt per line ('#' comments), or 'paper' for the "
                        "paper's prompts")
    q.add_argument("--out", default="quality_report.md", help="the markdown report (a .json is written beside it)")
    q.add_argument("--size", type=int, default=384, help="rendered image width, pixels (at least 96: NIQE blocks)")
    q.add_argument("--yaws", default="-30,-15,15,30",
                   help="novel-view yaw offsets, degrees, comma-separated (--yaws=-30,30 when the first is negative)")
    q.add_argument("--times", type=int, default=3, help="time samples per clip")
    q.add_argument("--seed", type=int, default=0, help="generation seed")
    q.add_argument("--detail", type=float, default=1.0, help="Gaussian budget multiplier of generated scenes")
    q.add_argument("--reconstruction", choices=["oracle", "fit"], default="oracle",
                   help="score the generator's ground truth (default) or the scene reconstructed from its clip")
    q.add_argument("--clip-model", default=None,
                   help="local path of a CLIP model for text-image similarity (default $MORPHOSIM_CLIP_MODEL)")
    q.add_argument("--qalign-model", default=None,
                   help="local path of a Q-Align model (default $MORPHOSIM_QALIGN_MODEL)")
    q.add_argument("--trust-remote-code", action="store_true",
                   help="let the Q-Align model folder's own Python code run (Q-Align needs it; without this flag "
                        "such a folder is refused)")
    q.set_defaults(func=_quality)


def _bench(args: argparse.Namespace) -> int:
    from .suite import builtin_suite_names, load_suite

    if args.list:
        for name in builtin_suite_names():
            s = load_suite(name)
            print(f"{name:10s} {s.env_id:20s} {len(s.perturbations)} perturbations x {s.episodes} seeds  "
                  f"{' '.join(s.description.split())[:70]}")
        return 0
    if args.suite is None:
        raise ValueError("Expected a suite name or file (see morphosim bench --list), found none")
    if args.workers < 1:
        raise ValueError(f"Expected --workers >= 1, found {args.workers}")
    require_extra("bench", "matplotlib", needed_for="morphosim bench (the report's plots)")   # before any episode
    if args.backend == "ray":
        require_extra("bench", "ray", "psutil", needed_for="morphosim bench --backend ray")
    from .runner import run_sweep

    try:
        suite = load_suite(args.suite)
        if args.episodes is not None:
            suite = suite.with_episodes(args.episodes)
        if args.reconstruction is not None or args.reconstruction_preset is not None:
            suite = suite.with_world(reconstruction=args.reconstruction,
                                     reconstruction_config=args.reconstruction_preset)
        out = args.out or f"out/bench/{suite.name}"
        result = run_sweep(suite, args.policy or ["oracle"], out, backend=args.backend, workers=args.workers,
                           cache_dir=args.cache_dir, address=args.ray_address, progress=not args.no_progress,
                           grounding=grounding_from_args(args))
    except ValueError as exc:
        print(f"morphosim bench: error: {exc}", file=sys.stderr)
        return EXIT_NOT_RUN
    total = len(result.records)
    print(f"{suite.name}: {total} episodes ({result.ran} run, {result.resumed} resumed), {result.failed} failed, "
          f"{result.wall_s:.1f} s -> {result.out / 'report.md'}")
    return exit_code(result.failed)


def _quality(args: argparse.Namespace) -> int:
    require_extra("bench", "brisque", "libsvm", "skimage", needed_for="morphosim quality (BRISQUE)")
    from .quality import quality_main

    return quality_main(args)
