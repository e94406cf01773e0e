"""Realistic errors on a clip's priors (`priors.corrupt_priors`), one kind at a time."""

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.priors import corrupt_priors

NONE = dict(depth_field=0.0, depth_noise=0.0, mask_pixels=0, mask_drop=0.0, track_noise=0.0, track_drop=0.0)


@pytest.fixture(scope="module")
def clip():
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=32, height=32, num_frames=5, detail=0.3))
    return sim.generate_clip("The bus is moving from right to left", seed=0)


def test_each_kind_of_error_alone(clip):
    same = corrupt_priors(clip, 0, **NONE)
    np.testing.assert_array_equal(same.masks, clip.masks)
    np.testing.assert_allclose(same.depth, clip.depth)
    np.testing.assert_array_equal(same.tracks, clip.tracks)
    masks = corrupt_priors(clip, 0, **{**NONE, "mask_pixels": 2})
    assert (masks.masks != clip.masks).any()
    np.testing.assert_allclose(masks.depth, clip.depth)
    depth = corrupt_priors(clip, 0, **{**NONE, "depth_field": 0.1})
    assert not np.allclose(depth.depth, clip.depth)
    np.testing.assert_array_equal(depth.masks, clip.masks)


@pytest.mark.parametrize("name", sorted(NONE))
def test_a_negative_amount_names_itself(clip, name):
    with pytest.raises(ValueError, match=name):
        corrupt_priors(clip, 0, **{**NONE, name: -1})


def test_objects_grow_in_some_frames_and_shrink_in_others():
    # before, the ground's dilation ate into every object in a "grow" frame: objects only shrank
    # (the example plate kept 0.79 of its area on average)
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=48, height=48, num_frames=12, detail=0.3))
    clip = sim.generate_clip("The bus is moving from right to left", seed=0)
    bus = next(i for i, n in clip.labels.items() if n == "bus")
    out = corrupt_priors(clip, 0, **{**NONE, "mask_pixels": 2})
    ratio = (out.masks == bus).reshape(12, -1).sum(1) / (clip.masks == bus).reshape(12, -1).sum(1)
    assert (ratio > 1.05).sum() >= 3 and (ratio < 0.95).sum() >= 3
    assert np.all(np.abs(ratio - 1.0) > 0.05)          # every frame's outline moved
    # a grown frame keeps every pixel of the bus, a shrunk one gives it none that it did not have
    grown, shrunk = int(np.argmax(ratio)), int(np.argmin(ratio))
    assert (out.masks[grown] == bus)[clip.masks[grown] == bus].all()
    assert not ((out.masks[shrunk] == bus) & (clip.masks[shrunk] != bus)).any()
