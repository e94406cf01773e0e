"""Size priors from the category: the generator's sizes, and the depth they give an object."""

import numpy as np
import pytest

from morphosim_gym.priors import CATEGORY_SIZES, ObjectSize, planned_sizes, size_depth
from morphosim_gym.priors.depth import contact_depth, ground_plane_depth
from morphosim_gym.priors.rgb import object_depths
from morphosim_gym.scene import Camera


def _camera(w=64, h=48):
    return Camera.look_at((0.0, -6.0, 2.0), (0.0, 0.0, 0.5), width=w, height=h, fov_y_deg=50.0)


def test_category_sizes_are_the_generators():
    from morphosim_gym.generate.assets import CATEGORY_SPECS, build_parts
    from morphosim_gym.scene.parts import parts_to_gaussians

    for name, size in CATEGORY_SIZES.items():
        c = parts_to_gaussians(build_parts(name), 1500, np.full(3, 0.5), np.random.default_rng(0))
        ext = c.means.max(0) - c.means.min(0)
        assert size.height == pytest.approx(float(ext[2]), rel=0.05, abs=0.01), name
        assert size.longest == pytest.approx(float(max(ext[0], ext[1])), rel=0.05, abs=0.01), name
        if name in CATEGORY_SPECS:
            assert size.mobility == CATEGORY_SPECS[name].mobility, name


def test_planned_sizes_scale_and_floor():
    info = {"plan": {"objects": [{"name": "bus", "category": "bus", "scale": 1.0},
                                 {"name": "cube", "category": "cube", "scale": 2.0},
                                 {"name": "thing", "category": "no such category"}]}}
    s = planned_sizes(info)
    assert set(s) == {"bus", "cube"} and s["bus"] == CATEGORY_SIZES["bus"]
    # a cube next to a 6 m bus is grown to 30% of it, as the generator does
    assert max(s["cube"].height, s["cube"].longest) == pytest.approx(0.3 * 6.02)
    assert planned_sizes({}) == {}


def test_size_depth_from_pixel_height():
    cam = _camera()
    m = np.zeros((48, 64), bool)
    m[10:30, 20:30] = True                                  # 20 rows
    assert size_depth(m, cam, 2.0) == pytest.approx(cam.fy * 2.0 / 20)
    # seen from above, a box's depth extent adds to its rows: the same rows put it farther
    assert size_depth(m, cam, ObjectSize(2.0, 2.0)) > 1.1 * size_depth(m, cam, 2.0)
    cut = m.copy()
    cut[0:5, 20:30] = True                                  # touches the top border
    assert size_depth(cut, cam, 2.0) is None
    blocked = np.zeros_like(m)
    blocked[30:40, 15:35] = True                            # an object in front hides its bottom
    assert size_depth(m, cam, 2.0, blocked=blocked) is None


def _drawn(cam, z, height, col=32):
    """Mask [H, W] of an upright object `height` m tall at camera depth z whose bottom row sits at
    the ground's row for that depth (standing) -- rows from the ground depth image."""
    ground = ground_plane_depth(cam)
    rows = np.flatnonzero(np.abs(ground[:, col] - z) == np.abs(ground[:, col] - z).min())
    bottom = int(rows[0])
    n = max(3, int(round(cam.fy * height / z)))
    m = np.zeros((cam.height, cam.width), bool)
    m[bottom - n:bottom, col - 4:col + 4] = True
    return m, ground


def test_a_swimmer_takes_its_depth_from_its_size():
    cam = _camera()
    m, ground = _drawn(cam, 6.0, 1.0)
    m = np.roll(m, -8, axis=0)                             # 8 rows higher: off the ground
    masks = np.where(m, 1, 0)[None].repeat(5, 0)
    grounds = ground[None].repeat(5, 0)
    contact = object_depths(masks, 1, grounds, [cam] * 5, None)
    thin = ObjectSize(1.0, 0.01, "swim")                   # 1 m tall, 1 cm deep: a flat fin
    swim = object_depths(masks, 1, grounds, [cam] * 5, thin)
    expect = size_depth(m, cam, thin)
    assert expect == pytest.approx(6.0, rel=0.1)          # drawn at 6 m
    assert np.allclose(swim, expect)
    # the ground contact is farther: the floor seen just under a swimmer lies behind it
    assert np.all(contact > 1.5 * expect)
    # a ground object lifted off the ground (a bouncing ball in the air) takes its size there too
    lifted = object_depths(masks, 1, grounds, [cam] * 5, ObjectSize(1.0, 0.01, "ground"), lifted_ratio=1.1)
    assert np.allclose(lifted, expect)


