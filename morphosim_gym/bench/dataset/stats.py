"""Per-feature statistics in LeRobot's form: min, max, mean, std, count and the quantiles q01, q10,
q50, q90, q99; per episode (exact), and over a dataset by merging episodes (exact mean and std;
quantiles as LeRobot merges them: the lowest of the episodes' lower quantiles and the highest of
their upper ones, a conservative envelope).

Shapes: a vector feature [D] gives [D] stats, a scalar (shape [1]) gives [1], an image feature
gives per-channel [3, 1, 1] stats of values scaled to [0, 1]; `count` is always [1].
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

__all__ = ["QUANTILES", "feature_stats", "image_stats", "merge_stats", "to_json"]

QUANTILES = {"q01": 0.01, "q10": 0.10, "q50": 0.50, "q90": 0.90, "q99": 0.99}


def _stats(x: np.ndarray, count: int) -> dict[str, np.ndarray]:
    """Stats over axis 0 of x [N, C]."""
    out = {"min": x.min(axis=0), "max": x.max(axis=0), "mean": x.mean(axis=0), "std": x.std(axis=0),
           "count": np.array([count], np.int64)}
    for name, q in QUANTILES.items():
        out[name] = np.quantile(x, q, axis=0)
    return out


def feature_stats(values: np.ndarray) -> dict[str, np.ndarray]:
    """Stats of a numeric feature's frames: values [T] (a scalar feature) or [T, D]."""
    x = np.asarray(values, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or len(x) == 0:
        raise ValueError(f"Expected feature values [T] or [T, D] with T >= 1, found shape {np.shape(values)}")
    return _stats(x, len(x))


def image_stats(frames: np.ndarray) -> dict[str, np.ndarray]:
    """Per-channel stats [3, 1, 1] of frames [T, H, W, 3] uint8, scaled to [0, 1]."""
    if frames.ndim != 4 or len(frames) == 0:
        raise ValueError(f"Expected frames [T, H, W, C] with T >= 1, found shape {frames.shape}")
    x = frames.reshape(-1, frames.shape[-1]).astype(np.float64) / 255.0
    return {k: (v if k == "count" else v.reshape(-1, 1, 1)) for k, v in _stats(x, len(frames)).items()}


def merge_stats(parts: list[Mapping[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """The stats of the union of the episodes whose stats are `parts`."""
    if not parts:
        raise ValueError("Expected stats of one or more episodes, found none")
    counts = np.array([float(p["count"][0]) for p in parts])
    means = np.stack([p["mean"] for p in parts])
    w = (counts / counts.sum()).reshape((-1,) + (1,) * (means.ndim - 1))
    mean = (w * means).sum(axis=0)
    var = (w * (np.stack([p["std"] for p in parts]) ** 2 + (means - mean) ** 2)).sum(axis=0)
    out = {"min": np.min(np.stack([p["min"] for p in parts]), axis=0),
           "max": np.max(np.stack([p["max"] for p in parts]), axis=0),
           "mean": mean, "std": np.sqrt(var), "count": np.array([int(counts.sum())], np.int64)}
    for name, q in QUANTILES.items():
        vals = np.stack([p[name] for p in parts])
        out[name] = vals.min(axis=0) if q <= 0.5 else vals.max(axis=0)
    return out


def to_json(stats: Mapping[str, Mapping[str, np.ndarray]]) -> dict:
    """Nested lists, as `meta/stats.json` holds them."""
    return {key: {k: np.asarray(v).tolist() for k, v in s.items()} for key, s in stats.items()}
