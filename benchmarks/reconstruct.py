#!/usr/bin/env python
"""Reconstruction quality and time on the generator's example prompts (issue #5 bars).

    python benchmarks/reconstruct.py [--prompts all|paper | --prompts-file F] [--size 128] [--frames 49] [--iterations 1200] [--json out.json]
                                     [--priors ground_truth|estimated|corrupted] [--only WORDS]...

--priors says where the fit's depth, masks and tracks come from (printed in every row):
ground_truth = the generator's renders of its own scene (an upper bound), estimated = from the
RGB frames alone (`morphosim_gym.priors.RGBPriorEstimators`), corrupted = ground truth with
realistic errors (`morphosim_gym.priors.corrupt_priors`: depth x smooth +-10% field + 1% noise,
masks +-1-2 px with 5% of frames dropped, tracks +1 px noise with 10% dropped). Quality is
always measured against the clip's ground truth.

For each prompt: generate the 49-frame clip, fit the 4D scene from the clip alone (never its
ground truth; any cached result is deleted first, so the time is a real fit; the fitted scene
is left in the cache for benchmarks/edit_quality.py), then measure input-view PSNR/SSIM,
novel-view PSNR/SSIM at yaw +-15 and +-30 degrees against renders of the clip's ground truth,
per-object instance IoU on input views and the feature field's semantic precision / recall
(`morphosim_gym.reconstruct.report`: each Gaussian's nearest name against the object it was fitted
for, so with estimated priors it is measured against estimated labels), and the selection a user
gets (`sel`): every object selected by its name as an edit does (`sim.editor.selector`), rendered
from the input cameras, pixel precision / recall against the clip's ground-truth masks
(`morphosim_gym.edit.select_quality`). Those masks follow the renderer's instance rule (the single
heaviest Gaussian), the selection a rule of shares (at least half a pixel's colour), so even the
generator's own scene with the object's exact Gaussians scores below 1 along small objects'
outlines: each object's `ceiling` says what that exact selection scores, and `sel½` scores the
selection against masks of its own rule drawn from the generator's scene (`share_masks`).
Prints one row per prompt and the bars.
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import morphosim_gym as ms
from _bars import bar_line, write_json
from morphosim_gym.edit.select_quality import selection_against_masks, share_masks
from morphosim_gym.generate.examples import EXAMPLE_PROMPTS, PAPER_SCENES
from morphosim_gym.priors import corrupt_priors
from morphosim_gym.reconstruct import ReconstructionConfig
from morphosim_gym.reconstruct.pipeline import cache_path
from morphosim_gym.reconstruct.report import quality_report

BARS = {"input_psnr": 30.0, "novel15_psnr": 24.0, "novel30_psnr": 21.0, "iou": 0.9, "selection_pr": 0.9,
        "selection_share_pr": 0.9, "seconds": 120.0}


PRIOR_CONFIG = {"ground_truth": "ground_truth", "estimated": "estimated", "corrupted": "ground_truth"}


def measure(sim: ms.MorphoSim, prompt: str, seed: int, priors: str = "ground_truth") -> dict:
    """Generate, reconstruct (timed) and report one prompt with the given prior source."""
    clip = sim.generate_clip(prompt, seed)
    fitted = corrupt_priors(clip, seed) if priors == "corrupted" else clip
    # a real fit every time; the result is left in the cache for benchmarks/edit_quality.py
    cache_path(fitted, sim.config.reconstruction_config).unlink(missing_ok=True)
    start = time.perf_counter()
    scene = sim.reconstruct(fitted)
    seconds = time.perf_counter() - start
    report = quality_report(clip, scene, seconds=seconds)     # always against the ground truth
    report["selection"] = selection_report(sim, clip, scene)
    report["prompt"] = prompt
    report["priors"] = priors
    log = getattr(scene, "_fit_log", None)          # set by a real fit (not by a cache hit)
    if log:
        fit_log = log["fit"]
        report["stage_seconds"] = {"fit": fit_log["seconds"],
                                   "completion": fit_log.get("completion", {}).get("seconds", 0.0),
                                   "polish": fit_log.get("complete", {}).get("seconds", 0.0),
                                   "features": log["features"]["seconds"]}
    return report


def selection_report(sim: ms.MorphoSim, clip: ms.GeneratedClip, scene: ms.Scene4D, frame_stride: int = 4) -> dict:
    """Per object: the editor's selection of its name, pixel precision / recall against the clip's
    ground-truth masks in the input views (every `frame_stride`-th frame), and the threshold chosen;
    "share": the same against the generator's share masks (`share_masks`), "ceiling": the
    generator's exact selection of the object (its own Gaussians) against the clip's masks."""
    frames = list(range(0, clip.num_frames, frame_stride))
    cams, times = [clip.cameras[i] for i in frames], [i / clip.fps for i in frames]
    truth_scene = clip.ground_truth
    out = {}
    for o in scene.objects:
        insts = [k for k, v in clip.labels.items() if v == o.name]
        if not insts:
            continue
        sim.editor.selector.clear()
        sel = sim.editor.selector.select(scene, [o.id], o.name)
        masks = np.isin(clip.masks[frames], insts)
        out[o.name] = {**selection_against_masks(scene, sel.mask, cams, times, masks),
                       "threshold": sel.threshold, "method": sel.method}
        if truth_scene is not None:
            exact = np.isin(truth_scene.gaussians.object_ids, insts)
            out[o.name]["share"] = selection_against_masks(scene, sel.mask, cams, times,
                                                           share_masks(truth_scene, insts, cams, times))
            out[o.name]["ceiling"] = selection_against_masks(truth_scene, exact, cams, times, masks)
    return out


def row(r: dict) -> dict:
    """The numbers the bars look at."""
    n = r["novel"]
    return {"input_psnr": r["input"]["psnr"], "novel15_psnr": min(n["-15"]["psnr"], n["+15"]["psnr"]),
            "novel30_psnr": min(n["-30"]["psnr"], n["+30"]["psnr"]), "iou": min(r["instance_iou"].values()),
            "seconds": r["seconds"],
            "semantic_pr": min((min(v["precision"], v["recall"]) for v in r.get("semantic", {}).values()),
                               default=0.0),
            "selection_pr": min((min(v["precision"], v["recall"]) for v in r.get("selection", {}).values()),
                                default=0.0),
            "selection_share_pr": min((min(v["share"]["precision"], v["share"]["recall"])
                                       for v in r.get("selection", {}).values() if "share" in v), default=0.0)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--prompts", choices=("all", "paper"), default="all")
    ap.add_argument("--prompts-file", type=Path, default=None,
                    help="prompts to run instead, one per line (# comments), e.g. "
                         "benchmarks/reconstruct_heldout_prompts.txt")
    ap.add_argument("--only", action="append", default=None, metavar="WORDS",
                    help="keep only the prompts containing these words (repeatable)")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--frames", type=int, default=49, help="frames per clip")
    ap.add_argument("--iterations", type=int, default=None,
                    help="fit iterations (default the ReconstructionConfig's 1200; the completion polish and the "
                         "feature field get a sixth of it each)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--json-each", type=Path, default=None, help="also rewrite this JSON after every prompt")
    ap.add_argument("--priors", choices=tuple(PRIOR_CONFIG), default="ground_truth",
                    help="where the fit's depth, masks and tracks come from")
    ap.add_argument("--cache-dir", default=None, help="where fitted scenes are left (default: the package cache)")
    args = ap.parse_args()
    prompts = EXAMPLE_PROMPTS if args.prompts == "all" else tuple(p for p, _ in PAPER_SCENES)
    if args.prompts_file:
        lines = (ln.strip() for ln in args.prompts_file.read_text().splitlines())
        prompts = tuple(ln for ln in lines if ln and not ln.startswith("#"))
    if args.only:
        prompts = tuple(p for p in prompts if any(w.lower() in p.lower() for w in args.only))
    config = ReconstructionConfig(progress=False, cache_dir=args.cache_dir, priors=PRIOR_CONFIG[args.priors])
    if args.iterations:
        n = max(1, args.iterations)
        config = replace(config, fit=replace(config.fit, iterations=n), complete_iterations=max(1, n // 6),
                         features=replace(config.features, iterations=max(1, n // 6)))
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=args.size, height=args.size, num_frames=args.frames),
                       reconstruction_config=config)
    reports = []
    print(f"{'prompt':58s} {'priors':>12s} {'input':>6s} {'+-15':>6s} {'+-30':>6s} {'IoU':>5s} {'sem':>5s} {'sel':>5s} "
          f"{'sel½':>5s} {'time':>6s}  load")
    for prompt in prompts:
        r = measure(sim, prompt, args.seed, args.priors)
        r["load"] = os.getloadavg()[0]
        reports.append(r)
        x = row(r)
        print(f"{prompt[:58]:58s} {args.priors:>12s} {x['input_psnr']:6.2f} {x['novel15_psnr']:6.2f} {x['novel30_psnr']:6.2f} "
              f"{x['iou']:5.3f} {x['semantic_pr']:5.3f} {x['selection_pr']:5.3f} {x['selection_share_pr']:5.3f} "
              f"{x['seconds']:5.1f}s  {r['load']:.1f}", flush=True)
        if args.json_each:          # after every prompt, so an interrupted run keeps what it measured
            write_json(args.json_each, {"size": args.size, "frames": args.frames, "iterations": args.iterations or 1200,
                                        "seed": args.seed, "priors": args.priors, "reports": reports})
    rows = [row(r) for r in reports]
    print("\nbars (worst prompt):")
    for key, bar in BARS.items():
        vals = [x[key] for x in rows]
        worst = max(vals) if key == "seconds" else min(vals)
        print(bar_line(key, bar, worst, higher_is_better=key != "seconds", median=float(np.median(vals))))
    write_json(args.json, {"size": args.size, "frames": args.frames, "iterations": args.iterations or 1200, "seed": args.seed, "priors": args.priors, "reports": reports})


if __name__ == "__main__":
    main()
