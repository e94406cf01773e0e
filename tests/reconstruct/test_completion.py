"""Completion of what a monocular clip never shows: the ground plane prior, its budget and its end, and the
backdrop prior."""

from dataclasses import replace

import numpy as np
import pytest
import torch

import morphosim_gym as ms
from morphosim_gym.language.vocabulary import word_to_setting
from morphosim_gym.reconstruct.completion import (
    _near_cameras,
    complete,
    find_backdrop,
    fit_backdrop_plane,
    fit_ground_plane,
    ground_reach,
    seen_through,
)
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


def _complete_ground(clip, budget, dynamic=None):
    model = initialize(clip, seed=0).model
    first = model.num
    with torch.no_grad():
        seen = model.means.numpy().copy()
    counts = complete(model, clip, dynamic or {0: False, 1: True}, seed=0, max_ground=budget)
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


def test_ground_ends_where_the_views_show_it_end(clip):
    """Underwater, the floor is a disc whose far edge the camera sees against empty water: the
    completed floor stops there on every side instead of running on for three extents. On the
    car's field, hills hide the ground's end: it still runs on."""
    # at 96 px the initial fit's ground reaches far enough to meet the free space the views show
    sim = ms.MorphoSim(generation=replace(SMALL, width=96, height=96), reconstruction="oracle")
    fish = sim.generate_clip("The fish swims through the crystal-clear waters from right to left", seed=0)
    gt = fish.ground_truth
    floor = gt.gaussians.means[gt.gaussians.object_ids == gt.object("water").id]
    radius = np.linalg.norm(floor[:, :2], axis=1).max()
    _, _, _, added = _complete_ground(fish, 6000, dynamic={0: False, 1: True, 2: False})
    assert len(added) > 0 and np.linalg.norm(added[:, :2], axis=1).max() < 1.1 * radius
    up, e1, e2 = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    # empty pixels past the disc's edge meet the plane just beyond it: the ground ends where seen
    assert ground_reach(fish, up, 0.0, e1, e2, np.zeros(2), seen=1.1 * radius) == 1.1 * radius
    # seen only near the objects, the free space bounds it: past the disc, not far past
    assert radius < ground_reach(fish, up, 0.0, e1, e2, np.zeros(2), seen=0.2 * radius) < 2.0 * radius
    assert ground_reach(clip, up, 0.0, e1, e2, np.zeros(2), seen=radius) > 3.0 * radius


def test_backdrop_plane_fit_ignores_outliers():
    rng = np.random.default_rng(0)
    n_true = np.array([0.3, -1.0, 0.0]) / np.linalg.norm([0.3, -1.0])
    along = np.array([-n_true[1], n_true[0], 0.0])
    wall = 4.0 * n_true + rng.uniform(-5, 5, (300, 1)) * along + rng.uniform(0, 2, (300, 1)) * [0.0, 0.0, 1.0]
    clutter = rng.uniform(-5, 5, (100, 3))               # rocks and plants in front of it
    n, d, inliers = fit_backdrop_plane(np.concatenate([wall, clutter]), rng)
    assert abs(n[2]) == 0.0 and abs(np.dot(n, n_true)) > 0.999 and abs(abs(d) - 4.0) < 0.01
    assert inliers[:300].all() and inliers[300:].sum() < 10
    with pytest.raises(ValueError, match="at least 2 points"):
        fit_backdrop_plane(wall[:1], rng)


@pytest.fixture(scope="module")
def mug():
    sim = ms.MorphoSim(generation=SMALL, reconstruction="oracle")
    return sim.generate_clip("a blue mug slides slowly across the table from left to right", seed=0)


def _background(clip):
    return {i for i, name in clip.labels.items() if word_to_setting(name.lower())}


