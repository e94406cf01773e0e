"""Check generated clips against their plans: colours, presence, directions, speeds.

    python -m morphosim_gym.generate.evaluate tests/language/corpus.jsonl [--size 128 --frames 49] [--json out.json]

For every generate command of a corpus (JSON lines with a "text" field; edit commands are
skipped) the clip is generated and, per object instance the plan names:
    * present: its instance mask covers >= 8 pixels in at least half of the frames;
    * colour (when asked): mean Lab colour over its mask pixels within Delta-E 15 of the asked RGB;
    * direction (straight / bounce / zigzag motions with a direction): cosine > 0.9 between the
      asked image direction and the measured displacement of its mask centroid (first to last
      frame; out-and-back motions use the first half); motions along the view axis must grow
      (towards the camera) or shrink (away) on screen instead; motions to a landmark must end
      nearer to it (at most half the starting distance, on the ground plane). With a moving camera the centroid is measured by projecting the object's
      centre through the first frame's camera (the generation view).
The speed check generates the same motion "slowly" and "quickly" for several categories and
requires the quick one to travel at least 1.5x farther on screen.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..metrics import delta_e, mean_lab, rgb_to_lab
from ..scene import GeneratedClip

__all__ = ["ObjectCheck", "check_clip", "evaluate", "speed_ratios", "main"]

DELTA_E_MAX = 15.0
COSINE_MIN = 0.9
SPEED_RATIO_MIN = 1.5


@dataclass
class ObjectCheck:
    """Measurements of one object of one clip."""

    text: str
    object: str
    present: bool
    delta_e: float | None = None
    cosine: float | None = None
    depth_ok: bool | None = None
    landmark_ok: bool | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        ok = self.present
        if self.delta_e is not None:
            ok &= self.delta_e < DELTA_E_MAX
        if self.cosine is not None:
            ok &= self.cosine > COSINE_MIN
        for flag in (self.depth_ok, self.landmark_ok):
            if flag is not None:
                ok &= flag
        return bool(ok)


def _centroids(clip: GeneratedClip, obj_id: int, moving_camera: bool) -> np.ndarray:
    """[T, 2] image centroid per frame (NaN where invisible), in the first camera's view."""
    T = clip.num_frames
    out = np.full((T, 2), np.nan)
    gt = clip.ground_truth
    for i in range(T):
        m = clip.masks[i] == obj_id
        if m.sum() < 3:
            continue
        if moving_camera and gt is not None:
            out[i] = clip.cameras[0].project(gt.object_center(obj_id, i / clip.fps))[0]
        else:
            ys, xs = np.nonzero(m)
            out[i] = [xs.mean(), ys.mean()]
    return out


