#!/usr/bin/env python
"""Benchmark of the asset layer (issue #19): what is installed, how well it covers the generator's
categories, and what a conversion costs.

Run from the repository root:

    python benchmarks/assets.py                         # counts, coverage, timings (~1 min)
    python benchmarks/assets.py --gallery /tmp/assets_gallery   # also render 6 assets to PNGs
    python benchmarks/assets.py --sweep 2000            # also convert every mesh at 2000 Gaussians
    python benchmarks/assets.py --json out.json

Coverage: an asset covers a category when the category's name, plural or a synonym (from
`language.vocabulary`) is a whole word of the asset's name, category or tags. Timings use a fresh
conversion cache: "cold" is load + convert + store, "cached" is a verified read of the entry.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from morphosim_gym.assets import AssetError, AssetIndex, AssetWarning, ConversionCache, asset_gaussians
from morphosim_gym.assets.search import lexical_scores
from morphosim_gym.language.vocabulary import CATEGORIES

TIMED = ["sweethome3d/blendswap-cc-0/horse2", "sweethome3d/scopia/smart-car", "sweethome3d/scopia/bus",
         "sweethome3d/blendswap-cc-by/fordfocus", "sweethome3d/blendswap-cc-0/armchair",
         "sweethome3d/katorlegaz/mid-century-chair", "sweethome3d/blendswap-cc-0/bed1", "robosuite/objects/bread",
         "robosuite/objects/milk", "robosuite/objects/can", "sweethome3d/scopia/truck"]
GALLERY = ["sweethome3d/blendswap-cc-0/horse2", "sweethome3d/scopia/smart-car",
           "sweethome3d/katorlegaz/mid-century-chair", "robosuite/objects/cereal", "sweethome3d/scopia/bus",
           "sweethome3d/blendswap-cc-by/horse"]


def coverage(index: AssetIndex, threshold: float = 0.75) -> dict[str, list[str]]:
    """Category -> ids of the mesh assets that name it as a whole word (threshold 0.75: in the name,
    category or tags; 1.0: in the name)."""
    meshes = index.kind("mesh")
    out = {}
    for cat in CATEGORIES.values():
        words = {cat.name, cat.plural, *cat.synonyms}
        hit = set()
        for w in words:
            scores = lexical_scores(w, meshes)
            hit |= {meshes[i].id for i in range(len(meshes)) if scores[i] >= threshold}
        out[cat.name] = sorted(hit)
    return out


def timings(index: AssetIndex, ids: list[str], budget: int) -> dict:
    cache = ConversionCache(Path(tempfile.mkdtemp(prefix="assets-bench-")))
    cold, warm, rows = [], [], []
    for asset_id in ids:
        if asset_id not in index:
            continue
        t0 = time.perf_counter()
        g = asset_gaussians(index.get(asset_id), budget=budget, cache=cache)
        t1 = time.perf_counter()
        asset_gaussians(index.get(asset_id), budget=budget, cache=cache)
        t2 = time.perf_counter()
        cold.append(t1 - t0)
        warm.append(t2 - t1)
        rows.append({"id": asset_id, "gaussians": len(g), "cold_s": round(t1 - t0, 4), "cached_s": round(t2 - t1, 4)})
    return {"budget": budget, "assets": rows, "median_cold_s": statistics.median(cold) if cold else None,
            "median_cached_s": statistics.median(warm) if warm else None}


def sweep(index: AssetIndex, budget: int) -> dict:
    """Convert every mesh (no cache): failures (with their message), warnings and times."""
    failures, times, warned = [], [], 0
    for r in index.kind("mesh"):
        t0 = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", AssetWarning)
            try:
                asset_gaussians(r, budget=budget, cache=False)
            except AssetError as exc:
                failures.append({"id": r.id, "error": str(exc)})
        warned += bool(caught)
        times.append(time.perf_counter() - t0)
    times.sort()
    return {"budget": budget, "meshes": len(times), "failures": failures, "with_warnings": warned,
            "median_s": statistics.median(times), "p95_s": times[int(0.95 * (len(times) - 1))], "max_s": times[-1]}


def gallery(index: AssetIndex, folder: Path, budget: int) -> list[str]:
    from morphosim_gym.assets.cli import render_asset

    out = []
    for asset_id in GALLERY:
        if asset_id in index:
            path = folder / f"{asset_id.replace('/', '__')}.png"
            render_asset(asset_gaussians(index.get(asset_id), budget=budget, cache=False), path, width=320)
            out.append(str(path))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--budget", type=int, default=20000)
    ap.add_argument("--gallery", type=Path, default=None)
    ap.add_argument("--sweep", type=int, default=0, metavar="BUDGET")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()

    cache_dir = Path(tempfile.mkdtemp(prefix="assets-index-"))
    t0 = time.perf_counter()
    index = AssetIndex.build(cache_dir=cache_dir)
    t1 = time.perf_counter()
    AssetIndex.build(cache_dir=cache_dir)
    t2 = time.perf_counter()
    cov = coverage(index)
    by_name = coverage(index, threshold=1.0)
    result = {"assets": len(index), "per_source": index.counts_by_source(),
              "index_build_s": round(t1 - t0, 3), "index_cached_s": round(t2 - t1, 3),
              "coverage": {k: len(v) for k, v in cov.items()},
              "covered_categories": sum(bool(v) for v in cov.values()), "categories": len(cov),
              "coverage_by_name": {k: len(v) for k, v in by_name.items()},
              "covered_categories_by_name": sum(bool(v) for v in by_name.values()),
              "coverage_examples": {k: v[:3] for k, v in cov.items() if v},
              "timings": timings(index, TIMED, args.budget)}
    if args.sweep:
        result["sweep"] = sweep(index, args.sweep)
    if args.gallery:
        result["gallery"] = gallery(index, args.gallery, args.budget)

    print(f"assets: {result['assets']}  per source: {result['per_source']}")
    print(f"index: build {result['index_build_s']} s, cached {result['index_cached_s']} s")
    print(f"categories covered: {result['covered_categories']} / {result['categories']} by name, category or tag; "
          f"{result['covered_categories_by_name']} by name (assets: any word / name)")
    for name, n in sorted(result["coverage"].items(), key=lambda kv: (-kv[1], kv[0])):
        print(f"  {n:4d} {result['coverage_by_name'][name]:4d}  {name}")
    tm = result["timings"]
    print(f"conversion at {tm['budget']} Gaussians: median cold {tm['median_cold_s']:.3f} s, "
          f"cached {tm['median_cached_s']:.4f} s")
    for row in tm["assets"]:
        print(f"  {row['cold_s']:7.3f} s  {row['cached_s']:7.4f} s  {row['id']}")
    if args.sweep:
        sw = result["sweep"]
        print(f"sweep at {sw['budget']}: {sw['meshes']} meshes, {len(sw['failures'])} failed, "
              f"{sw['with_warnings']} with warnings, median {sw['median_s']:.3f} s, p95 {sw['p95_s']:.3f} s, "
              f"max {sw['max_s']:.3f} s")
        for f in sw["failures"]:
            print(f"  FAILED {f['id']}: {f['error']}")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