def test_backdrop_continues_sideways_up_to_the_height_seen(mug):
    """The table's wall, seen only behind the mug, continues on both sides (a novel view turned
    sideways finds wall, not the void), on its plane, no higher than it was seen, in its colour."""
    model = initialize(mug, seed=0).model
    backdrop = find_backdrop(model, {0: False, 1: True}, _background(mug), np.random.default_rng(0))
    assert backdrop is not None and abs(backdrop.normal[1]) > 0.99     # the generator's wall faces -y
    with torch.no_grad():
        seen = model.means.numpy()[backdrop.inliers]
        seen_rgb = model.colors().numpy()[backdrop.inliers]
    with torch.no_grad():
        centre = np.median(model.means.numpy()[model.object_ids.numpy() == 1], axis=0)
        before = model.means.numpy()[model.object_ids.numpy() == 0]
    first = len(model.means)
    counts = complete(model, mug, {0: False, 1: True}, seed=0)
    assert counts["backdrop"] > 0
    # the ground ends not far behind the wall (the table's disc, seen up to its edge, is no farther)
    with torch.no_grad():
        ground = model.means.numpy()[first:first + counts["ground"]]
    seen_reach = np.linalg.norm(before[:, :2] - centre[:2], axis=1).max()
    assert np.linalg.norm(ground[:, :2] - centre[:2], axis=1).max() < 1.1 * max(1.5 * backdrop.distance, seen_reach)
    start = len(model.means) - counts["symmetry"] - counts["backdrop"]
    with torch.no_grad():
        added = model.means.numpy()[start:start + counts["backdrop"]]
        rgb = model.colors().numpy()[start:start + counts["backdrop"]]
    assert np.all(np.abs(added @ backdrop.normal - backdrop.offset) < 0.05)
    width = np.ptp(seen[:, 0])
    assert added[:, 0].min() < seen[:, 0].min() - 0.5 * width and added[:, 0].max() > seen[:, 0].max() + 0.5 * width
    assert added[:, 2].max() < seen[:, 2].max() + 0.05 * width
    assert np.abs(np.median(rgb, 0) - np.median(seen_rgb, 0)).max() < 0.1
    assert model.object_ids[start:start + counts["backdrop"]].unique().tolist() == sorted(_background(mug))


def test_sideways_gaussians_off_any_plane_are_no_backdrop(mug):
    model = initialize(mug, seed=0).model
    backdrop = find_backdrop(model, {0: False, 1: True}, _background(mug), np.random.default_rng(0))
    # a static object is never a backdrop, however flat (the wall, were it not the setting's)
    assert find_backdrop(model, {0: False, 1: True}, set(), np.random.default_rng(0)) is None
    with torch.no_grad():                            # scatter the wall over the room
        lo, hi = model.means.min(0).values, model.means.max(0).values
        g = torch.Generator().manual_seed(0)
        model.means[backdrop.inliers] = lo + (hi - lo) * torch.rand(len(backdrop.inliers), 3, generator=g)
    assert find_backdrop(model, {0: False, 1: True}, _background(mug), np.random.default_rng(0)) is None


def test_points_an_input_view_sees_past_are_seen_through(mug):
    cam, depth = mug.cameras[0], mug.depth[0]
    rows, cols = np.nonzero((depth > 0) & np.isin(mug.masks[0], list(_background(mug))))   # the still table and wall
    uv = np.c_[cols, rows] + 0.5
    front = cam.unproject(uv, 0.5 * depth[rows, cols])      # in the free space the view looks through
    behind = cam.unproject(uv, 1.5 * depth[rows, cols])     # hidden behind the surface the view shows
    assert seen_through(front, mug).mean() > 0.95
    assert not seen_through(behind, mug).any()
    assert not seen_through(cam.position - 5.0 * cam.forward[None], mug).any()    # behind every camera
    assert not seen_through(front, replace(mug, depth=None)).any()


@pytest.mark.parametrize("seen_colours", [False, True])
def test_backdrop_colours_come_from_what_the_views_show(mug, seen_colours):
    """A pink layer hidden 1 cm behind the wall (a fit leaves hidden Gaussians of any colour):
    with `seen_colours` the wall's continuation takes the colours the views show."""
    from morphosim_gym.reconstruct.completion import _append

    model = initialize(mug, seed=0).model
    backdrop = find_backdrop(model, {0: False, 1: True}, _background(mug), np.random.default_rng(0))
    on = backdrop.inliers
    with torch.no_grad():
        model.opacity_logits[on] = 8.0                                      # an opaque wall in front
        means = model.means.numpy()[on] - 0.01 * backdrop.normal          # behind the wall, away from the objects
        quats, scales = model.quats.numpy()[on], model.scales().numpy()[on]
        seen_rgb = np.median(model.colors().numpy()[on], axis=0)
    pink = np.tile([1.0, 0.3, 0.8], (len(on), 1))
    _append(model, means, quats, scales, np.full(len(on), 0.99), pink, model.object_ids.numpy()[on])
    counts = complete(model, mug, {0: False, 1: True}, seed=0, seen_colours=seen_colours)
    start = len(model.means) - counts["symmetry"] - counts["backdrop"]
    with torch.no_grad():
        rgb = model.colors().numpy()[start:start + counts["backdrop"]]
    is_pink = np.abs(rgb - [1.0, 0.3, 0.8]).max(axis=1) < 0.05
    if seen_colours:
        assert not is_pink.any() and np.abs(np.median(rgb, 0) - seen_rgb).max() < 0.1
    else:
        assert is_pink.mean() > 0.2
