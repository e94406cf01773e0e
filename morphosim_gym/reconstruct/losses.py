"""Losses of the 4D fit: photometric (L1 + SSIM), depth, masks, tracks, and scaffold regularisers."""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F

from .fused_ssim import SSIM_C1, SSIM_C2, WINDOW_RADIUS, fused_ssim_applies, fused_ssim_loss, window_taps
from .model import gather_rows

__all__ = ["ssim_loss", "conv_ssim_loss", "photometric_loss", "depth_loss", "scale_shift_depth_loss", "mask_loss", "mask_iou_loss", "empty_alpha_loss", "track_loss",
           "arap_loss", "smooth_motion_loss", "psnr_torch"]

_WINDOWS: dict[tuple, torch.Tensor] = {}


def _window(channels: int, dtype: torch.dtype) -> torch.Tensor:
    key = (channels, dtype)
    if key not in _WINDOWS:
        g = torch.from_numpy(window_taps(np.dtype(np.float64)))
        w = (g[:, None] * g[None, :]).to(dtype)
        _WINDOWS[key] = w.expand(channels, 1, len(g), len(g)).contiguous()
    return _WINDOWS[key]


def ssim_loss(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """1 - SSIM of two [H, W, C] images (Gaussian window 11, sigma 1.5, zero padding): on CPU
    tensors with a target `b` that needs no gradient, the compiled `fused_ssim_loss` (7x faster at
    128 px, the same value to float rounding), else `conv_ssim_loss`."""
    if fused_ssim_applies(a, b):
        return fused_ssim_loss(a, b)
    return conv_ssim_loss(a, b)


def conv_ssim_loss(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """`ssim_loss` as torch convolutions (any device and dtype, gradients to both images)."""
    x = a.permute(2, 0, 1)[None]
    y = b.permute(2, 0, 1)[None]
    c = x.shape[1]
    w = _window(c, x.dtype)
    mx = F.conv2d(x, w, padding=WINDOW_RADIUS, groups=c)
    my = F.conv2d(y, w, padding=WINDOW_RADIUS, groups=c)
    sxx = F.conv2d(x * x, w, padding=WINDOW_RADIUS, groups=c) - mx * mx
    syy = F.conv2d(y * y, w, padding=WINDOW_RADIUS, groups=c) - my * my
    sxy = F.conv2d(x * y, w, padding=WINDOW_RADIUS, groups=c) - mx * my
    s = ((2 * mx * my + SSIM_C1) * (2 * sxy + SSIM_C2)) / ((mx * mx + my * my + SSIM_C1) * (sxx + syy + SSIM_C2))
    return 1.0 - s.mean()


def _where(mask: torch.Tensor) -> torch.Tensor | None:
    """The flat indices of a boolean mask's True pixels (None when there are none). Select them
    with `_pick` (`index_select`, whose backward sums in index order): one `nonzero` per mask,
    where boolean indexing runs one per selected tensor and another in its backward."""
    idx = torch.nonzero(mask.reshape(-1)).reshape(-1)
    return idx if len(idx) else None


def _pick(x: torch.Tensor, idx: torch.Tensor) -> torch.Tensor:
    return x.reshape(-1).index_select(0, idx)


def photometric_loss(pred: torch.Tensor, target: torch.Tensor, ssim_weight: float = 0.2) -> torch.Tensor:
    """(1 - w) L1 + w (1 - SSIM)."""
    return (1 - ssim_weight) * (pred - target).abs().mean() + ssim_weight * ssim_loss(pred, target)


def depth_loss(pred: torch.Tensor, target: torch.Tensor, alpha: torch.Tensor, trim: float = 0.0,
               weight: torch.Tensor | None = None) -> torch.Tensor:
    """Relative L1 depth error where the prior has a depth and the render is mostly opaque; with
    `trim` > 0 the largest `trim` fraction of the errors is left out (a trimmed mean: an imperfect
    prior's outliers, such as a wrong object depth or a mask a pixel off, do not pull the fit);
    `weight` [H, W] scales each pixel's error (its confidence)."""
    idx = _where((target > 0) & (alpha.detach() > 0.5))
    if idx is None:
        return pred.sum() * 0.0
    t = _pick(target, idx)
    err = (_pick(pred, idx) - t).abs() / t
    if weight is not None:
        err = err * _pick(weight, idx)
    if trim > 0 and err.numel() > 10:
        keep = max(1, int(round(err.numel() * (1.0 - trim))))
        err = torch.topk(err, keep, largest=False, sorted=False).values
    return err.mean()


def scale_shift_depth_loss(pred: torch.Tensor, target: torch.Tensor, alpha: torch.Tensor, groups: torch.Tensor,
                           weight: torch.Tensor | None = None, delta: float = 0.05, min_pixels: int = 8) -> torch.Tensor:
    """Scale- and shift-invariant depth term: within each group of pixels (`groups` [H, W] ids,
    one per instance; < 0 left out) the prior `target` [H, W] is aligned to the render by the
    (weighted) least-squares scale and shift (computed without gradient), and the render pays
    a Huber distance (`delta`, relative to the group's median depth) to the aligned prior. The
    render keeps the prior's shape (which part is nearer, how the ground recedes) without its
    scale, which an estimated depth often gets wrong per object. Pixels without a prior or
    mostly transparent are left out; groups under `min_pixels` pixels too. `weight` [H, W] are
    per-pixel confidences."""
    idx = _where((target > 0) & (alpha.detach() > 0.5) & (groups >= 0))
    if idx is None:
        return pred.sum() * 0.0
    # every group at once: per-group sums by index_add over the valid pixels' group ids (small
    # integers: an id no pixel has is a group of 0 pixels, which weighs nothing)
    inv = _pick(groups, idx).long()
    count = torch.bincount(inv)
    kept = count >= min_pixels
    if not kept.any():
        return pred.sum() * 0.0
    x, y = _pick(target, idx), _pick(pred, idx)
    w = (_pick(weight, idx) if weight is not None else torch.ones_like(x)).to(pred.dtype)

    def per_group(v: torch.Tensor) -> torch.Tensor:
        return torch.zeros(len(count), dtype=v.dtype).index_add(0, inv, v)

    with torch.no_grad():
        yd = y.detach()
        sw = per_group(w).clamp(min=1e-9)
        mx, my = per_group(w * x) / sw, per_group(w * yd) / sw
        dx = x - mx[inv]
        vx = per_group(w * dx ** 2) / sw
        cov = per_group(w * dx * (yd - my[inv])) / sw
        scale = torch.where(vx > 1e-10, (cov / vx.clamp(min=1e-10)).clamp(0.2, 5.0), torch.ones_like(vx))
        shift = my - scale * mx
        ref = my.abs().clamp(min=1e-6)
    r = (y - (scale[inv] * x + shift[inv])).abs() / ref[inv]
    hub = torch.where(r < delta, 0.5 * r * r / delta, r - 0.5 * delta)
    c = torch.where(kept, count, 0).to(pred.dtype)          # groups under min_pixels weigh 0
    return (per_group(hub * w) / sw * c).sum() / c.sum()


def mask_loss(soft: torch.Tensor, target_onehot: torch.Tensor, valid: torch.Tensor | None = None,
              weight: torch.Tensor | None = None) -> torch.Tensor:
    """MSE between rendered soft instance maps [H, W, K] and one-hot masks [H, W, K], over the
    `valid` [H, W] pixels (all by default), each weighted by its `weight` [H, W] (the mask
    prior's confidence; 1 by default)."""
    err = ((soft - target_onehot) ** 2).sum(-1) / soft.shape[-1]
    if weight is not None:
        err = err * weight
    if valid is None:
        return err.mean()
    idx = _where(valid)
    if idx is None:
        return soft.sum() * 0.0
    return _pick(err, idx).mean()


def mask_iou_loss(soft: torch.Tensor, target_onehot: torch.Tensor, valid: torch.Tensor | None = None,
                  weight: torch.Tensor | None = None) -> torch.Tensor:
    """1 - soft IoU (sum of minima over sum of maxima) of each instance's rendered map [H, W, K]
    with its mask [H, W, K], averaged over the instances present in the frame. Every instance
    weighs the same whatever its area, so the outline of a small object counts as much as the
    ground's (a pixel-mean loss barely sees it). Pixels count by their `weight` [H, W] in both
    sums (the mask prior's confidence; 1 by default)."""
    keep = None
    if valid is not None:
        keep = valid[..., None].to(soft.dtype)
    if weight is not None:
        keep = weight[..., None].to(soft.dtype) if keep is None else keep * weight[..., None].to(soft.dtype)
    if keep is not None:
        present_mask = (target_onehot * (valid[..., None] if valid is not None else 1.0)).sum(dim=(0, 1)) > 0
        soft, target_onehot = soft * keep, target_onehot * keep
    else:
        present_mask = target_onehot.sum(dim=(0, 1)) > 0
    present = present_mask & (target_onehot.sum(dim=(0, 1)) > 0)
    if not present.any():
        return soft.sum() * 0.0
    s = soft.clamp(0.0, 1.0)
    inter = torch.minimum(s, target_onehot).sum(dim=(0, 1))
    union = torch.maximum(s, target_onehot).sum(dim=(0, 1)).clamp(min=1e-6)
    weight = present.to(soft.dtype)                         # the mean over the instances present
    return ((1.0 - inter / union) * weight).sum() / weight.sum()


def empty_alpha_loss(alpha: torch.Tensor, empty: torch.Tensor) -> torch.Tensor:
    """Mean opacity over the pixels where the prior says nothing is drawn."""
    idx = _where(empty)
    if idx is None:
        return alpha.sum() * 0.0
    return _pick(alpha, idx).mean()


def track_loss(pred_uv: torch.Tensor, target_uv: torch.Tensor, visible: torch.Tensor, size: float,
               delta: float = 0.0, weight: torch.Tensor | None = None) -> torch.Tensor:
    """Mean distance (in units of the image size) of projected track points to their 2D tracks:
    L1 per coordinate, or with `delta` > 0 (pixels) Huber (quadratic below `delta`, so a
    track's pixel-level jitter is averaged rather than followed; linear above it, so a lost
    track pulls no harder than under L1). Each track counts by its `weight` [P] (its
    confidence; a weighted mean, 1 by default)."""
    if not visible.any():
        return pred_uv.sum() * 0.0
    r = (pred_uv[visible] - target_uv[visible]).abs()
    if delta > 0:
        r = torch.where(r < delta, 0.5 * r * r / delta, r - 0.5 * delta)
    per = r.sum(-1) / size
    if weight is None:
        return per.mean()
    w = (weight if visible.dim() == 1 else weight[:, None].expand_as(visible))[visible].to(per.dtype)
    return (per * w).sum() / w.sum().clamp(min=1e-6)


def arap_loss(node_pos_t: torch.Tensor, node_pos_0: torch.Tensor, pairs: torch.Tensor) -> torch.Tensor:
    """As-rigid-as-possible: distances between neighbouring nodes [P, 2] keep their canonical length."""
    if pairs.numel() == 0:
        return node_pos_t.sum() * 0.0
    d_t = (gather_rows(node_pos_t, pairs[:, 0]) - gather_rows(node_pos_t, pairs[:, 1])).norm(dim=-1)
    d_0 = (node_pos_0[pairs[:, 0]] - node_pos_0[pairs[:, 1]]).norm(dim=-1)
    return ((d_t - d_0) ** 2).mean()


def smooth_motion_loss(node_quats: torch.Tensor, node_trans: torch.Tensor, frames: torch.Tensor) -> torch.Tensor:
    """Second differences of node translations and rotations around the given frames [F] (1..T-2).
    `DynamicGaussians.node_trans` are the node centres' displacements, so this smooths each
    centre's path (not a translation about the world origin, which a turn changes too)."""
    if node_trans.shape[1] == 0 or frames.numel() == 0:
        return node_trans.sum() * 0.0
    a, b, c = frames - 1, frames, frames + 1
    acc_t = node_trans[a] - 2 * node_trans[b] + node_trans[c]
    q = node_quats / node_quats.norm(dim=-1, keepdim=True)
    acc_q = q[a] - 2 * q[b] + q[c]
    return (acc_t ** 2).sum(-1).mean() + (acc_q ** 2).sum(-1).mean()


def psnr_torch(a: torch.Tensor, b: torch.Tensor) -> float:
    """PSNR in dB of two images in [0, 1]."""
    mse = float(((a - b) ** 2).mean())
    return float("inf") if mse == 0 else 10.0 * float(torch.log10(torch.tensor(1.0 / mse)))
