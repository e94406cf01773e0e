#!/usr/bin/env python
"""Resolve a seeded random sample of the 300+ noun list (tests/language/nouns_300.txt) with real
assets on, for judging by a person (issue #19: the share a person would accept).

    .venv/bin/python benchmarks/noun_sample.py --seed 19 --n 50 [--draw-only]
    .venv/bin/python benchmarks/noun_sample.py --seed 2027 --n 60 --exclude-seed 19 --exclude-n 50   # held out
    .venv/bin/python benchmarks/noun_sample.py --seed 4099 --n 60 --exclude-seed 19 --exclude-n 50 \
        --exclude-seed 2027 --exclude-n 60                                                           # third
    .venv/bin/python benchmarks/noun_sample.py --nouns benchmarks/noun_dev.txt                       # a whole list

The sample is drawn from the list by `numpy.random.default_rng(seed)` before anything resolves
(`--exclude-seed`: first leave out the nouns of an earlier sample, so the new one is held out).
Each row: the noun, what it grounds to (a category, a shape, or "asset:<id>" with the asset's
name), the method ("kind": a stand-in of the same kind) and similarity, or the refusal with its
nearest candidates. `--nouns FILE` resolves every noun of FILE in its order instead of drawing
(the dev list `benchmarks/noun_dev.txt`: nouns outside the 300 list, seen data). `--grounding` sets the grounding level (default: the library's, "kind").
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


def read_nouns(path: Path) -> list[str]:
    """The nouns of a list file: one a line, blank lines and "#" comments skipped.

    Raises:
        SystemExit: the file is missing or holds no noun (the message names it).
    """
    try:
        nouns = [x.strip() for x in path.read_text().splitlines() if x.strip() and not x.startswith("#")]
    except OSError as exc:
        raise SystemExit(f"Expected a readable noun list, found {path}: {exc}") from exc
    if not nouns:
        raise SystemExit(f"Expected at least one noun in {path}, found none")
    return nouns


def all_nouns() -> list[str]:
    return read_nouns(NOUNS)


def draw(seed: int, n: int, exclude: tuple[int, int] | list[tuple[int, int]] | None = None) -> list[str]:
    """`n` nouns of the list by the seed; `exclude`: one (seed, n) or a list of them, each drawn
    as it was (each one without the samples listed before it), without the nouns they drew."""
    nouns = all_nouns()
    earlier = [exclude] if isinstance(exclude, tuple) else list(exclude or [])
    gone: set[str] = set()
    for i, (s, k) in enumerate(earlier):
        gone |= set(draw(s, k, earlier[:i] or None))
    nouns = [x for x in nouns if x not in gone]
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
    if o.grounding == "kind":
        out["stand_in"] = True
    if o.category.startswith("asset:"):
        out["asset_name"] = asset_index().get(o.category[len("asset:"):]).name
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=19)
    ap.add_argument("--n", type=int, default=50)
    ap.add_argument("--draw-only", action="store_true")
    ap.add_argument("--exclude-seed", type=int, action="append", default=[],
                    help="leave out the nouns of the sample of this seed (repeat for several samples, in the "
                         "order they were drawn; each was drawn without the ones before it)")
    ap.add_argument("--exclude-n", type=int, action="append", default=[], help="... of this size (one per "
                    "--exclude-seed; default 50)")
    ap.add_argument("--nouns", type=Path, default=None,
                    help="resolve every noun of this file (one a line, '#' comments) instead of drawing a sample")
    ap.add_argument("--grounding", default=None, help="grounding level (default: the library's)")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    if len(args.exclude_n) > len(args.exclude_seed):
        ap.error(f"Expected at most one --exclude-n per --exclude-seed, found {len(args.exclude_n)} for "
                 f"{len(args.exclude_seed)}")
    sizes = args.exclude_n + [50] * (len(args.exclude_seed) - len(args.exclude_n))
    exclude = list(zip(args.exclude_seed, sizes))
    if args.nouns is not None:
        if exclude:
            ap.error("Expected --nouns without --exclude-seed (a whole list is not drawn), found both")
        sample = read_nouns(args.nouns)
        print(f"list {args.nouns} ({len(sample)} nouns): {', '.join(sample)}")
    else:
        sample = draw(args.seed, args.n, exclude)
        held = "".join(f", without the seed-{s} sample" for s, _ in exclude)
        print(f"sample (seed {args.seed}, {args.n}{held}): {', '.join(sample)}")
    if args.draw_only:
        return 0
    os.environ.pop("MORPHOSIM_ASSET_SOURCES", None)
    if args.grounding:
        os.environ["MORPHOSIM_GROUNDING"] = args.grounding
    from morphosim_gym.language.grounding import grounding_level

    level = grounding_level()
    print(f"grounding level: {level}")
    import morphosim_gym.generate.compose  # noqa: F401  (registers the real assets as open-vocabulary candidates)

    rows = [resolve(n) for n in sample]
    for r in rows:
        if r["result"] == "refused":
            print(f"  {r['noun']:18s} REFUSED; nearest: {r['nearest'][:110]}")
        else:
            sim = "" if r.get("similarity") is None else f" {r['similarity']:.2f}"
            print(f"  {r['noun']:18s} -> {r['result']}{' (' + r['asset_name'] + ')' if 'asset_name' in r else ''}"
                  f" [{r.get('method', '')}{sim}]{' STAND-IN' if r.get('stand_in') else ''}")
    if args.json:
        args.json.write_text(json.dumps({"seed": None if args.nouns else args.seed,
                                         "nouns_file": str(args.nouns) if args.nouns else None, "exclude": [list(e) for e in exclude], "grounding": level, "sample": sample,
                                         "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
