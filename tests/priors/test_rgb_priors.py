"""Priors from RGB alone: masks from motion labelled by the plan, ground-contact depth, flow tracks."""

import numpy as np
import pytest

from morphosim_gym.priors import (PlanTarget, PriorEstimators, RGBPriorEstimators, default_estimators, ground_plane_depth,
                                  prepare_priors)
from morphosim_gym.priors.prepare import FAR_HEIGHTS
from morphosim_gym.scene import Camera, GeneratedClip


def _camera(w=64, h=48):
    # 2 m above the ground, looking along +y and tilted down
    return Camera.look_at((0.0, -6.0, 2.0), (0.0, 0.0, 0.5), width=w, height=h, fov_y_deg=50.0)


def _moving_square(t=9, w=64, h=48, still=False):
    """A textured ground-coloured background and a red square sliding left to right on it."""
    rng = np.random.default_rng(0)
    bg = (rng.integers(90, 110, (h, w, 3))).astype(np.uint8)
    frames, boxes = [], []
    for i in range(t):
        f = bg.copy()
        x0 = 8 + (0 if still else 4 * i)
        f[24:36, x0:x0 + 10] = (220, 30, 30)
        frames.append(f)
        boxes.append([x0 / w, 24 / h, (x0 + 10) / w, 36 / h])
    return np.stack(frames), np.asarray(boxes)


def test_moving_object_is_found_and_labelled_from_the_plan():
    frames, boxes = _moving_square()
    est = RGBPriorEstimators(setting_label="road")
    assert isinstance(est, PriorEstimators)
    masks, labels = est.masks(frames, None, [PlanTarget("bus", boxes)], cameras=[_camera()] * len(frames))
    assert labels[0] == "road" and labels[1] == "bus"
    truth = np.zeros(masks.shape, bool)
    for i, b in enumerate(boxes):
        x0 = round(b[0] * 64)
        truth[i, 24:36, x0:x0 + 10] = True
    pred = masks == 1
    assert (pred & truth).sum() / (pred | truth).sum() > 0.8


def test_nothing_moving_and_a_single_frame_give_only_the_setting():
    frames, _ = _moving_square(still=True)
    est = RGBPriorEstimators()
    masks, labels = est.masks(frames, None, [], cameras=[_camera()] * len(frames))
    assert set(np.unique(masks)) <= {-1, 0} and labels.get(0) == "ground"
    one, _ = est.masks(frames[:1], None, [], cameras=[_camera()])
    assert set(np.unique(one)) <= {-1, 0}


def test_object_depth_comes_from_its_ground_contact():
    frames, boxes = _moving_square()
    cam = _camera()
    est = RGBPriorEstimators()
    masks, _ = est.masks(frames, None, [PlanTarget("bus", boxes)], cameras=[cam] * len(frames))
    depth = est.depth(frames, cam, masks=masks)
    ground = est.depth(frames, cam)
    assert depth.shape == masks.shape and np.all(np.isfinite(depth))
    sel = masks[4] == 1
    rows = np.flatnonzero(sel.any(axis=1))
    # constant over the object, equal to the ground just under its lowest row
    z = depth[4][sel]
    assert np.ptp(z) < 1e-5
    assert abs(z[0] - np.median(ground[4][min(rows.max() + 1, 47)][sel.any(axis=0)])) < 0.05 * z[0]
    with pytest.raises(ValueError, match="cameras"):
        est.depth(frames, [cam] * 2)


def test_a_clip_of_frames_and_cameras_gets_every_prior_estimated():
    frames, boxes = _moving_square()
    cam = _camera()
    info = {"trajectories": {"bus": {"boxes": (boxes * [64, 48, 64, 48]).tolist()}}, "setting": "road"}
    clip = GeneratedClip(frames=frames, cameras=(cam,) * len(frames), fps=8.0, info=info)
    out = prepare_priors(clip)
    assert out.info["priors"] == {"depth": "estimated", "masks": "estimated", "tracks": "estimated"}
    assert out.labels == {0: "road", 1: "bus"}
    assert out.depth.shape == (9, 48, 64) and out.tracks.shape[1:] == (9, 2)
    assert clip.depth is None                      # the caller's clip is left as it was
    with pytest.raises(ValueError, match="priors source"):
        prepare_priors(clip, "oracle")


