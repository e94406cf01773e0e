"""Latents of Gaussians no supervised pixel reached come from their nearest supervised neighbours."""

import numpy as np
import torch

import morphosim_gym as ms
from morphosim_gym.reconstruct.features import _fill_unseen
from morphosim_gym.reconstruct.initialize import initialize


def _model():
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=48, height=48, num_frames=9, detail=0.5),
                       reconstruction="oracle")
    clip = sim.generate_clip("The bus is moving from right to left", seed=0)
    model = initialize(clip, seed=0).model
    rng = np.random.default_rng(0)
    model.features = torch.nn.Parameter(torch.as_tensor(rng.normal(size=(model.num, 4)), dtype=torch.float32))
    return model, rng


def test_unreached_latents_take_their_neighbours_mean():
    model, rng = _model()
    reached = rng.uniform(0.5, 2.0, model.num)
    unseen = rng.random(model.num) < 0.1
    reached[unseen] = 0.0
    reached[np.flatnonzero(unseen)[:3]] = 1e-6          # a trace of supervision counts as none
    before = model.features.detach().numpy().copy()
    assert _fill_unseen(model, reached, k=4, frame=4) == unseen.sum()
    after = model.features.detach().numpy()
    np.testing.assert_array_equal(after[~unseen], before[~unseen])
    means = model.warp(4)[0].detach().numpy()
    seen_idx = np.flatnonzero(~unseen)
    for i in np.flatnonzero(unseen)[:20]:
        nearest = seen_idx[np.argsort(np.linalg.norm(means[seen_idx] - means[i], axis=1))[:4]]
        np.testing.assert_allclose(after[i], before[nearest].mean(0), rtol=1e-5, atol=1e-6)


def test_nothing_to_fill_changes_nothing():
    model, _ = _model()
    before = model.features.detach().numpy().copy()
    assert _fill_unseen(model, np.ones(model.num), k=4, frame=0) == 0
    assert _fill_unseen(model, np.zeros(model.num), k=4, frame=0) == 0       # no supervision at all: nothing to copy
    np.testing.assert_array_equal(model.features.detach().numpy(), before)


def test_encoder_maps_at_reduced_resolution():
    """The feature targets at the reduced pixels: the map itself at full resolution (no copy of a
    per-pixel embedding map), the pixels under each reduced pixel's centre otherwise."""
    from morphosim_gym.reconstruct.features import _at_pixels

    a = np.arange(6 * 8 * 2, dtype=np.float32).reshape(6, 8, 2)
    full = _at_pixels(a, np.arange(6), np.arange(8))
    assert full is a
    rows, cols = np.array([0, 2, 5]), np.array([1, 1, 7])
    got = _at_pixels(a, rows, cols)
    assert got.flags.c_contiguous and np.array_equal(got, a[rows][:, cols])
    assert np.array_equal(_at_pixels(a[..., 0], rows, cols), a[rows][:, cols][..., 0])