def check_clip(plan: Any, clip: GeneratedClip) -> list[ObjectCheck]:
    """Check one clip against its generate plan (one `ObjectCheck` per object instance)."""
    scene = clip.ground_truth
    moving_camera = len({c.world_to_camera.tobytes() for c in clip.cameras}) > 1
    motions = {m.target: m for m in plan.motions}
    results = []
    for spec in plan.objects:
        names = [spec.name] if spec.count == 1 else [f"{spec.name} {k + 1}" for k in range(spec.count)]
        for name in names:
            obj = scene.object(name)
            masks = clip.masks == obj.id
            area = masks.reshape(clip.num_frames, -1).sum(axis=1)
            res = ObjectCheck(plan.text, name, bool((area >= 8).mean() >= 0.5))
            if spec.color is not None and masks.any():
                res.delta_e = delta_e(mean_lab(clip.frames[masks.any(axis=(1, 2))], masks[masks.any(axis=(1, 2))]),
                                      rgb_to_lab(np.asarray(spec.color.rgb)))
            m = motions.get(spec.name)
            if m is not None and m.path != "stop":
                c = _centroids(clip, obj.id, moving_camera)
                ok = np.flatnonzero(~np.isnan(c[:, 0]))
                if len(ok) >= 2:
                    first, last = ok[0], ok[-1]
                    if m.path == "oscillate":
                        last = ok[len(ok) // 2]
                    disp = c[last] - c[first]
                    if m.end is not None:
                        # ends nearer the landmark, measured on the ground plane (so "onto" counts)
                        goal = scene.object(m.end).id
                        d0 = np.linalg.norm((scene.object_center(obj.id, 0.0) - scene.object_center(goal, 0.0))[:2])
                        d1 = np.linalg.norm((scene.object_center(obj.id, scene.duration)
                                             - scene.object_center(goal, scene.duration))[:2])
                        res.landmark_ok = bool(d1 < 0.5 * d0)
                    elif m.direction_world is not None and m.path in ("straight", "bounce", "zigzag", "oscillate"):
                        want = np.asarray(m.direction_image, dtype=np.float64)
                        if np.linalg.norm(want) > 0.5 and abs(m.direction_depth) < 0.8:
                            res.cosine = float(disp @ want / max(np.linalg.norm(disp) * np.linalg.norm(want), 1e-9))
                        elif abs(m.direction_depth) > 0.5:
                            grow = area[ok[-1]] > area[ok[0]]
                            res.depth_ok = bool(grow if m.direction_depth < 0 else not grow)
                else:
                    res.notes.append("not visible long enough to measure motion")
            results.append(res)
    return results


SPEED_SUBJECTS = ("car", "ball", "dog", "bus", "sheep", "cube", "horse", "duck")


def speed_ratios(sim: Any, seed: int = 0, subjects: Sequence[str] = SPEED_SUBJECTS) -> dict[str, float]:
    """On-screen travel of "a X moves quickly from left to right" over "... slowly ...", per subject."""
    out = {}
    for s in subjects:
        travel = []
        for adverb in ("slowly", "quickly"):
            clip = sim.generate_clip(f"a {s} moves {adverb} from left to right", seed=seed)
            oid = clip.ground_truth.object(s).id
            c = _centroids(clip, oid, False)
            ok = np.flatnonzero(~np.isnan(c[:, 0]))
            travel.append(float(np.linalg.norm(c[ok[-1]] - c[ok[0]])) if len(ok) >= 2 else 0.0)
        out[s] = travel[1] / max(travel[0], 1e-9)
    return out


def evaluate(texts: Sequence[str], sim: Any, seed: int = 0) -> dict:
    """Generate and check every generate command; a summary with per-check pass rates."""
    from ..language import parse

    checks: list[ObjectCheck] = []
    skipped, errors, seconds = 0, [], []
    for text in texts:
        try:
            plan = parse(text)
        except ValueError:
            skipped += 1
            continue
        if plan.mode != "generate" or not plan.objects:
            skipped += 1
            continue
        start = time.perf_counter()
        try:
            clip = sim.generate_clip(text, seed=seed)
        except ValueError as exc:
            errors.append({"text": text, "error": str(exc)})
            continue
        seconds.append(time.perf_counter() - start)
        checks.extend(check_clip(plan, clip))

    def rate(vals: list[bool]) -> dict:
        return {"passed": int(sum(vals)), "total": len(vals), "rate": float(np.mean(vals)) if vals else None}

    ratios = speed_ratios(sim, seed)
    return {
        "objects": rate([c.passed for c in checks]),
        "present": rate([c.present for c in checks]),
        "color": rate([c.delta_e < DELTA_E_MAX for c in checks if c.delta_e is not None]),
        "direction": rate([c.cosine > COSINE_MIN for c in checks if c.cosine is not None]),
        "depth": rate([c.depth_ok for c in checks if c.depth_ok is not None]),
        "landmark": rate([c.landmark_ok for c in checks if c.landmark_ok is not None]),
        "speed_ratios": ratios,
        "speed": rate([r >= SPEED_RATIO_MIN for r in ratios.values()]),
        "delta_e_max": max((c.delta_e for c in checks if c.delta_e is not None), default=None),
        "cosine_min": min((c.cosine for c in checks if c.cosine is not None), default=None),
        "clip_seconds_median": float(np.median(seconds)) if seconds else None,
        "skipped": skipped, "errors": errors,
        "failures": [c.__dict__ | {"passed": False} for c in checks if not c.passed],
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry: evaluate a corpus and print a table (and JSON with --json)."""
    from ..pipeline import MorphoSim
    from .compose import GenerationConfig

    ap = argparse.ArgumentParser(prog="python -m morphosim_gym.generate.evaluate", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("corpus")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--frames", type=int, default=49)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    texts = []
    for line in Path(args.corpus).read_text().splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            texts.append(json.loads(line)["text"])
    sim = MorphoSim(generation=GenerationConfig(width=args.size, height=args.size, num_frames=args.frames))
    report = evaluate(sorted(set(texts)), sim, args.seed)
    for k in ("objects", "present", "color", "direction", "depth", "landmark", "speed"):
        r = report[k]
        print(f"{k:10s} {r['passed']:4d}/{r['total']:<4d} {100 * (r['rate'] or 0):6.1f}%")
    print(f"max Delta-E {report['delta_e_max']:.2f}  min cosine {report['cosine_min']:.3f}  "
          f"median clip {report['clip_seconds_median']:.2f} s  skipped {report['skipped']}  errors {len(report['errors'])}")
    print("speed ratios (quickly / slowly):", {k: round(v, 2) for k, v in report["speed_ratios"].items()})
    for f in report["failures"][:20]:
        print("FAIL", json.dumps(f))
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
