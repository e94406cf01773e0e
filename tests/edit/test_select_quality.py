"""Selections measured where they are seen: rendered against 2D masks (edit.select_quality)."""

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.edit.select_quality import rendered_selection, selection_against_masks

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
