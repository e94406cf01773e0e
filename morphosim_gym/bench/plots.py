"""The report's figures (matplotlib, headless): bars with intervals, and frame strips."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from .episode import EpisodeKey
from .layout import frames_path, slug
from .stats import ConditionSummary, Interval, PowerSummary
from .suite import BASE, Suite

__all__ = ["bar_chart", "frame_strips", "power_chart"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _bars(ax, conditions: list[str], policies: list[str], values: dict, title: str, percent: bool) -> None:
    width = 0.8 / max(len(policies), 1)
    x = np.arange(len(conditions))
    scale = 100.0 if percent else 1.0
    for i, policy in enumerate(policies):
        ivs: list[Optional[Interval]] = [values.get((policy, c)) for c in conditions]
        mean = np.array([iv.mean * scale if iv and iv.n else np.nan for iv in ivs])
        lo = np.array([(iv.mean - iv.low) * scale if iv and iv.n else 0.0 for iv in ivs])
        hi = np.array([(iv.high - iv.mean) * scale if iv and iv.n else 0.0 for iv in ivs])
        ax.bar(x + (i - (len(policies) - 1) / 2) * width, np.nan_to_num(mean), width, yerr=[lo, hi], capsize=3,
               label=policy)
    ax.axhline(0.0, color="black", linewidth=0.6)
    ax.set_xticks(x, conditions, rotation=35, ha="right", fontsize=8)
    ax.set_title(title, fontsize=9)


def power_chart(path: Path, rows: list[PowerSummary], metric: str = "return") -> bool:
    """Paired and unpaired 95% interval widths of each condition's difference to the base (one panel
    per policy, `metric` only). Returns False when there is nothing to draw."""
    rows = [r for r in rows if r.metric == metric and r.pairs > 0]
    if not rows:
        return False
    plt = _pyplot()
    policies = list(dict.fromkeys(r.policy for r in rows))
    per = max(len(rows) // len(policies), 1)
    fig, axes = plt.subplots(len(policies), 1, figsize=(max(6.0, 2 + 0.38 * per), 3.4 * len(policies)), squeeze=False)
    for ax, policy in zip(axes[:, 0], policies):
        mine = [r for r in rows if r.policy == policy]
        x = np.arange(len(mine))
        ax.bar(x - 0.2, [r.paired_width for r in mine], 0.4, label="paired")
        ax.bar(x + 0.2, [r.unpaired_width for r in mine], 0.4, label="unpaired")
        ax.set_xticks(x, [r.perturbation for r in mine], rotation=35, ha="right", fontsize=8)
        ax.set_title(f"{policy}: 95% CI width of Δ {metric} (same episodes)", fontsize=9)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return True


def bar_chart(path: Path, summaries: list[ConditionSummary], policies: list[str], conditions: list[str]) -> bool:
    """Success rate per condition, and the paired differences of success and return to the base,
    each with its 95% interval, one bar per policy. Returns False when there is nothing to draw."""
    if not summaries:
        return False
    plt = _pyplot()
    perturbed = [c for c in conditions if c != BASE]
    fig, axes = plt.subplots(1, 3, figsize=(4 + 1.1 * len(conditions) * 1.5, 3.6), squeeze=False)
    ax = axes[0]
    _bars(ax[0], conditions, policies, {(s.policy, s.perturbation): s.success for s in summaries},
          "success rate (%)", True)
    ax[0].set_ylim(0, 105)
    _bars(ax[1], perturbed, policies, {(s.policy, s.perturbation): s.delta_success for s in summaries},
          "Δ success vs base (points)", True)
    _bars(ax[2], perturbed, policies, {(s.policy, s.perturbation): s.delta_return for s in summaries},
          "Δ return vs base", False)
    ax[0].legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def frame_strips(out: Path, suite: Suite, policy: str) -> Optional[str]:
    """One row of frames per condition (seed `suite.seed`), base first; returns the file name, or
    None when no episode of this policy kept frames."""
    rows = []
    for cond in suite.conditions:
        p = frames_path(out, EpisodeKey(policy, cond.name, suite.seed))
        if p.exists():
            import imageio.v3 as iio

            rows.append((cond.name, iio.imread(p)))
    if not rows:
        return None
    plt = _pyplot()
    h, w = rows[0][1].shape[:2]
    fig, axes = plt.subplots(len(rows), 1, figsize=(1.6 * w / h * 1.0 + 1.5, 1.5 * len(rows)), squeeze=False)
    for ax, (name, img) in zip(axes[:, 0], rows):
        ax.imshow(img)
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_ylabel(name, rotation=0, ha="right", va="center", fontsize=8)
    axes[0, 0].set_title(f"{policy}: frames over the episode (left to right)", fontsize=9)
    fig.tight_layout()
    name = f"frames_{slug(policy)}.png"
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    return name
