"""Parse-time benchmark of the rule parser (a table and JSON; not a pass/fail test).

    python -m morphosim_gym.language.bench [tests/language/corpus.jsonl] [--repeats 5]

Times every corpus command that needs no embedding model (vocabulary nouns only: the items of kind
"embedding" and those whose plan grounds a noun by embedding are timed separately, after a warm
model load), reporting the median, 95th percentile and maximum per command in milliseconds.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from typing import Sequence

from ..errors import CommandError
from .evaluate import CorpusScene, load_corpus
from .rules import parse_rules

__all__ = ["main", "time_commands"]


def _uses_embeddings(plan) -> bool:
    return any(o.grounding == "embedding" for o in plan.objects)


def time_commands(items: Sequence[dict], repeats: int = 5) -> list[float]:
    """Median-of-`repeats` parse time (ms) of each item."""
    out = []
    for it in items:
        scene = CorpusScene(it["scene"]) if it.get("scene") else None
        ts = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            try:
                parse_rules(it["text"], scene)
            except CommandError:
                pass
            ts.append((time.perf_counter() - t0) * 1000.0)
        out.append(statistics.median(ts))
    return out


def _stats(ms: list[float]) -> dict:
    if not ms:
        return {"n": 0}
    s = sorted(ms)
    return {"n": len(s), "median_ms": round(statistics.median(s), 3), "mean_ms": round(statistics.fmean(s), 3),
            "p95_ms": round(s[min(len(s) - 1, int(0.95 * len(s)))], 3), "max_ms": round(s[-1], 3)}


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m morphosim_gym.language.bench", description=__doc__.split("\n")[0])
    ap.add_argument("corpus", nargs="?", default="tests/language/corpus.jsonl")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    items = load_corpus(args.corpus)
    from . import embeddings

    t0 = time.perf_counter()  # first parse in this process: builds the word tables and the typo index
    parse_rules("a red ball bounces from right to left")
    first_ms = (time.perf_counter() - t0) * 1000.0

    # split: which commands need the embedding model (decided without loading it: vocabulary-only parse)
    plain, embed_items = [], []
    for it in items:
        scene = CorpusScene(it["scene"]) if it.get("scene") else None
        before = embeddings.is_loaded()
        try:
            plan = parse_rules(it["text"], scene)
            needs = _uses_embeddings(plan) or (not before and embeddings.is_loaded())
        except CommandError:
            needs = not before and embeddings.is_loaded()
        (embed_items if needs or it.get("kind") == "embedding" else plain).append(it)
    t_plain = time_commands(plain, args.repeats)
    t_embed = time_commands(embed_items, args.repeats)
    rep = {"no_embeddings": _stats(t_plain), "with_embeddings_warm": _stats(t_embed),
           "first_parse_ms": round(first_ms, 1), "model_loaded": embeddings.is_loaded()}
    print(f"{'commands':<28}{'n':>5}{'median ms':>11}{'mean ms':>9}{'p95 ms':>9}{'max ms':>9}")
    for name, st in (("vocabulary only", rep["no_embeddings"]), ("with embeddings (warm)", rep["with_embeddings_warm"])):
        if st["n"]:
            print(f"{name:<28}{st['n']:>5}{st['median_ms']:>11.3f}{st['mean_ms']:>9.3f}{st['p95_ms']:>9.3f}"
                  f"{st['max_ms']:>9.3f}")
    print(f"first parse in a fresh process (word tables, typo index): {first_ms:.1f} ms")
    print(json.dumps(rep))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
