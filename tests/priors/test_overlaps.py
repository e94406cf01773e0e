"""Pixels where moving objects' boxes overlap go to the object whose motion they follow."""

import numpy as np
import pytest

from morphosim_gym.priors import PlanTarget
from morphosim_gym.priors.masks import box_masks
from morphosim_gym.priors.overlaps import split_by_motion

from ._stages import with_and_without

H = W = 64
T = 25
BACK_ROWS, FRONT_ROWS = (14.0, 30.0), (26.0, 46.0)     # the front object hides the back one's rows 26-30


def _texture(u, v, phase):
    """A smooth colour pattern in object coordinates (so a sub-pixel shift renders exactly)."""
    return np.stack([128 + 60 * np.sin(0.9 * u + 0.4 * v + phase + c) + 40 * np.sin(0.5 * v - 0.7 * u + 2 * c)
                     for c in range(3)], -1)


def _clip(back_speed=1.0, front_speed=0.4):
    """Two rectangles moving right over a flat setting, the front one drawn over the back one.
    Returns frames [T, H, W, 3], the truth ids [T, H, W] (0 setting, 1 back, 2 front) and the
    planned targets: the back box tight, the front box 6 rows too tall (a loose plan box)."""
    yy, xx = np.mgrid[0:H, 0:W] + 0.5
    frames = np.empty((T, H, W, 3), np.float32)
    truth = np.zeros((T, H, W), np.int32)
    boxes = {"back": [], "front": []}
    for t in range(T):
        img = np.full((H, W, 3), 90.0)
        x_back, x_front = 6.0 + back_speed * t, 8.0 + front_speed * t
        for name, x0, rows, wid, phase, k in (("back", x_back, BACK_ROWS, 26.0, 0.0, 1),
                                              ("front", x_front, FRONT_ROWS, 30.0, 1.7, 2)):
            inside = (xx >= x0) & (xx < x0 + wid) & (yy >= rows[0]) & (yy < rows[1])
            colour = _texture(xx - x0, yy - rows[0], phase)
            img[inside] = colour[inside]
            truth[t][inside] = k
            top = rows[0] - (6.0 if name == "front" else 0.0)
            boxes[name].append([x0 / W, top / H, (x0 + wid) / W, rows[1] / H])
        frames[t] = img
    targets = [PlanTarget(n, np.array(b)) for n, b in boxes.items()]
    return frames, truth, targets


def _nearest_box_ids(truth, targets):
    """What `label_regions` gives: every object pixel inside the front box goes to the front."""
    ids = truth.copy()
    for t in range(T):
        ids[t][(truth[t] > 0) & box_masks(targets, t, H, W, 0.0)[1]] = 2
    return ids


def _back_recall(ids, truth):
    return float(((ids == 1) & (truth == 1)).sum() / (truth == 1).sum())


@pytest.mark.parametrize("back_speed", [1.0, 0.5])     # 0.5: the motions part by 0.4 px in 4 frames, 1.2 in 12
def test_the_back_object_gets_back_the_band_the_front_box_took(back_speed):
    frames, truth, targets = _clip(back_speed=back_speed)
    ids = _nearest_box_ids(truth, targets)
    before = ids.copy()
    out = split_by_motion(frames, ids, targets, box_margin=0.0)
    assert _back_recall(ids, truth) < 0.8                       # the band rows 20-26 went to the front
    assert _back_recall(out, truth) > 0.97
    front = truth == 2
    assert ((out == 2) & front).sum() / front.sum() > 0.97       # the front keeps its own pixels
    assert np.array_equal(ids, before)                           # input untouched
    assert np.array_equal(out[truth == 0], ids[truth == 0])     # the setting untouched


def test_objects_moving_alike_keep_their_labels():
    for back_speed in (0.7, 0.73):          # the same motion; motions that part by 0.36 px in 12 frames
        frames, truth, targets = _clip(back_speed=back_speed, front_speed=0.7)
        ids = _nearest_box_ids(truth, targets)
        assert np.array_equal(split_by_motion(frames, ids, targets, box_margin=0.0), ids), back_speed


def test_pixels_never_go_from_a_farther_object_to_a_nearer_one():
    frames, truth, targets = _clip(back_speed=0.4, front_speed=1.0)
    ids = truth.copy()
    ids[truth == 2] = 1                      # the front object wrongly labelled as the one behind
    out = split_by_motion(frames, ids, targets, box_margin=0.0)
    assert np.array_equal(out, ids)
    # the right labels stay right, though along the front's outline the back object's own samples
    # a few frames away are hidden and the front's motion fits them better (a corner pixel whose
    # patch is mostly the other object's may move: one in a frame)
    out = split_by_motion(frames, truth, targets, box_margin=0.0)
    assert (out != truth).sum() <= T


def test_one_target_or_no_overlap_changes_nothing():
    frames, truth, targets = _clip()
    ids = _nearest_box_ids(truth, targets)
    assert np.array_equal(split_by_motion(frames, ids, targets[:1]), ids)
    far = PlanTarget("front", np.tile([[0.9, 0.9, 0.95, 0.95]], (T, 1)))
    assert np.array_equal(split_by_motion(frames, ids, [targets[0], far], box_margin=0.0), ids)


@pytest.mark.parametrize("frames", [1, 3])
def test_a_clip_too_short_for_the_offsets_keeps_its_labels(frames):
    clip, truth, targets = _clip()
    ids = _nearest_box_ids(truth, targets)[:frames]
    short = [PlanTarget(tg.label, tg.boxes[:frames]) for tg in targets]
    assert np.array_equal(split_by_motion(clip[:frames], ids, short, box_margin=0.0), ids)


def test_bad_input_names_the_problem():
    frames, truth, targets = _clip()
    with pytest.raises(ValueError, match="ids"):
        split_by_motion(frames, truth[:, :10], targets)
    with pytest.raises(ValueError, match="ratio"):
        split_by_motion(frames, truth, targets, ratio=1.5)


def test_two_white_sheep_side_by_side_are_told_apart_in_estimated_masks():
    # the sibling-shape split would tell these two apart too (0.94 / 0.89 with the motion split off)
    clip, on, off = with_and_without("two sheep walk across the field from left to right", "motion_split", 96, 25,
                                     sibling_shapes=False)

    def sheep_iou(e):
        out = {}
        for inst, name in clip.labels.items():
            if name.startswith("sheep"):
                got = np.isin(e.masks, [k for k, n in e.labels.items() if n == name])
                want = clip.masks == inst
                out[name] = (got & want).sum() / (got | want).sum()
        return out

    assert min(sheep_iou(off).values()) < 0.72                    # the one behind lost a band
    assert min(sheep_iou(on).values()) > 0.8
