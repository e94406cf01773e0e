"""Completion of what a monocular clip never shows: the ground plane prior and its budget."""

import numpy as np
import pytest
import torch

import morphosim_gym as ms
from morphosim_gym.reconstruct.completion import _near_cameras, complete, fit_ground_plane
from morphosim_gym.reconstruct.initialize import initialize

SMALL = ms.GenerationConfig(width=48, height=48, num_frames=9, detail=0.5)


@pytest.fixture(scope="module")
def clip():
    sim = ms.MorphoSim(generation=SMALL, reconstruction="oracle")
    return sim.generate_clip("A car is moving from right to left through a serene sunlit landscape", seed=0)


def test_ground_plane_fit_ignores_outliers():
    rng = np.random.default_rng(0)
    xy = rng.uniform(-5, 5, (400, 2))
    n_true = np.array([0.1, -0.05, 1.0]) / np.linalg.norm([0.1, -0.05, 1.0])
    z = (0.3 - n_true[0] * xy[:, 0] - n_true[1] * xy[:, 1]) / n_true[2]
    pts = np.c_[xy, z]
    pts[:80, 2] += rng.uniform(0.5, 3.0, 80)             # things standing on the ground
    n, d, inliers = fit_ground_plane(pts, rng)
    assert np.dot(n, n_true) > 0.999 and abs(d - 0.3) < 0.01
    assert inliers[80:].all() and not inliers[:80].any()
    with pytest.raises(ValueError, match="at least 3 points"):
        fit_ground_plane(pts[:2], rng)


def _complete_ground(clip, budget):
    model = initialize(clip, seed=0).model
    first = model.num
    with torch.no_grad():
        seen = model.means.numpy().copy()
    counts = complete(model, clip, {0: False, 1: True}, seed=0, max_ground=budget)
    with torch.no_grad():
        added = model.means.numpy()[first:first + counts["ground"]]
    return model, first, seen, added


def test_ground_reaches_out_within_its_budget(clip):
    reach = {}
    for budget in (600, 6000):
        model, first, seen, added = _complete_ground(clip, budget)
        assert 0 < len(added) <= budget * 1.5            # splitting near the cameras adds a few
        lo, hi = seen[:, :2].min(0), seen[:, :2].max(0)
        # the ground continues beyond everything seen, on every side
        assert np.all(added[:, :2].min(0) < lo - 0.25 * (hi - lo)) and np.all(added[:, :2].max(0) > hi + 0.25 * (hi - lo))
        reach[budget] = np.abs(added[:, :2]).max()
        # no added disc is left straddling an input camera's plane inside its view
        near, in_view = _near_cameras(model, clip, first)
        assert not near.any() and not in_view.any()
    # a small budget coarsens the cells instead of dropping the outer rings
    assert reach[600] > 0.8 * reach[6000]


def test_far_sides_seen_by_the_input_views_are_dropped(clip):
    model = initialize(clip, seed=0).model
    counts = complete(model, clip, {0: False, 1: True}, seed=0)
    assert counts["symmetry"] > 0
    # the mirrored far side of the car keeps the car's id and sits behind it, as seen from the camera
    ids = model.object_ids.numpy()
    with torch.no_grad():
        means = model.means.numpy()
    car = np.flatnonzero(ids == 1)
    cam = clip.cameras[0]
    depth = means[car] @ cam.world_to_camera[2, :3] + cam.world_to_camera[2, 3]
    mirrored = car[-counts["symmetry"]:] if counts["symmetry"] else car[:0]
    assert np.median(depth[np.isin(car, mirrored)]) > np.median(depth[~np.isin(car, mirrored)])
