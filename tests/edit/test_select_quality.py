"""Selections measured where they are seen: rendered against 2D masks (edit.select_quality)."""

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.edit.select_quality import rendered_selection, selection_against_masks, share_masks

SMALL = ms.GenerationConfig(width=48, height=48, num_frames=5, detail=0.5)


@pytest.fixture(scope="module")
def clip():
    return ms.MorphoSim(generation=SMALL, reconstruction="oracle").generate_clip("The bus is moving from right to left", 0)


def _views(clip):
    frames = list(range(clip.num_frames))
    return [clip.cameras[i] for i in frames], [i / clip.fps for i in frames]


def test_the_objects_own_gaussians_cover_its_mask_and_nothing_else(clip):
    scene = clip.ground_truth
    cams, times = _views(clip)
    bus = scene.object("bus").id
    inst = next(k for k, v in clip.labels.items() if v == "bus")
    own = selection_against_masks(scene, scene.gaussians.object_ids == bus, cams, times, clip.masks == inst)
    # at 48 px the bus's 1-px rim decides (the clip's masks come from a per-pixel rule of their own): 0.91 / 0.99
    assert own["precision"] > 0.88 and own["recall"] > 0.95
    # the road's Gaussians do not cover the bus; nothing selected is precision 1 (no false pixel), recall 0
    road = selection_against_masks(scene, scene.gaussians.object_ids != bus, cams, times, clip.masks == inst)
    assert road["precision"] < 0.05 and road["recall"] < 0.05
    none = selection_against_masks(scene, np.zeros(len(scene.gaussians), bool), cams, times, clip.masks == inst)
    assert none == {"precision": 1.0, "recall": 0.0}


def test_occluded_gaussians_count_only_as_far_as_they_show(clip):
    scene = clip.ground_truth
    road = scene.gaussians.object_ids == scene.object("road").id
    share = rendered_selection(scene, road, clip.cameras[0], 0.0)
    inst = next(k for k, v in clip.labels.items() if v == "bus")
    assert share[clip.masks[0] == inst].mean() < 0.1          # the road under the bus is hidden by it
    assert share[clip.masks[0] == next(k for k, v in clip.labels.items() if v == "road")].mean() > 0.9


def test_bad_input_names_the_problem(clip):
    scene = clip.ground_truth
    cams, times = _views(clip)
    sel = np.ones(len(scene.gaussians), bool)
    with pytest.raises(ValueError, match="selection mask of shape"):
        rendered_selection(scene, sel[:-1], cams[0], 0.0)
    with pytest.raises(ValueError, match="bool"):
        selection_against_masks(scene, sel, cams, times, clip.masks)
    with pytest.raises(ValueError, match="one camera and one time per mask"):
        selection_against_masks(scene, sel, cams[:2], times, clip.masks >= 0)
    with pytest.raises(ValueError, match="camera's size"):
        selection_against_masks(scene, sel, cams, times, (clip.masks >= 0)[:, :10])


def test_share_masks_are_what_the_exact_selection_meets(clip):
    scene = clip.ground_truth
    cams, times = _views(clip)
    bus = scene.object("bus").id
    inst = next(k for k, v in clip.labels.items() if v == "bus")
    truth = share_masks(scene, [bus], cams, times)
    assert truth.shape == clip.masks.shape and truth.dtype == bool
    exact = scene.gaussians.object_ids == bus
    assert selection_against_masks(scene, exact, cams, times, truth) == {"precision": 1.0, "recall": 1.0}
    # the clip's instance masks (largest single weight) leave out rim pixels where the bus gives
    # more than half the colour: the share masks hold them and little else
    rims = truth & ~(clip.masks == inst)
    assert rims.sum() > 0 and ((clip.masks == inst) & ~truth).sum() <= rims.sum()
    assert 0.85 < (truth & (clip.masks == inst)).sum() / truth.sum() < 1.0
    # the road's and the bus's masks do not overlap; the road's nearly equals its instance mask
    road = share_masks(scene, [scene.object("road").id], cams, times)
    road_inst = clip.masks == next(k for k, v in clip.labels.items() if v == "road")
    assert not (road & truth).any() and (road & road_inst).sum() / (road | road_inst).sum() > 0.97
    with pytest.raises(ValueError, match="object ids"):
        share_masks(scene, [10_000], cams, times)
    with pytest.raises(ValueError, match="one time per camera"):
        share_masks(scene, [bus], cams, times[:1])
