#!/usr/bin/env python
"""Resolve a seeded random sample of the 300+ noun list (tests/language/nouns_300.txt) with real
assets on, for judging by a person (issue #19: the share a person would accept).

    .venv/bin/python benchmarks/noun_sample.py --seed 19 --n 50 [--draw-only]

The sample is drawn from the list by `numpy.random.default_rng(seed)` before anything resolves.
Each row: the noun, what it grounds to (a category, a shape, or "asset:<id>" with the asset's
name), the method and similarity, or the refusal with its nearest candidates.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
NOUNS = Path(__file__).resolve().parents[1] / "tests" / "language" / "nouns_300.txt"


def draw(seed: int, n: int) -> list[str]:
    nouns = [x.strip() for x in NOUNS.read_text().splitlines() if x.strip() and not x.startswith("#")]
    return [nouns[i] for i in sorted(np.random.default_rng(seed).choice(len(nouns), n, replace=False).tolist())]


def resolve(noun: str) -> dict:
    from morphosim_gym.errors import CommandError
    from morphosim_gym.generate.real_assets import asset_index
    from morphosim_gym.language import parse

    try:
        plan = parse(f"a {noun}")
    except CommandError as exc:
        msg = str(exc)
        return {"noun": noun, "result": "refused", "nearest": msg[msg.rfind("Nearest shapes and assets:") + 27:]}
    if not plan.objects:
        return {"noun": noun, "result": f"setting {plan.setting}"}
    o = plan.objects[0]
    out = {"noun": noun, "result": o.category, "method": o.grounding, "similarity": o.similarity}
    if o.category.startswith("asset:"):
        out["asset_name"] = asset_index().get(o.category[len("asset:"):]).name
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=19)
    ap.add_argument("--n", type=int, default=50)
    ap.add_argument("--draw-only", action="store_true")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    sample = draw(args.seed, args.n)
    print(f"sample (seed {args.seed}, {args.n}): {', '.join(sample)}")
    if args.draw_only:
        return 0
    os.environ.pop("MORPHOSIM_ASSET_SOURCES", None)
    import morphosim_gym.generate.compose  # noqa: F401  (registers the real assets as open-vocabulary candidates)

    rows = [resolve(n) for n in sample]
    for r in rows:
        if r["result"] == "refused":
            print(f"  {r['noun']:18s} REFUSED; nearest: {r['nearest'][:110]}")
        else:
            sim = "" if r.get("similarity") is None else f" {r['similarity']:.2f}"
            print(f"  {r['noun']:18s} -> {r['result']}{' (' + r['asset_name'] + ')' if 'asset_name' in r else ''}"
                  f" [{r.get('method', '')}{sim}]")
    if args.json:
        args.json.write_text(json.dumps({"seed": args.seed, "sample": sample, "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
