"""The 4D fit: settings checks and the learning-rate decay that lets node poses settle."""

from dataclasses import replace

import numpy as np
import pytest
import torch

import morphosim_gym as ms
from morphosim_gym.reconstruct.fit import FitConfig, fit
from morphosim_gym.reconstruct.initialize import initialize
from morphosim_gym.reconstruct.lifting import estimate_background_color


@pytest.fixture(scope="module")
def clip():
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=48, height=48, num_frames=9, detail=0.5),
                       reconstruction="oracle")
    return sim.generate_clip("The bus is moving from right to left", seed=0)


def _pose_jitter(clip, lr_decay: float) -> float:
    """Mean frame-to-frame second difference, in pixels, of the fitted node centres' image
    positions (the bus drives at a steady speed, so a settled fit has almost none)."""
    init = initialize(clip, seed=0)
    model = init.model
    cfg = FitConfig(iterations=100, lr_decay=lr_decay, progress=False)
    fit(model, clip, init.reference, init.dynamic, cfg, seed=0, background=estimate_background_color(clip))
    centres = model.node_centres
    with torch.no_grad():
        px = np.stack([cam.project(model.points_at(centres, torch.arange(len(centres))[:, None],
                                                   torch.ones(len(centres), 1), t).numpy())[0]
                       for t, cam in enumerate(clip.cameras)])
    return float(np.linalg.norm(px[:-2] - 2 * px[1:-1] + px[2:], axis=-1).mean())


def test_decaying_learning_rate_settles_the_node_poses(clip):
    constant = _pose_jitter(clip, lr_decay=1.0)
    decayed = _pose_jitter(clip, lr_decay=0.03)
    assert decayed < 0.75 * constant, (decayed, constant)


@pytest.mark.parametrize("change, message", [(dict(iterations=0), "at least 1 fit iteration"),
                                              (dict(lr_decay=0.0), "lr_decay in \\(0, 1\\]"),
                                              (dict(lr_decay=1.5), "lr_decay in \\(0, 1\\]")])
def test_bad_settings_are_named(change, message):
    with pytest.raises(ValueError, match=message):
        replace(FitConfig(), **change)
