"""Summary statistics of a sweep: rates, means, and paired differences with bootstrap intervals.

The paired difference of a perturbation is taken seed by seed against the base episode of the
same seed and policy (both must have run without error), and its 95% interval is the
percentile bootstrap over seeds (resampling pairs, so the pairing is kept). Resampling uses a
fixed generator: a report is reproducible from its results.

Statistical power (`power`): on the same pairs, the interval an unpaired design would give
(perturbed and base episodes resampled independently, as if they came from different seeds)
against the paired one. An interval's width shrinks as 1/sqrt(n), so an unpaired design needs
(unpaired width / paired width)^2 times as many episodes for the paired interval's width; the
report states that ratio and the share of episodes pairing saves, 1 - (paired / unpaired)^2.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Iterable, Optional

import numpy as np

from .suite import BASE

__all__ = ["bootstrap_mean", "bootstrap_difference", "Interval", "ConditionSummary", "summarize", "PowerSummary",
           "power"]

N_BOOT = 4000


@dataclass(frozen=True)
class Interval:
    """A mean and its bootstrap interval (nan bounds when there is no data)."""

    mean: float
    low: float
    high: float
    n: int

    def as_dict(self) -> dict:
        """JSON-friendly (None for nan)."""
        return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in asdict(self).items()}


def bootstrap_mean(values: Iterable[float], level: float = 0.95, n_boot: int = N_BOOT, seed: int = 0) -> Interval:
    """The mean of `values` with a percentile-bootstrap `level` interval."""
    x = np.asarray(list(values), dtype=np.float64)
    if x.size == 0:
        return Interval(float("nan"), float("nan"), float("nan"), 0)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, x.size, size=(n_boot, x.size))
    means = x[idx].mean(axis=1)
    tail = (1.0 - level) / 2.0
    lo, hi = np.quantile(means, [tail, 1.0 - tail])
    return Interval(float(x.mean()), float(lo), float(hi), int(x.size))


def bootstrap_difference(x: Iterable[float], y: Iterable[float], level: float = 0.95, n_boot: int = N_BOOT,
                         seed: int = 0) -> Interval:
    """mean(x) - mean(y) with an unpaired percentile-bootstrap interval (x and y resampled independently)."""
    a = np.asarray(list(x), dtype=np.float64)
    b = np.asarray(list(y), dtype=np.float64)
    if a.size == 0 or b.size == 0:
        return Interval(float("nan"), float("nan"), float("nan"), 0)
    rng = np.random.default_rng(seed)
    diffs = a[rng.integers(0, a.size, (n_boot, a.size))].mean(1) - b[rng.integers(0, b.size, (n_boot, b.size))].mean(1)
    tail = (1.0 - level) / 2.0
    lo, hi = np.quantile(diffs, [tail, 1.0 - tail])
    return Interval(float(a.mean() - b.mean()), float(lo), float(hi), int(min(a.size, b.size)))


@dataclass(frozen=True)
class PowerSummary:
    """Paired against unpaired 95% interval widths of one condition's difference to the base.

    Attributes:
        metric: "return" or "success".
        pairs: the number of (perturbed, base) pairs both designs use.
        paired_width, unpaired_width: interval widths (high - low).
        episode_ratio: episodes an unpaired design needs per paired episode for the paired width,
            (unpaired / paired)^2; inf when the paired width is 0 and the unpaired one is not, nan
            when both are 0 (no variation to compare).
        saved: the share of episodes pairing saves, 1 - 1 / episode_ratio (nan with the ratio).
    """

    policy: str
    perturbation: str
    metric: str
    pairs: int
    paired_width: float
    unpaired_width: float
    episode_ratio: float
    saved: float

    def as_dict(self) -> dict:
        """JSON-friendly (None for nan, "inf" for an infinite ratio)."""
        out = asdict(self)
        for k, v in out.items():
            if isinstance(v, float) and np.isnan(v):
                out[k] = None
            elif isinstance(v, float) and np.isinf(v):
                out[k] = "inf"
        return out


def _ratio(paired: float, unpaired: float) -> tuple[float, float]:
    if paired > 1e-12:
        r = (unpaired / paired) ** 2
        return r, 1.0 - 1.0 / r if r > 0 else float("nan")
    if unpaired > 1e-12:
        return float("inf"), 1.0
    return float("nan"), float("nan")


def power(records: list[dict], policies: list[str], conditions: list[str],
          metrics: tuple[str, ...] = ("return", "success")) -> list[PowerSummary]:
    """Per (policy, perturbation, metric): paired vs unpaired interval widths on the same pairs."""
    out = []
    for policy in policies:
        mine = [r for r in records if r["policy"] == policy and r["status"] == "ok"]
        base = {r["seed"]: r for r in mine if r["perturbation"] == BASE}
        for cond in conditions:
            if cond == BASE:
                continue
            pairs = [(r, base[r["seed"]]) for r in mine if r["perturbation"] == cond and r["seed"] in base]
            for metric in metrics:
                x = [float(r[metric]) for r, _ in pairs]
                y = [float(b[metric]) for _, b in pairs]
                paired = bootstrap_mean([a - b for a, b in zip(x, y)])
                unpaired = bootstrap_difference(x, y)
                wp = paired.high - paired.low if pairs else float("nan")
                wu = unpaired.high - unpaired.low if pairs else float("nan")
                ratio, saved = _ratio(wp, wu) if pairs else (float("nan"), float("nan"))
                out.append(PowerSummary(policy, cond, metric, len(pairs), wp, wu, ratio, saved))
    return out


@dataclass(frozen=True)
class ConditionSummary:
    """One policy under one condition (perturbation or base)."""

    policy: str
    perturbation: str
    episodes: int
    failed: int
    success: Interval
    returns: Interval
    delta_success: Optional[Interval]        # paired, perturbed minus base; None for the base
    delta_return: Optional[Interval]

    def as_dict(self) -> dict:
        """JSON-friendly."""
        out = {"policy": self.policy, "perturbation": self.perturbation, "episodes": self.episodes,
               "failed": self.failed}
        for name in ("success", "returns", "delta_success", "delta_return"):
            v = getattr(self, name)
            out[name] = None if v is None else v.as_dict()
        return out


def summarize(records: list[dict], policies: list[str], conditions: list[str]) -> list[ConditionSummary]:
    """Per (policy, condition) summaries of finished records (failed episodes are counted, not averaged)."""
    out = []
    for policy in policies:
        mine = [r for r in records if r["policy"] == policy]
        base = {r["seed"]: r for r in mine if r["perturbation"] == BASE and r["status"] == "ok"}
        for cond in conditions:
            recs = [r for r in mine if r["perturbation"] == cond]
            ok = [r for r in recs if r["status"] == "ok"]
            succ = bootstrap_mean([float(r["success"]) for r in ok])
            ret = bootstrap_mean([float(r["return"]) for r in ok])
            ds = dr = None
            if cond != BASE:
                pairs = [(r, base[r["seed"]]) for r in ok if r["seed"] in base]
                ds = bootstrap_mean([float(r["success"]) - float(b["success"]) for r, b in pairs])
                dr = bootstrap_mean([float(r["return"]) - float(b["return"]) for r, b in pairs])
            out.append(ConditionSummary(policy, cond, len(recs), len(recs) - len(ok), succ, ret, ds, dr))
    return out
