"""The feature field's instance channel: objects that share a label stay apart in selections."""

from dataclasses import replace

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.edit.select import Selector
from morphosim_gym.edit.select_quality import selection_against_masks
from morphosim_gym.reconstruct import ReconstructionConfig, reconstruct
from morphosim_gym.reconstruct.features import FeatureConfig, InstanceCodeEncoder
from morphosim_gym.reconstruct.fit import FitConfig
from morphosim_gym.scene import instance_codes

SMALL = ms.GenerationConfig(width=48, height=48, num_frames=9, detail=0.5)
FAST = ReconstructionConfig(fit=FitConfig(iterations=120, progress=False),
                            features=FeatureConfig(iterations=60, progress=False), progress=False, cache=False)


@pytest.fixture(scope="module")
def clip():
    return ms.MorphoSim(generation=SMALL, reconstruction="oracle").generate_clip(
        "two sheep walk across the field from left to right", seed=0)


def _sheep_2(scene, clip):
    """Selection of "sheep 2": share of each sheep's Gaussians taken, and pixel precision / recall."""
    ids = scene.gaussians.object_ids
    two = scene.object("sheep 2").id
    sel = Selector().select(scene, [two], "sheep 2")
    frames = range(clip.num_frames)
    inst = [k for k, v in clip.labels.items() if v == "sheep 2"]
    pr = selection_against_masks(scene, sel.mask, [clip.cameras[i] for i in frames], [i / clip.fps for i in frames],
                                 np.isin(clip.masks, inst))
    taken = {o.name: float(sel.mask[ids == o.id].mean()) for o in scene.objects}
    return taken, pr


def test_codes_are_unit_vectors_and_the_first_ones_orthogonal():
    c = instance_codes([0, 1, 2, 40, -3])
    np.testing.assert_allclose(np.linalg.norm(c, axis=1), 1.0, rtol=1e-6)
    np.testing.assert_array_equal(c[:3], np.eye(16, dtype=np.float32)[:3])
    np.testing.assert_array_equal(instance_codes([40]), c[3:4])          # fixed per id
    with pytest.raises(ValueError, match="width"):
        instance_codes([0], dim=0)


def test_the_encoder_paints_each_instance_its_code(clip):
    feat, valid = InstanceCodeEncoder().encode(clip, 0)
    for inst in np.unique(clip.masks[0]):
        if inst >= 0:
            np.testing.assert_array_equal(feat[clip.masks[0] == inst], np.broadcast_to(instance_codes([inst])[0],
                                                                                        ((clip.masks[0] == inst).sum(), 16)))
    assert (valid == (clip.masks[0] >= 0)).all()


def test_two_sheep_are_selected_apart(clip):
    scene = reconstruct(clip, FAST)
    assert "instance" in scene.decoders
    taken, pr = _sheep_2(scene, clip)
    # (a fifth of sheep 2's Gaussians, under it and hidden in every frame, read as grass: the pixels count)
    assert taken["sheep 1"] < 0.05 and taken["sheep 2"] > 0.7, taken
    assert pr["precision"] > 0.9 and pr["recall"] > 0.9, pr
    # without the channel the names cannot tell them apart ("sheep 1" and "sheep 2" embed 0.89 alike)
    names_only = reconstruct(clip, replace(FAST, features=replace(FAST.features, encoders=("semantic", "color"))))
    taken, pr = _sheep_2(names_only, clip)
    assert taken["sheep 1"] > 0.5 and pr["precision"] < 0.8, (taken, pr)
