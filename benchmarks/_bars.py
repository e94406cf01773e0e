"""Shared output of the benchmark scripts: one MET/MISS line per bar, and the JSON record."""

from __future__ import annotations

import json
from pathlib import Path


def bar_line(name: str, bar: float, worst: float, higher_is_better: bool = True, median: float | None = None) -> str:
    """'  MET  name  bar ...  worst ...' (MISS when `worst` is on the wrong side of `bar`)."""
    ok = worst >= bar if higher_is_better else worst <= bar
    line = f"  {'MET ' if ok else 'MISS'} {name:14s} bar {bar:6.2f}  worst {worst:7.3f}"
    return line if median is None else f"{line}  median {median:7.3f}"


def write_json(path: Path | None, payload: dict) -> None:
    """Write `payload` to `path` (indented) and say so; nothing when no path was asked for."""
    if path is not None:
        path.write_text(json.dumps(payload, indent=2))
        print(f"wrote {path}")
