"""Edit latency on a reconstructed scene, side by side with generating and reconstructing it again.

    python benchmarks/edit.py [--size 224] [--json out.json] [--repeat 20]

Builds (or loads from the reconstruction cache) a scene reconstructed from a generated clip
(with its feature field; `--size` sets the clip resolution and so the Gaussian count), then
times, each as the median over `--repeat` runs:
    first query   a recolour of a target never selected before (embedding + per-Gaussian
                  decoding + the threshold search with its renders), the selector's cache cleared;
    cached edit   the same target again (selection cached), for each kind of edit;
and, in the same run, generating the clip and reconstructing it again without the cache.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from dataclasses import replace
from pathlib import Path

import morphosim_gym as ms
from morphosim_gym.reconstruct import ReconstructionConfig

PROMPT = "The bus is moving from right to left"
EDITS = ["make the bus yellow", "make the bus darker", "delete the bus", "extract the bus", "reverse the bus",
         "move the bus to the right", "make the bus twice as fast", "stop the bus"]


def _time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", type=int, default=224, help="clip resolution (sets the Gaussian count)")
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    gen = ms.GenerationConfig(width=args.size, height=args.size)
    sim = ms.MorphoSim(generation=gen, reconstruction_config=ReconstructionConfig(progress=False))
    clip = sim.generate_clip(PROMPT, seed=0)
    scene = sim.reconstruct(clip)                       # cached after the first run
    sim.edit(scene, EDITS[0])                           # JIT, embedding model load
    results = {"gaussians": len(scene.gaussians), "size": args.size}

    def first_query() -> None:
        sim.editor.selector.clear()
        sim.edit(scene, EDITS[0])

    results["first_query_ms"] = 1000 * _time(first_query, max(3, args.repeat // 4))
    sim.edit(scene, EDITS[0])
    results["cached_ms"] = {e: 1000 * _time(lambda e=e: sim.edit(scene, e), args.repeat) for e in EDITS}
    start = time.perf_counter()
    clip2 = sim.generate_clip(PROMPT, seed=1)
    cfg = replace(sim.config.reconstruction_config or ReconstructionConfig(), cache=False, progress=False)
    from morphosim_gym.reconstruct import reconstruct

    reconstruct(clip2, cfg)
    results["generate_and_reconstruct_s"] = time.perf_counter() - start
    worst = max(results["cached_ms"].values())
    results["speedup_vs_regenerate"] = results["generate_and_reconstruct_s"] * 1000 / worst
    print(f"scene: {results['gaussians']} Gaussians (clip {args.size}x{args.size})")
    print(f"first query (cold selection)   {results['first_query_ms']:8.1f} ms")
    for e, v in results["cached_ms"].items():
        print(f"cached  {e:32s} {v:8.2f} ms")
    print(f"generate + reconstruct again   {results['generate_and_reconstruct_s']:8.1f} s  "
          f"(x{results['speedup_vs_regenerate']:.0f} the slowest cached edit)")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
