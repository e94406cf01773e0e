#!/usr/bin/env python
"""Instance masks estimated from RGB against the generator's own masks (issue #18), per object.

    python benchmarks/prior_masks.py [--size 128] [--frames 49] [--prompts-file F] [--json out.json]
                                     [--compare colour_refine]

For each prompt: generate the clip, estimate its masks from the frames alone
(`prepare_priors(clip, "estimated")`: `RGBPriorEstimators`), and score each planned object's
estimated mask against the generator's mask of the same name (IoU, mean over the frames where the
object shows at least 4 pixels). Seconds to run, not minutes: the quick check before a full
`benchmarks/reconstruct.py --priors estimated` run, whose instance IoU follows these masks.
`--compare STAGE` also scores the masks with that stage of `RGBPriorEstimators` switched off
(`colour_refine`, `skyline`, `rims`, `motion_split`, `sibling_shapes`).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import morphosim_gym as ms
from _bars import write_json
from morphosim_gym.generate.examples import EXAMPLE_PROMPTS
from morphosim_gym.metrics import iou
from morphosim_gym.priors import default_estimators, prepare_priors


def mask_ious(clip: ms.GeneratedClip, est: ms.GeneratedClip) -> dict[str, float]:
    """Per object name: mean IoU of the estimated mask against the generator's."""
    by_name: dict[str, list[int]] = {}
    for k, name in est.labels.items():
        by_name.setdefault(name, []).append(k)
    out = {}
    for inst, name in clip.labels.items():
        vals = [iou(np.isin(est.masks[i], by_name.get(name, [])), clip.masks[i] == inst)
                for i in range(clip.num_frames) if (clip.masks[i] == inst).sum() >= 4]
        if vals:
            out[name] = float(np.mean(vals))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--frames", type=int, default=49)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--prompts-file", type=Path, default=None)
    ap.add_argument("--compare", choices=("colour_refine", "skyline", "rims", "motion_split", "sibling_shapes"), default=None,
                    help="also score the estimators with this stage switched off")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    prompts = EXAMPLE_PROMPTS
    if args.prompts_file:
        lines = (ln.strip() for ln in args.prompts_file.read_text().splitlines())
        prompts = tuple(ln for ln in lines if ln and not ln.startswith("#"))
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=args.size, height=args.size, num_frames=args.frames))
    variants = {"default": {}}
    if args.compare:
        variants[f"no {args.compare}"] = {args.compare: False}
    rows = []
    print(f"{'prompt':44s} {'object':12s} " + " ".join(f"{v:>16s}" for v in variants))
    for prompt in prompts:
        clip = sim.generate_clip(prompt, args.seed)
        scores, seconds = {}, {}
        for name, overrides in variants.items():
            start = time.perf_counter()
            est = prepare_priors(clip, "estimated", estimators=default_estimators(clip, **overrides))
            seconds[name] = time.perf_counter() - start
            scores[name] = mask_ious(clip, est)
        for obj in scores["default"]:
            print(f"{prompt[:44]:44s} {obj[:12]:12s} " + " ".join(f"{scores[v].get(obj, 0.0):16.3f}" for v in variants))
            rows.append({"prompt": prompt, "object": obj, **{v: scores[v].get(obj, 0.0) for v in variants},
                         "estimate_seconds": seconds})
    for v in variants:
        vals = [r[v] for r in rows]
        print(f"{v:>20s}: mean IoU {np.mean(vals):.3f}, worst {np.min(vals):.3f} over {len(vals)} objects")
    write_json(args.json, {"size": args.size, "frames": args.frames, "seed": args.seed, "rows": rows})


if __name__ == "__main__":
    main()