def test_above_the_horizon_is_sky_outdoors_and_a_backdrop_indoors():
    frames, boxes = _moving_square()
    cam = _camera()
    up = (slice(None), slice(0, 3))                # the top rows look above the horizon
    trajectories = {"bus": {"boxes": (boxes * [64, 48, 64, 48]).tolist()}}
    outdoor = prepare_priors(GeneratedClip(frames=frames, cameras=(cam,) * 9, fps=8.0,
                                           info={"trajectories": trajectories, "setting": "road"}))
    # left empty (no depth, no instance): the reconstruction makes it the scene's sky
    assert np.all(outdoor.depth[up] == 0) and np.all(outdoor.masks[up] == -1)
    indoor = prepare_priors(GeneratedClip(frames=frames, cameras=(cam,) * 9, fps=8.0,
                                          info={"trajectories": {"cup": trajectories["bus"]}, "setting": "table"}))
    # a wall closes an indoor view: the setting, as far as the farthest ground seen
    assert np.all(indoor.depth[up] > 0) and np.all(indoor.masks[up] == 0)


def test_bad_priors_name_the_field():
    frames, _ = _moving_square()
    cam = _camera()
    tracks = np.zeros((4, len(frames), 2), np.float32)
    tracks[0, 3] = np.nan
    with pytest.raises(ValueError, match="finite tracks"):
        GeneratedClip(frames=frames, cameras=(cam,) * len(frames), fps=8.0, tracks=tracks)
    with pytest.raises(ValueError, match="depth of shape"):
        GeneratedClip(frames=frames, cameras=(cam,) * len(frames), fps=8.0, depth=np.ones((2, 48, 64), np.float32))


def test_one_moving_region_under_two_planned_boxes_is_shared_out_front_first():
    from morphosim_gym.priors.masks import label_regions

    fg = np.zeros((1, 40, 40), bool)
    fg[0, 10:22, 6:20] = True                        # the one behind (its box ends higher up)
    fg[0, 16:32, 12:30] = True                       # the one in front overlaps it: one connected region
    back = PlanTarget("sheep 2", np.array([[6 / 40, 10 / 40, 20 / 40, 22 / 40]]))
    front = PlanTarget("sheep 1", np.array([[12 / 40, 16 / 40, 30 / 40, 32 / 40]]))
    ids, labels = label_regions(fg, [front, back])
    assert labels == {1: "sheep 1", 2: "sheep 2"}
    truth_front = np.zeros((40, 40), bool)
    truth_front[16:32, 12:30] = True
    truth_back = fg[0] & ~truth_front
    for k, truth in ((1, truth_front), (2, truth_back)):
        pred = ids[0] == k
        assert (pred & truth).sum() / (pred | truth).sum() > 0.9, labels[k]


def test_an_object_hidden_at_its_foot_takes_its_contact_from_the_free_columns():
    from morphosim_gym.priors.depth import contact_depth

    ground = np.repeat(np.arange(1, 21, dtype=np.float32)[::-1, None], 10, axis=1)   # row r: depth 20 - r
    mask = np.zeros((20, 10), bool)
    mask[4:10, 2:8] = True                           # bottom row 9: the ground below (row 10) is at 10
    blocked = np.zeros_like(mask)
    blocked[10:, 2:6] = True                         # another object in front under four columns
    mask[10:12, 2:6] = False
    assert contact_depth(mask, ground, 1.0, blocked=blocked) == 10.0
    assert contact_depth(mask, ground, 1.0, blocked=np.ones_like(mask)) == 10.0   # all blocked: as without


def test_an_object_entering_after_the_first_frame_is_tracked():
    from morphosim_gym.priors import flow_tracks

    rng = np.random.default_rng(1)
    bg = rng.integers(90, 110, (48, 64, 3)).astype(np.uint8)
    patch = rng.integers(0, 255, (12, 12, 3)).astype(np.uint8)
    frames = []
    for i in range(9):
        f = bg.copy()
        x0 = 70 - 3 * i                                 # outside the view until frame 3
        lo, hi = max(x0, 0), min(x0 + 12, 64)
        if hi > lo:
            f[20:32, lo:hi] = patch[:, lo - x0:hi - x0]
        frames.append(f)
    tracks, visible = flow_tracks(np.stack(frames), spacing=4)
    # tracks seeded after frame 0 follow the patch at its speed (3 px per frame to the left)
    on = visible[:, 6] & visible[:, 8] & (tracks[:, 6, 1] > 21) & (tracks[:, 6, 1] < 31) & (tracks[:, 6, 0] > 52)
    assert on.sum() >= 3
    assert np.allclose(tracks[on, 8, 0] - tracks[on, 6, 0], -6.0, atol=1.0)


