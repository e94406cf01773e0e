"""Mask losses of the fit: the pixel-mean MSE and the per-instance soft IoU."""

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
