"""Densification and pruning of Gaussians during the fit (small functions, as in 3DGS).

Running statistics live in a plain dict from `initialize_state`; `refine` clones small
Gaussians and splits large ones whose positional gradients stay high, and prunes nearly
transparent ones, keeping the optimiser's moments of the Gaussians that survive.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from .model import DynamicGaussians

__all__ = ["Strategy", "initialize_state", "accumulate", "refine", "GAUSSIAN_PARAMS"]

GAUSSIAN_PARAMS = ("means", "quats", "log_scales", "opacity_logits", "color_logits")


@dataclass(frozen=True)
class Strategy:
    """When and how to densify and prune.

    Attributes:
        refine_start, refine_stop, refine_every: iterations between which, and how often, to refine.
        grad_threshold: mean positional-gradient norm (per unit of footprint) above which a
            Gaussian is densified.
        split_scale: Gaussians larger than this many footprints are split, smaller ones cloned.
        prune_opacity: Gaussians below this opacity are removed.
        max_gaussians: never grow beyond this many.
        max_footprints: with a value, after every step each Gaussian's scales are kept within
            this many times its footprint (its first size, the pixel it came from); None: free.
    """

    refine_start: int = 150
    refine_stop: int = 900
    refine_every: int = 150
    grad_threshold: float = 2e-4
    split_scale: float = 1.6
    prune_opacity: float = 0.02
    max_gaussians: int = 60000
    max_footprints: float | None = None

    def __post_init__(self) -> None:
        if self.max_footprints is not None and not (np.isfinite(self.max_footprints) and self.max_footprints >= 1):
            raise ValueError(f"Expected max_footprints >= 1 or None, found {self.max_footprints!r}")


def initialize_state(model: DynamicGaussians) -> dict:
    """Per-Gaussian gradient statistics."""
    return {"grad": torch.zeros(model.num), "count": torch.zeros(model.num)}


@torch.no_grad()
def accumulate(state: dict, model: DynamicGaussians, footprint: torch.Tensor) -> None:
    """Add this step's positional gradient norms (scaled by each Gaussian's footprint)."""
    g = model.means.grad
    if g is None:
        return
    n = g.norm(dim=-1) / footprint.clamp(min=1e-6)
    state["grad"] += n                                   # 0 where the step did not see a Gaussian
    state["count"] += (n > 0).to(state["count"].dtype)


def _edit_params(model: DynamicGaussians, optimizer: torch.optim.Optimizer, keep: torch.Tensor,
                 extra: dict[str, torch.Tensor] | None) -> None:
    """Keep rows `keep` of every per-Gaussian parameter (and its Adam moments), append `extra` rows."""
    for group in optimizer.param_groups:
        name = group.get("name")
        if name not in GAUSSIAN_PARAMS and name != "features":
            continue
        old = group["params"][0]
        new_data = old.data[keep]
        if extra is not None and name in extra:
            new_data = torch.cat([new_data, extra[name]])
        new = torch.nn.Parameter(new_data)
        st = optimizer.state.pop(old, None)
        if st:
            for k in ("exp_avg", "exp_avg_sq"):
                v = st[k][keep]
                if extra is not None and name in extra:
                    v = torch.cat([v, torch.zeros_like(extra[name])])
                st[k] = v
            optimizer.state[new] = st
        group["params"][0] = new
        setattr(model, name, new)


@torch.no_grad()
def refine(model: DynamicGaussians, optimizer: torch.optim.Optimizer, state: dict, strategy: Strategy,
           footprint: torch.Tensor, generator: torch.Generator) -> dict[str, int]:
    """Densify and prune once; returns counts {"cloned", "split", "pruned"}."""
    avg = state["grad"] / state["count"].clamp(min=1)
    scales = model.scales().max(dim=-1).values
    big = scales > strategy.split_scale * footprint
    hot = avg > strategy.grad_threshold
    room = max(0, strategy.max_gaussians - model.num)
    hot_idx = torch.nonzero(hot).squeeze(1)
    if len(hot_idx) > room:
        order = torch.argsort(avg[hot_idx], descending=True)[:room]
        hot_idx = hot_idx[order]
    clone = hot_idx[~big[hot_idx]]
    split = hot_idx[big[hot_idx]]
    extra = {}
    ids_extra = []
    fp_extra = []
    if len(clone) or len(split):
        src = torch.cat([clone, split])
        means = model.means.data[src].clone()
        if len(split):
            # sample the new centre inside the parent along its own axes
            from .model import quat_to_rotmat

            R = quat_to_rotmat(model.quats.data[split])
            noise = torch.randn((len(split), 3), generator=generator) * model.scales().data[split]
            means[len(clone):] += torch.einsum("nij,nj->ni", R, noise)
        extra["means"] = means
        extra["quats"] = model.quats.data[src].clone()
        ls = model.log_scales.data[src].clone()
        if len(split):
            ls[len(clone):] -= torch.log(torch.tensor(1.6))
        extra["log_scales"] = ls
        extra["opacity_logits"] = model.opacity_logits.data[src].clone()
        extra["color_logits"] = model.color_logits.data[src].clone()
        if model.features is not None:
            extra["features"] = model.features.data[src].clone()
        ids_extra = model.object_ids[src]
        fp_extra = footprint[src]
        if len(split):   # the split parents shrink too
            model.log_scales.data[split] -= torch.log(torch.tensor(1.6))
    keep = model.opacities().detach() >= strategy.prune_opacity
    pruned = int((~keep).sum())
    _edit_params(model, optimizer, keep, extra or None)
    ids = model.object_ids[keep]
    fp = footprint[keep]
    if len(ids_extra):
        ids = torch.cat([ids, ids_extra])
        fp = torch.cat([fp, fp_extra])
    model.object_ids = ids
    model.rebind()
    state["grad"] = torch.zeros(model.num)
    state["count"] = torch.zeros(model.num)
    state["footprint"] = fp
    return {"cloned": int(len(clone)), "split": int(len(split)), "pruned": pruned}
