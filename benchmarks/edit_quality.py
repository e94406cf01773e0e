#!/usr/bin/env python
"""Edit quality on reconstructed scenes of the paper's prompts (issue #6 bars).

    python benchmarks/reconstruct.py        # fits the scenes (left in the reconstruction cache)
    python benchmarks/edit_quality.py [--size 128] [--json out.json]

For each paper scene, reconstructed from its generated clip (loaded from the cache when
benchmarks/reconstruct.py already fitted it with the same settings), measures:
    selection   precision / recall of the selector's Gaussians for every object, queried by its
                name, against the object each Gaussian was reconstructed for;
    recolor     "make the <object> <colour>": mean ΔE (CIE76) of the target's rendered colour to
                the asked colour, and PSNR outside the target's mask dilated by 2 px against the
                unedited render, in the generation view and two novel views at three times;
    remove      the target's id absent from the instance map (every frame, generation view);
    extract     only the target's id left;
    reverse     mean distance between the reversed centroid path and the original path
                traversed backwards, as a fraction of the image width (dynamic targets);
    paper edit  the edit of the paper's caption applied without error.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

import morphosim_gym as ms
from _bars import bar_line, write_json
from morphosim_gym.generate.examples import PAPER_SCENES
from morphosim_gym.metrics import delta_e, mean_lab, psnr, rgb_to_lab
from morphosim_gym.reconstruct import ReconstructionConfig

BARS = {"precision": 0.95, "recall": 0.95, "delta_e": 15.0, "outside_psnr": 45.0, "reverse_error": 0.02}


def views(scene: ms.Scene4D, t: float) -> list[ms.Camera]:
    """The generation camera at time t and two novel views around the scene centre."""
    cam = scene.camera_at(t)
    centre = scene.centre(t)
    return [cam, cam.orbit(20.0, centre), cam.orbit(-30.0, centre)]


def selection_scores(sim: ms.MorphoSim, scene: ms.Scene4D) -> dict[str, dict[str, float]]:
    """Precision / recall of the selection of each object by its name."""
    out = {}
    for obj in scene.objects:
        sim.editor.selector.clear()
        sel = sim.editor.selector.select(scene, [obj.id], obj.name)
        truth = scene.gaussians.object_ids == obj.id
        tp = float((sel.mask & truth).sum())
        out[obj.name] = {"precision": tp / max(float(sel.mask.sum()), 1.0), "recall": tp / max(float(truth.sum()), 1.0),
                         "method": sel.method}
    return out


def recolor_scores(sim: ms.MorphoSim, scene: ms.Scene4D, name: str, colour: str) -> dict[str, float]:
    """Worst ΔE to the asked colour and worst PSNR outside the target over views and times."""
    text = f"make the {name} {colour}"
    edited = sim.edit(scene, text)
    target = rgb_to_lab(np.array(ms.parse(text).edits[0].color.rgb))
    oid = scene.object(name).id
    des, outs = [], []
    for t in (0.0, scene.duration / 2, scene.duration):
        for cam in views(scene, t):
            before, after = ms.render(scene, cam, t), ms.render(edited, cam, t)
            mask = before.instance == oid
            if mask.sum() < 20:
                continue
            # the target's colour where the target covers the pixel (its inner part)
            inner = cv2.erode(mask.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
            des.append(delta_e(mean_lab(after.rgb, inner if inner.sum() >= 10 else mask), target))
            outside = ~cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
            outs.append(psnr(before.rgb, after.rgb, outside))
    return {"delta_e": float(max(des)), "outside_psnr": float(min(outs)), "views": len(des)}


def centroids(scene: ms.Scene4D, oid: int) -> np.ndarray:
    """Image centroid of an object in every frame, from the generation camera at t = 0 (held
    still, so that a moving generation camera does not add its own motion to the path)."""
    out = []
    for i in range(scene.num_frames):
        t = i / scene.fps
        ys, xs = np.nonzero(ms.render(scene, scene.camera_at(0.0), t).instance == oid)
        out.append([xs.mean(), ys.mean()] if len(xs) else [np.nan, np.nan])
    return np.array(out)


def structural_scores(sim: ms.MorphoSim, scene: ms.Scene4D, name: str) -> dict[str, float | bool]:
    """Remove, extract and (for a moving target) reverse."""
    oid = scene.object(name).id
    times = [i / scene.fps for i in range(0, scene.num_frames, 6)]
    gone = sim.edit(scene, f"delete the {name}")
    only = sim.edit(scene, f"extract the {name}")
    out: dict[str, float | bool] = {
        "removed": all(not np.any(ms.render(gone, gone.camera_at(t), t).instance == oid) for t in times),
        "extracted": all(set(np.unique(ms.render(only, only.camera_at(t), t).instance).tolist()) <= {-1, oid}
                         for t in times),
    }
    if scene.object(name).dynamic:
        rev = sim.edit(scene, f"reverse the motion of the {name}")
        a, b = centroids(scene, oid), centroids(rev, oid)
        ok = ~np.isnan(a[::-1, 0]) & ~np.isnan(b[:, 0])
        out["reverse_error"] = float(np.linalg.norm(a[::-1] - b, axis=1)[ok].mean() / scene.camera.width)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cache-dir", default=None, help="the reconstruction cache (as given to benchmarks/reconstruct.py)")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=args.size, height=args.size),
                       reconstruction_config=ReconstructionConfig(progress=False, cache_dir=args.cache_dir))
    results = []
    for prompt, paper_edit in PAPER_SCENES:
        scene = sim.reconstruct(sim.generate_clip(prompt, args.seed))
        name = ms.parse(prompt).objects[0].name
        colour = "yellow" if "blue" in prompt.lower() or name == "cube" else "blue"
        r = {"prompt": prompt, "target": name, "selection": selection_scores(sim, scene),
             "recolor": recolor_scores(sim, scene, name, colour), **structural_scores(sim, scene, name)}
        sim.edit(scene, paper_edit)
        r["paper_edit"] = paper_edit
        results.append(r)
        sel = r["selection"]
        p = min(v["precision"] for v in sel.values())
        rc = min(v["recall"] for v in sel.values())
        rev = f"{r['reverse_error']:.4f}" if "reverse_error" in r else "   -  "
        print(f"{prompt[:52]:52s} sel P {p:.3f} R {rc:.3f}  ΔE {r['recolor']['delta_e']:5.1f}  "
              f"out {r['recolor']['outside_psnr']:5.1f} dB  removed {r['removed']}  extracted {r['extracted']}  "
              f"reverse {rev}", flush=True)
    print("\nbars (worst scene):")
    worst = {
        "precision": min(v["precision"] for r in results for v in r["selection"].values()),
        "recall": min(v["recall"] for r in results for v in r["selection"].values()),
        "delta_e": max(r["recolor"]["delta_e"] for r in results),
        "outside_psnr": min(r["recolor"]["outside_psnr"] for r in results),
        "reverse_error": max(r.get("reverse_error", 0.0) for r in results),
    }
    for key, bar in BARS.items():
        print(bar_line(key, bar, worst[key], higher_is_better=key not in ("delta_e", "reverse_error")))
    print(f"  {'MET ' if all(r['removed'] and r['extracted'] for r in results) else 'MISS'} remove / extract")
    write_json(args.json, {"size": args.size, "seed": args.seed, "results": results})


if __name__ == "__main__":
    main()
