"""Mask losses of the fit: the pixel-mean MSE and the per-instance soft IoU."""

import pytest
import torch

from morphosim_gym.reconstruct.losses import mask_iou_loss, mask_loss


def _maps():
    target = torch.zeros(32, 32, 2)
    target[..., 0] = 1.0
    target[10:14, 10:14, 0] = 0.0
    target[10:14, 10:14, 1] = 1.0                      # a 16-pixel object on a large ground
    return target


def test_perfect_maps_cost_nothing():
    t = _maps()
    assert mask_iou_loss(t.clone(), t).item() == 0.0 and mask_loss(t.clone(), t).item() == 0.0


def test_small_objects_weigh_as_much_as_the_ground():
    t = _maps()
    miss = t.clone()
    miss[10:14, 10:12, 1] = 0.0                          # half of the small object missed
    miss[10:14, 10:12, 0] = 1.0
    # the pixel-mean loss barely notices; the per-instance IoU loses a quarter for that object
    assert mask_loss(miss, t).item() < 0.01
    iou = mask_iou_loss(miss, t).item()
    assert 0.2 < iou < 0.3
    # instances absent from the frame do not count, and invalid pixels are ignored
    t3, m3 = torch.cat([t, torch.zeros(32, 32, 1)], -1), torch.cat([miss, torch.zeros(32, 32, 1)], -1)
    assert abs(mask_iou_loss(m3, t3).item() - iou) < 1e-6
    valid = torch.ones(32, 32, dtype=torch.bool)
    valid[10:14, 10:12] = False
    assert mask_iou_loss(miss, t, valid).item() < 1e-6


def test_gradients_reach_the_rendered_maps():
    t = _maps()
    soft = (t * 0.8 + 0.1).requires_grad_(True)
    mask_iou_loss(soft, t).backward()
    assert soft.grad is not None and soft.grad.abs().sum() > 0


def test_covering_more_than_the_object_costs():
    # the union term: a map that also covers pixels outside the object is charged for them
    t = _maps()
    over = t.clone()
    over[..., 1] = 1.0                                   # the small object's map covers the whole frame
    loss = mask_iou_loss(over, t).item()
    # object: IoU 16 / 1024; ground: untouched, IoU 1
    expected = (1 - 16 / 1024) / 2
    assert abs(loss - expected) < 1e-4 and loss > 0.45


def test_scale_shift_depth_is_blind_to_scale_and_shift_only():
    from morphosim_gym.reconstruct.losses import scale_shift_depth_loss

    rows = torch.linspace(2.0, 6.0, 16)[:, None].expand(16, 16).clone()       # a receding ground
    groups = torch.zeros(16, 16, dtype=torch.long)
    alpha = torch.ones(16, 16)
    # the prior at the wrong scale and offset: no penalty (the shape is right)
    assert scale_shift_depth_loss(rows, 0.5 * rows + 1.0, alpha, groups) == pytest.approx(0.0, abs=1e-6)
    # the wrong shape (the ground flipped) pays, and a gradient step moves the render towards it
    flipped = rows.flip(0)
    pred = rows.clone().requires_grad_(True)
    loss = scale_shift_depth_loss(pred, flipped, alpha, groups)
    assert loss > 0.01
    loss.backward()
    step = pred.detach() - 1.0 * pred.grad
    assert scale_shift_depth_loss(step, flipped, alpha, groups) < loss
    # groups are aligned separately: two objects, each with its own scale, pay nothing
    g2 = groups.clone()
    g2[:, 8:] = 1
    two = torch.where(g2 == 1, 3.0 * rows, rows)
    assert scale_shift_depth_loss(rows, two, alpha, g2) == pytest.approx(0.0, abs=1e-6)
    assert scale_shift_depth_loss(rows, two, alpha, groups) > 0.01
    # a group under min_pixels is left out: 4 pixels of another id that no scale fits
    g3 = groups.clone()
    g3[0, :4] = 5
    odd = rows.clone()
    odd[0, :4] = torch.tensor([9.0, 1.0, 9.0, 1.0])
    assert scale_shift_depth_loss(rows, odd, alpha, g3, min_pixels=8) == pytest.approx(0.0, abs=1e-6)
    assert scale_shift_depth_loss(rows, odd, alpha, g3, min_pixels=4) > 1e-3


def test_scale_shift_depth_weighs_each_group_by_its_pixels():
    """The loss against a plain loop over the groups (each group's weighted least-squares scale
    and shift, a weighted mean Huber term, groups weighted by their pixel counts), with weights,
    pixels left out and a group too small."""
    from morphosim_gym.reconstruct.losses import scale_shift_depth_loss

    gen = torch.Generator().manual_seed(0)
    target = torch.rand(24, 24, generator=gen) * 4 + 1
    target[torch.rand(24, 24, generator=gen) < 0.1] = 0                # no prior there
    alpha = torch.rand(24, 24, generator=gen)
    groups = torch.randint(-1, 3, (24, 24), generator=gen)
    groups[0, :3] = 7                                                  # 3 pixels: under min_pixels
    weight = torch.rand(24, 24, generator=gen)
    pred = target * (1 + 0.2 * torch.randn(24, 24, generator=gen))
    valid = (target > 0) & (alpha > 0.5) & (groups >= 0)
    terms, counts = [], []
    for g in torch.unique(groups[valid]).tolist():
        sel = valid & (groups == g)
        if sel.sum() < 8:
            continue
        x, y, w = target[sel].double(), pred[sel].double(), weight[sel].double()
        mx, my = (w * x).sum() / w.sum(), (w * y).sum() / w.sum()
        scale = ((w * (x - mx) * (y - my)).sum() / (w * (x - mx) ** 2).sum()).clamp(0.2, 5.0)
        r = (y - (scale * x + my - scale * mx)).abs() / my.abs()
        hub = torch.where(r < 0.05, 0.5 * r * r / 0.05, r - 0.025)
        terms.append((hub * w).sum() / w.sum())
        counts.append(float(sel.sum()))
    want = sum(t * c for t, c in zip(terms, counts)) / sum(counts)
    assert len(terms) == 3
    assert scale_shift_depth_loss(pred, target, alpha, groups, weight=weight).item() == pytest.approx(want.item(), rel=1e-5)