def test_a_swimmer_beside_another_object_keeps_its_depth_from_its_other_frames():
    # frames 0-4: another object right beside the fish hides its outline, so its size says
    # nothing there; its depth goes on from frames 5-8, never the far ground contact
    cam = _camera()
    m, ground = _drawn(cam, 6.0, 1.0)
    m = np.roll(m, -8, axis=0)
    masks = np.where(m, 1, 0)[None].repeat(9, 0)
    cols = np.flatnonzero(m.any(axis=0))
    for i in range(5):
        masks[i][m.any(axis=1), cols[-1] + 1:cols[-1] + 6] = 2     # the neighbour, right of it
    grounds = ground[None].repeat(9, 0)
    thin = ObjectSize(1.0, 0.01, "swim")
    z = object_depths(masks, 1, grounds, [cam] * 9, thin)
    expect = size_depth(m, cam, thin)
    assert size_depth(masks[0] == 1, cam, thin, blocked=masks[0] == 2) is None
    assert np.allclose(z, expect)
    contact = object_depths(masks, 1, grounds, [cam] * 9, None)
    assert np.all(contact > 1.5 * expect)


def test_contact_takes_the_nearest_feet():
    # a sheep-like mask: a body with two legs reaching lower; the legs' contact is the object's
    cam = _camera()
    ground = ground_plane_depth(cam)
    m = np.zeros((48, 64), bool)
    m[20:28, 20:40] = True
    m[28:34, 21:23] = m[28:34, 37:39] = True
    low = contact_depth(m, ground, 1.0, percentile=10)
    assert low == pytest.approx(float(ground[34, 22]), rel=0.02)
    assert contact_depth(m, ground, 1.0) > 1.1 * low        # the median sees the ground under the belly


def test_a_bouncing_object_is_measured_against_itself_on_the_ground():
    # 10 frames of one object 1 m tall at 6 m: on the ground in frames 0 and 9, up to 8 rows above
    # it between (a bounce). Its category says 3 m: the size depth (18 m) never overrules the
    # contact. Its own contact x rows on the ground puts the flying frames back at 6 m.
    cam = _camera(64, 96)
    m, ground = _drawn(cam, 6.0, 1.0)
    lifts = [0, 3, 6, 8, 8, 8, 8, 6, 3, 0]
    masks = np.stack([np.where(np.roll(m, -k, axis=0), 1, 0) for k in lifts])
    grounds = ground[None].repeat(len(lifts), 0)
    wrong = ObjectSize(3.0, 3.0, "ground")
    contact = object_depths(masks, 1, grounds, [cam] * len(lifts), wrong)
    own = object_depths(masks, 1, grounds, [cam] * len(lifts), wrong, own_lift_ratio=1.15)
    assert own[0] == contact[0] == pytest.approx(6.0, rel=0.1)
    assert np.all(contact[3:7] > 1.25 * 6.0)                   # the ground seen under it lies behind
    high = np.array(lifts) >= 6
    np.testing.assert_allclose(own[high], own[0], rtol=1e-6)    # the same rows: the same depth
    assert np.all(own <= 1.15 * own[0])        # 3 rows up: within the ratio, the contact stays (6.6 m)
    # no plan (no size, a real video's moving region): the contact as it was
    assert np.array_equal(object_depths(masks, 1, grounds, [cam] * 10, None, own_lift_ratio=1.15),
                          object_depths(masks, 1, grounds, [cam] * 10, None), equal_nan=True)