def test_still_planned_objects_are_found_by_colour():
    from morphosim_gym.priors.masks import static_plan_labels

    frames, boxes = _moving_square()
    frames = frames.copy()
    frames[:, 30:44, 50:56] = (40, 160, 60)          # a still green plant, never moving
    est = RGBPriorEstimators(setting_label="water")
    cams = [_camera()] * len(frames)
    masks, labels = est.masks(frames, None, [PlanTarget("fish", boxes)], cameras=cams, static_labels=["seaweed"])
    sid = next(k for k, v in labels.items() if v == "seaweed")
    truth = np.zeros(masks.shape[1:], bool)
    truth[30:44, 50:56] = True
    for i in range(len(frames)):
        pred = masks[i] == sid
        assert (pred & truth).sum() / (pred | truth).sum() > 0.8
    # without the plan naming it, the plant is part of the setting
    plain, plain_labels = est.masks(frames, None, [PlanTarget("fish", boxes)], cameras=cams)
    assert "seaweed" not in plain_labels.values() and np.all(plain[:, 35, 52] == 0)
    info = {"plan": {"objects": [{"name": "cube"}, {"name": "plate"}],
                     "motions": [{"target": "cube", "path": "straight"}]}, "setting": "underwater"}
    assert static_plan_labels(info) == ["plate", "seaweed"]


def test_the_setting_is_named_as_the_generator_names_its_background():
    from morphosim_gym.generate.settings import SETTING_NAMES, build_setting
    from morphosim_gym.priors import setting_label

    frames, _ = _moving_square(t=2)
    for name in SETTING_NAMES:
        clip = GeneratedClip(frames=frames, cameras=(_camera(),) * 2, fps=8.0, info={"setting": name})
        built = build_setting(name, 5.0, np.random.default_rng(0), budget=200)
        assert setting_label(clip) == built.label, name


def test_up_in_the_sky_everything_but_the_objects_is_sky():
    frames, boxes = _moving_square()
    cam = _camera()
    info = {"trajectories": {"bird": {"boxes": (boxes * [64, 48, 64, 48]).tolist()}}, "setting": "sky",
            "plan": {"objects": [{"name": "bird", "category": "bird", "scale": 1.0}]}}
    out = prepare_priors(GeneratedClip(frames=frames, cameras=(cam,) * 9, fps=8.0, info=info))
    bird = out.masks == 1
    assert bird.any() and set(np.unique(out.masks[~bird]).tolist()) == {-1}   # no ground: no setting
    assert np.all(out.depth[~bird] == 0) and np.all(out.depth[bird] > 0)
    # on a road the lower rows are the setting, on the ground plane
    road = prepare_priors(GeneratedClip(frames=frames, cameras=(cam,) * 9, fps=8.0, info={**info, "setting": "road"}))
    assert np.all(road.masks[:, -5:][road.masks[:, -5:] != 1] == 0) and np.all(road.depth[:, -5:] > 0)


