"""The paper's frame-wise trajectory energy on the latent grid.

    E_i = (1 - sum_{u in B_i} A_{i,u,n} / sum_u A_{i,u,n})^2

for latent frame i, spatial location u on the latent H x W grid and motion token(s) n (the
attention of a multi-word target is the sum over its tokens). Boxes are soft masks (the covered
fraction of each latent cell), so the "in-box mass" is ``sum_u M_{i,u} A_{i,u,n}``.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch

__all__ = ["target_attention", "frame_energy", "in_box_fraction", "trajectory_loss"]

_EPS = 1e-12


def target_attention(token_maps: torch.Tensor, groups: Sequence[Sequence[int]]) -> torch.Tensor:
    """Sum the recorded token columns of each target.

    Args:
        token_maps: [..., K_tokens, T, H, W] attention per recorded token.
        groups: for each target, the positions (into the K_tokens axis) of its tokens.

    Returns:
        [..., N_targets, T, H, W].
    """
    return torch.stack([token_maps[..., list(g), :, :, :].sum(dim=-4) for g in groups], dim=-4)


def in_box_fraction(attn: torch.Tensor, masks: torch.Tensor) -> torch.Tensor:
    """Fraction of each frame's attention mass inside its box.

    Args:
        attn: [..., T, H, W] non-negative attention on the latent grid.
        masks: [..., T, H, W] box coverage in [0, 1] (broadcastable to `attn`).

    Returns:
        [..., T] in [0, 1].
    """
    inside = (attn * masks).sum(dim=(-2, -1))
    total = attn.sum(dim=(-2, -1))
    return inside / total.clamp_min(_EPS)


def frame_energy(attn: torch.Tensor, masks: torch.Tensor) -> torch.Tensor:
    """E_i = (1 - in-box fraction)^2 per frame: [..., T, H, W] x [..., T, H, W] -> [..., T]."""
    return (1.0 - in_box_fraction(attn, masks)) ** 2


def trajectory_loss(attn: torch.Tensor, masks: torch.Tensor, frame_reduction: str = "mean") -> torch.Tensor:
    """The guidance loss: E_i reduced over frames (mean, or the paper's plain sum), then averaged
    over targets (and batch).

    Args:
        attn: [..., N_targets, T, H, W]; masks: broadcastable to it.
        frame_reduction: "mean" (E in [0, 1]) or "sum" (sum_i E_i, in [0, T]).

    Returns:
        scalar tensor.
    """
    fe = frame_energy(attn, masks)
    if frame_reduction == "sum":
        return fe.sum(dim=-1).mean()
    if frame_reduction != "mean":
        raise ValueError(f"Expected frame_reduction 'mean' or 'sum', found {frame_reduction!r}")
    return fe.mean()