def test_an_object_walking_away_on_the_ground_keeps_its_contact_depth():
    # nearer and farther on the ground: contact x rows stays put, nothing counts as lifted
    cam = _camera(64, 96)
    zs = [4.0, 5.0, 6.0, 7.0, 8.0, 9.0]
    masks = np.stack([np.where(_drawn(cam, z, 1.0)[0], 1, 0) for z in zs])
    grounds = ground_plane_depth(cam)[None].repeat(len(zs), 0)
    size = ObjectSize(3.0, 3.0, "ground")
    own = object_depths(masks, 1, grounds, [cam] * len(zs), size, own_lift_ratio=1.15)
    assert np.array_equal(own, object_depths(masks, 1, grounds, [cam] * len(zs), size))
    np.testing.assert_allclose(own, zs, rtol=0.12)


@pytest.mark.parametrize("bad", [1.0, 0.5, -2.0, float("nan"), float("inf")])
def test_own_lift_ratio_must_exceed_one(bad):
    from morphosim_gym.priors.rgb import RGBPriorEstimators

    with pytest.raises(ValueError, match="own_lift_ratio"):
        RGBPriorEstimators(own_lift_ratio=bad)


def test_an_object_judged_by_its_own_scale_is_not_lifted_by_a_wrong_category_size():
    # 1 m tall, standing at 6 m in every frame, of a category whose size says 0.6 m: the size
    # depth (4.4 m) would lift it off the ground; measured against itself it never leaves it
    cam = _camera(64, 96)
    m, ground = _drawn(cam, 6.0, 1.0)
    masks = np.where(m, 1, 0)[None].repeat(6, 0)
    grounds = ground[None].repeat(6, 0)
    small = ObjectSize(0.6, 0.6, "ground")
    by_category = object_depths(masks, 1, grounds, [cam] * 6, small)
    own = object_depths(masks, 1, grounds, [cam] * 6, small, own_lift_ratio=1.15)
    np.testing.assert_allclose(by_category, size_depth(m, cam, small), rtol=1e-6)
    assert by_category[0] < 0.8 * 6.0                          # 4.4 m: the look-down adds depth extent
    np.testing.assert_allclose(own, 6.0, rtol=0.1)
    # too few whole frames to judge by (frames 2-5 reach the left border): the category's size
    # decides where it can, as before
    cut = masks.copy()
    rows = np.flatnonzero(m.any(axis=1))
    cut[2:, rows[0]:rows[-1] + 1, :m.shape[1] // 2] = 1
    unjudged = object_depths(cut, 1, grounds, [cam] * 6, small, own_lift_ratio=1.15)
    np.testing.assert_allclose(unjudged[:2], by_category[:2], rtol=1e-6)


def test_a_flat_object_takes_the_depth_of_its_top_not_of_the_ground():
    # a plate lying on the ground: with `flat_tops`, its pixels at the plane its height above
    # the ground (a fit that puts the plate and the table in one plane draws the table over the
    # plate's rim)
    from morphosim_gym.priors import RGBPriorEstimators

    cam = _camera()
    plate = CATEGORY_SIZES["plate"]
    assert plate.height < 0.2 * plate.longest
    masks = np.zeros((2, 48, 64), np.int32)
    masks[:, 30:36, 20:40] = 2
    frames = np.zeros((2, 48, 64, 3), np.uint8)
    labels, sizes = {0: "ground", 2: "plate"}, {"plate": plate}
    depth = RGBPriorEstimators(backdrop=True, flat_tops=True).depth(frames, cam, masks, labels, sizes)
    m = masks[0] == 2
    ground = ground_plane_depth(cam)[m]
    by_default = RGBPriorEstimators(backdrop=True).depth(frames, cam, masks, labels, sizes)
    np.testing.assert_allclose(by_default[0][m], ground, rtol=1e-6)        # off by default: the ground's
    top = ground_plane_depth(cam, plate.height)[m]
    np.testing.assert_allclose(depth[0][m], top, rtol=1e-6)
    assert np.all(depth[1][m] < ground - 1e-3)
    seen = (masks[0] == 0) & (ground_plane_depth(cam) > 0)          # the ground around it keeps its depth
    np.testing.assert_allclose(depth[0][seen], ground_plane_depth(cam)[seen], rtol=1e-6)