def _plane_rows(cam, est):
    """Per row of the middle column: the ground plane's depth (uncapped) and the estimate's."""
    frames = np.full((2, cam.height, cam.width, 3), 100, np.uint8)
    return ground_plane_depth(cam, 0.0, 1e6)[:, cam.width // 2], est.depth(frames, cam)[0][:, cam.width // 2]


@pytest.mark.parametrize("height", [0.2, 2.0, 8.0])
def test_far_ground_ends_at_a_number_of_camera_heights_whatever_the_scale(height):
    # the same view at three scales (a table top, a field, a road seen from high up)
    s = height / 2.0
    cam = Camera.look_at((0.0, -6.0 * s, height), (0.0, 0.0, 0.5 * s), width=64, height=48, fov_y_deg=50.0)
    plane, z = _plane_rows(cam, RGBPriorEstimators(far_heights=4.0))
    near, beyond = (plane > 0) & (plane <= 4.0 * height), plane > 4.0 * height
    assert near.sum() >= 10 and beyond.sum() >= 3
    np.testing.assert_allclose(z[near], plane[near], rtol=1e-5)       # the ground as it is
    # farther rows: a backdrop as far as the farthest ground left, not the plane behind it
    np.testing.assert_allclose(z[beyond], plane[near].max(), rtol=1e-5)
    assert beyond.sum() == 13                                         # the same rows at every scale


def test_without_far_heights_the_ground_reaches_max_depth():
    cam = Camera.look_at((0.0, -6.0, 2.0), (0.0, 0.0, 0.5), width=64, height=48, fov_y_deg=50.0)
    plane, z = _plane_rows(cam, RGBPriorEstimators(far_heights=None, max_depth=50.0))
    seen = (plane > 0) & (plane <= 50.0)
    assert np.count_nonzero(seen & (plane > 8.0)) >= 3
    np.testing.assert_allclose(z[seen], plane[seen], rtol=1e-5)


@pytest.mark.parametrize("bad", [0.0, -2.0, float("nan"), float("inf")])
def test_a_bad_far_heights_is_named(bad):
    with pytest.raises(ValueError, match="far_heights"):
        RGBPriorEstimators(far_heights=bad)


def test_under_an_open_sky_a_planned_clip_sees_the_ground_eight_camera_heights_far():
    frames, boxes = _moving_square()
    cam = Camera.look_at((0.0, -6.0, 2.0), (0.0, 0.0, 0.2), width=64, height=48, fov_y_deg=50.0)
    trajectories = {"car": {"boxes": (boxes * [64, 48, 64, 48]).tolist()}}
    depth, masks = {}, {}
    for setting in ("road", "table"):
        clip = GeneratedClip(frames=frames, cameras=(cam,) * 9, fps=8.0,
                             info={"trajectories": trajectories, "setting": setting})
        out = prepare_priors(clip)
        depth[setting], masks[setting] = out.depth, out.masks
        assert default_estimators(clip).far_heights == (FAR_HEIGHTS if setting == "road" else None)
    assert depth["road"].max() <= FAR_HEIGHTS * 2.0 + 1e-3 and np.count_nonzero(depth["road"]) > 0
    # flat colours cannot tell the sky from the setting: beyond the ground's reach is sky
    beyond = ground_plane_depth(cam, 0.0, 1e6) > FAR_HEIGHTS * 2.0
    assert beyond.sum() >= 64 and np.all(masks["road"][:, beyond] == -1) and np.all(depth["road"][:, beyond] == 0)
    # where walls close the view the floor reaches as far as it is seen (max_depth)
    assert depth["table"].max() > FAR_HEIGHTS * 2.0 * 1.5


def test_a_bouncing_ball_keeps_its_depth_in_the_air():
    # the generator's bouncing ball (64 px, 17 frames): the ground seen under it in the air lies
    # behind it; measured against itself on the ground it stays where it flies
    # (measured: worst frame 7% off the generator's depth, 56% with own_lift_ratio=None)
    import morphosim_gym as ms
    from morphosim_gym.priors import prepare_priors

    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=64, height=64, num_frames=17), reconstruction="oracle")
    clip = sim.generate_clip("A small, vibrant red rubber ball is bouncing from right to left", seed=0)

    def worst(own_lift_ratio) -> float:
        est = prepare_priors(clip, "estimated", estimators=default_estimators(clip, own_lift_ratio=own_lift_ratio))
        ball = next(i for i, n in est.labels.items() if n == "ball")
        errors = []
        for t in range(clip.num_frames):
            m = (est.masks[t] == ball) & (clip.depth[t] > 0)
            if m.any():
                errors.append(abs(np.median(est.depth[t][m]) / np.median(clip.depth[t][m]) - 1))
        return max(errors)

    assert default_estimators(clip).own_lift_ratio == RGBPriorEstimators().own_lift_ratio
    assert worst(RGBPriorEstimators().own_lift_ratio) < 0.12 and worst(None) > 0.4
