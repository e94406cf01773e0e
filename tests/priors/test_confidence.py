"""Confidences of the priors: a mask's outline and jumpy tracks count less; exact renders fully."""

import numpy as np
import pytest
import torch

from morphosim_gym.priors import mask_confidence, prior_confidences, track_confidence
from morphosim_gym.reconstruct.losses import mask_iou_loss, mask_loss, track_loss


def test_mask_confidence_is_low_on_the_outline_and_full_inside():
    m = np.full((1, 20, 20), 0, np.int32)
    m[0, 5:15, 5:15] = 1
    c = mask_confidence(m, radius=2.0, floor=0.25)
    assert c[0, 10, 10] == 1.0 and c[0, 1, 1] == 1.0          # deep inside either region
    assert c[0, 5, 10] == 0.25 and c[0, 4, 10] == 0.25        # either side of the outline
    assert c[0, 6, 10] == pytest.approx(0.5, abs=0.03) and c[0, 3, 10] == pytest.approx(0.5, abs=0.03)  # 1 px off
    assert c.min() >= 0.25


def test_a_jumpy_track_gets_a_low_weight():
    t = np.arange(9, dtype=np.float32)
    smooth = np.stack([t, 2 * t], -1)
    tracks = np.stack([smooth + k for k in range(10)])
    tracks[3, 5] += (8.0, 0.0)                 # one track jumps 8 px at frame 5 and back
    w = track_confidence(tracks, np.ones(tracks.shape[:2], bool))
    assert w[3] < 0.1 and np.all(np.delete(w, 3) > 0.9)


def test_exact_tracks_get_no_weights_exact_masks_outline_weights_and_corrupted_ones_both():
    import morphosim_gym as ms
    from morphosim_gym.priors import corrupt_priors, prepare_priors

    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=32, height=32, num_frames=5, detail=0.3))
    clip = sim.generate_clip("The bus is moving from right to left", seed=0)
    exact_masks, exact_tracks = prior_confidences(prepare_priors(clip, "ground_truth"))
    assert exact_tracks is None and np.array_equal(exact_masks, mask_confidence(clip.masks))
    bad = prepare_priors(corrupt_priors(clip, 0), "ground_truth")
    assert bad.info["priors"]["masks"] == "corrupted"
    masks, tracks = prior_confidences(bad)
    assert masks.shape == clip.masks.shape and masks.min() < 1.0 and tracks.shape == (len(clip.tracks),)


def test_the_losses_use_the_weights():
    soft = torch.zeros(4, 4, 1)
    target = torch.zeros(4, 4, 1)
    target[0, 0] = 1.0                          # one wrong pixel
    w = torch.ones(4, 4)
    assert mask_loss(soft, target, weight=w) > 0
    w[0, 0] = 0.0
    assert mask_loss(soft, target, weight=w) == 0
    soft2 = target.clone()
    soft2[1, 1] = 1.0                           # a false positive the weight silences
    w2 = torch.ones(4, 4)
    w2[1, 1] = 0.0
    assert mask_iou_loss(soft2, target, weight=w2) == pytest.approx(0.0)
    assert mask_iou_loss(soft2, target) == pytest.approx(0.5)
    pred = torch.zeros(2, 2)
    tgt = torch.tensor([[0.0, 0.0], [10.0, 0.0]])       # the second track is 10 px off
    vis = torch.ones(2, dtype=torch.bool)
    assert track_loss(pred, tgt, vis, 10.0, weight=torch.tensor([1.0, 0.0])) == 0
    assert track_loss(pred, tgt, vis, 10.0, weight=torch.tensor([1.0, 1.0])) == pytest.approx(0.5)
