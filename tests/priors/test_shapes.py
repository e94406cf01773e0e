"""Numbered siblings that move in step share out their pixels by the shape they share in their boxes."""

import numpy as np
import pytest

from morphosim_gym.metrics import iou
from morphosim_gym.priors import PlanTarget
from morphosim_gym.priors.masks import box_masks
from morphosim_gym.priors.shapes import place_shape, shared_shape, sibling_groups, split_by_shape

from ._stages import with_and_without

H = W = 64
T = 20
BOX = (24.0, 20.0)                        # every sibling's planned box (w, h): looser than its shape
OFFSETS = ((4.0, 8.0), (9.0, 14.0), (14.0, 20.0))     # back, middle, front: each lower in the image


def _inside(xx, yy, x0, y0):
    """The sibling's shape in a box at (x0, y0): an ellipse low in the box, leaving margins."""
    u, v = (xx - x0) / BOX[0], (yy - y0) / BOX[1]
    return ((u - 0.5) / 0.38) ** 2 + ((v - 0.6) / 0.33) ** 2 <= 1.0


def _clip(labels=("duck 1", "duck 2", "duck 3")):
    """Three equal shapes moving right in step (1 px a frame), the nearer drawn over the farther.
    Returns the truth ids [T, H, W] (k + 1 for target k, 0 the setting) and the targets."""
    yy, xx = np.mgrid[0:H, 0:W] + 0.5
    truth = np.zeros((T, H, W), np.int32)
    boxes = [[] for _ in OFFSETS]
    for t in range(T):
        for k, (x, y) in enumerate(OFFSETS):           # back to front
            x0 = x + t
            truth[t][_inside(xx, yy, x0, y)] = k + 1
            boxes[k].append([x0 / W, y / H, (x0 + BOX[0]) / W, (y + BOX[1]) / H])
    return truth, [PlanTarget(n, np.array(b)) for n, b in zip(labels, boxes)]


def _nearest_box(truth, targets):
    """What `label_regions` gives such a row: each object pixel to the nearest box that holds it."""
    ids = truth.copy()
    for t in range(T):
        for k, box in enumerate(box_masks(targets, t, H, W, 0.0)):      # back to front: the nearest last
            ids[t][(truth[t] > 0) & box] = k + 1
    return ids


def _ious(ids, truth):
    return [float(np.mean([iou(ids[t] == k, truth[t] == k) for t in range(T)])) for k in (1, 2, 3)]


def test_the_shared_shape_is_the_shape_though_siblings_always_overlap():
    truth, targets = _clip()
    shape = shared_shape(truth > 0, [tg.boxes for tg in targets], size=32, margin=0.1)
    g = (np.arange(32) + 0.5) / 32 * 1.2 - 0.1
    want = _inside(g[None, :] * BOX[0], g[:, None] * BOX[1], 0.0, 0.0)
    assert ((shape >= 0.6) == want).mean() > 0.97
    # each sibling alone sees its neighbours in its box in every frame: its share map is no shape
    one = shared_shape(truth > 0, [targets[0].boxes], size=32, margin=0.1)
    assert ((one >= 0.6) & ~want).sum() > 0.1 * want.sum()


def test_siblings_in_step_get_back_their_bodies():
    truth, targets = _clip()
    ids = _nearest_box(truth, targets)
    before = _ious(ids, truth)
    assert min(before) < 0.5, before           # the front box took most of the ones behind
    after = _ious(split_by_shape(ids, targets), truth)
    assert min(after) > 0.9, after
    assert np.array_equal(ids, _nearest_box(truth, targets))      # the input is not changed


def test_pixels_outside_the_group_and_other_objects_are_left_alone():
    truth, targets = _clip(labels=("duck 1", "duck 2", "boat"))
    ids = _nearest_box(truth, targets)
    ids[0, :4, :4] = -1
    r, c = np.argwhere(truth[5] == 2)[len(np.argwhere(truth[5] == 2)) // 2]
    ids[5, r, c] = 0                                             # a hole in a duck's mask
    out = split_by_shape(ids, targets)
    assert np.array_equal(out[ids == 3], ids[ids == 3])          # the boat is no duck's sibling
    assert np.array_equal(out[ids <= 0], ids[ids <= 0])          # no pixel joins or leaves the objects


def test_objects_that_are_no_siblings_are_not_split():
    truth, targets = _clip(labels=("cube", "plate", "ball_2"))
    assert sibling_groups(targets) == []
    ids = _nearest_box(truth, targets)
    assert np.array_equal(split_by_shape(ids, targets), ids)
    _, targets = _clip(labels=("sheep 1", "cow 2", "sheep 3"))
    assert sibling_groups(targets) == [[0, 2]]


def test_a_shape_is_placed_in_its_box():
    shape = np.zeros((10, 10))
    shape[3:7, 3:7] = 1.0
    placed = place_shape(shape, np.array([0.25, 0.25, 0.75, 0.75]), 40, 40, margin=0.0)
    assert placed[20, 20] == pytest.approx(1.0) and placed[12, 12] == 0.0 and placed[5, 30] == 0.0
    assert not place_shape(shape, np.array([0.5, 0.5, 0.5, 0.7]), 40, 40).any()     # an empty box


def test_bad_input_is_named():
    truth, targets = _clip()
    with pytest.raises(ValueError, match="ids"):
        split_by_shape(truth[0], targets)
    with pytest.raises(ValueError, match="threshold"):
        split_by_shape(truth, targets, threshold=0.0)


def test_three_generated_ducks_are_told_apart():
    clip, on, off = with_and_without("three ducks swim across the water from left to right", "sibling_shapes",
                                     size=64, frames=9)

    def worst(est):
        vals = []
        for inst, name in clip.labels.items():
            if name.startswith("duck"):
                k = [i for i, v in est.labels.items() if v == name]
                vals.append(np.mean([iou(np.isin(est.masks[t], k), clip.masks[t] == inst) for t in range(clip.num_frames)]))
        return min(vals)

    assert worst(on) > worst(off) + 0.2, (worst(on), worst(off))
