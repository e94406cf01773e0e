"""Real, open-vocabulary worlds: asset coverage of the 40 categories, how the 300-noun list
resolves, generation time of 49-frame clips with real assets, Gaussians per scene, and PNGs.

    .venv/bin/python benchmarks/realworld.py [--out benchmarks/results/realworld.txt] [--png /tmp/realworld]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

NOUNS = Path(__file__).resolve().parents[1] / "tests" / "language" / "nouns_300.txt"
PROMPTS = ("a red chair moves to the right", "a teapot on the table", "a dog runs to the left on the grass",
           "a car drives along the road", "a fire hydrant and a bench")


def _resolve(noun: str) -> str:
    from morphosim_gym.errors import CommandError
    from morphosim_gym.language import parse
    try:
        plan = parse(f"a {noun}")
        if not plan.objects:
            return f"setting {plan.setting}"
        o = plan.objects[0]
    except CommandError as exc:
        return f"ERROR {str(exc)[-90:]}"
    except Exception as exc:  # noqa: BLE001 - the table records any failure
        return f"FAIL {type(exc).__name__}: {exc}"[:120]
    sim = "" if o.similarity is None else f" {o.similarity:.2f}"
    return f"{o.category} [{o.grounding}{sim}]"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="benchmarks/results/realworld.txt")
    ap.add_argument("--png", default="/tmp/realworld")
    args = ap.parse_args()
    os.environ.pop("MORPHOSIM_ASSET_SOURCES", None)
    import imageio

    from morphosim_gym.generate.assets import CATEGORY_SPECS
    from morphosim_gym.generate.compose import GenerationConfig
    from morphosim_gym.generate.procedural import ProceduralBackend
    from morphosim_gym.generate.real_assets import asset_candidates
    from morphosim_gym.language import parse

    lines = []
    covered = {c: len(asset_candidates(c)) for c in sorted(CATEGORY_SPECS)}
    lines.append(f"categories with a real asset: {sum(1 for n in covered.values() if n)} / {len(covered)}")
    lines.append("  " + ", ".join(f"{c} {n}" for c, n in covered.items()))
    nouns = [n.strip() for n in NOUNS.read_text().splitlines() if n.strip() and not n.startswith("#")]
    table = [(n, _resolve(n)) for n in nouns]
    bad = sum(1 for _, r in table if r.startswith(("ERROR", "FAIL")))
    lines.append(f"nouns: {len(nouns)}, resolved {len(nouns) - bad}, errors {bad}")
    lines.extend(f"  {n:22s} -> {r}" for n, r in table)
    rng = np.random.default_rng(0)
    sample = sorted(rng.choice(len(nouns), 40, replace=False).tolist())
    lines.append("random sample of 40 (rng 0): " + ", ".join(nouns[i] for i in sample))
    backend = ProceduralBackend(GenerationConfig(num_frames=49, width=128, height=128))
    Path(args.png).mkdir(parents=True, exist_ok=True)
    lines.append("generation, 49 frames at 128 px, assets auto, conversions cached (median of 3; machine loaded):")
    for k, prompt in enumerate(PROMPTS):
        plan = parse(prompt)
        backend.generate(plan, 0, prompt)          # warm the conversion cache
        times = []
        for _ in range(3):
            t = time.perf_counter()
            clip = backend.generate(plan, 0, prompt)
            times.append(time.perf_counter() - t)
        scene = clip.ground_truth
        imageio.imwrite(Path(args.png) / f"scene{k}.png", clip.frames[0])
        objs = ", ".join(f"{o.name}={o.asset or 'procedural'}" for o in scene.objects if o.role != "background")
        lines.append(f"  {statistics.median(times):6.2f} s  {len(scene.gaussians):6d} Gaussians  sky "
                     f"{'yes' if scene.sky is not None else 'no '}  {prompt!r}: {objs}")
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
