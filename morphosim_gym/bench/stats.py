"""Summary statistics of a sweep: rates, means, and paired differences with bootstrap intervals.

The paired difference of a perturbation is taken seed by seed against the base episode of the
same seed and policy (both must have run without error), and its 95% interval is the
percentile bootstrap over seeds (resampling pairs, so the pairing is kept). Resampling uses a
fixed generator: a report is reproducible from its results.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Iterable, Optional

import numpy as np

from .suite import BASE

__all__ = ["bootstrap_mean", "Interval", "ConditionSummary", "summarize"]

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
