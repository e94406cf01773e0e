"""An object's spin about the line of sight, from its own pixels (`reconstruct.spin`)."""

from dataclasses import replace

import cv2
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.reconstruct.initialize import InitConfig, initialize
from morphosim_gym.reconstruct.lifting import kabsch
from morphosim_gym.reconstruct.spin import spin_angles, spin_poses
from morphosim_gym.scene import Camera, GeneratedClip

from .conftest import football_clip

SIZE = 64


def _turning_disc(step_deg: float | list, frames: int = 9) -> GeneratedClip:
    """A still camera looking along +y at a textured disc (radius 14 px) that turns by `step_deg`
    a frame (or by each of a list's, one per frame pair; image x towards image y) while it slides
    1 px a frame to the right; the texture is
    a pattern of dark and light squares about 9 px wide, slightly blurred."""
    y, x = np.mgrid[:SIZE, :SIZE].astype(np.float32)
    squares = cv2.GaussianBlur((np.sin(x / 3.0 + 0.4) * np.sin(y / 2.7 + 1.1) > 0).astype(np.float32), (0, 0), 0.8)
    texture = np.stack([40 + 180 * squares, 30 + 50 * squares, 30 + 30 * squares], -1)
    yy, xx = np.mgrid[:SIZE, :SIZE]
    steps = np.broadcast_to(np.asarray(step_deg, float), (frames - 1,))
    turned = np.concatenate([[0.0], np.cumsum(steps)])
    imgs, masks = [], []
    for k in range(frames):
        cx, cy = 24.0 + k, 32.0
        shift = np.float32([[1, 0, cx - 32.0], [0, 1, cy - 32.0]])
        turn = cv2.getRotationMatrix2D((32.0, 32.0), -turned[k], 1.0)   # cv2: counter-clockwise on screen
        img = cv2.warpAffine(cv2.warpAffine(texture, turn, (SIZE, SIZE), flags=cv2.INTER_CUBIC), shift, (SIZE, SIZE),
                             flags=cv2.INTER_CUBIC)
        disc = (xx + 0.5 - cx) ** 2 + (yy + 0.5 - cy) ** 2 <= 14 ** 2
        imgs.append(np.where(disc[..., None], img, 40.0).clip(0, 255).astype(np.uint8))
        masks.append(np.where(disc, 1, 0).astype(np.int32))
    cam = Camera.look_at((0.0, -4.0, 0.0), (0.0, 0.0, 0.0), width=SIZE, height=SIZE, fov_y_deg=50.0)
    return GeneratedClip(frames=np.stack(imgs), cameras=(cam,) * frames, fps=10.0,
                         depth=np.full((frames, SIZE, SIZE), 4.0, np.float32), masks=np.stack(masks),
                         labels={0: "ground", 1: "disc"})


@pytest.mark.parametrize("step", [3.0, -4.0])
def test_spin_angles_read_the_turn_of_a_textured_disc(step):
    angles, ok, corr, still = spin_angles(_turning_disc(step), 1)
    assert ok.all() and np.median(corr) > 0.95
    deg = np.degrees(angles)
    assert np.all(np.sign(deg) == np.sign(step))
    assert abs(np.median(deg) - step) < 0.25 * abs(step)      # measured: 3.6 for 3, -4.3 for -4
    # the rotation explains the pixels far better than a translation alone does
    assert np.median((1 - still) / (1 - corr)) > 2.0


def test_a_uniform_disc_shows_no_turn():
    clip = _turning_disc(3.0)
    flat = np.where(clip.masks[..., None] == 1, np.uint8(180), clip.frames)
    angles, ok, _, _ = spin_angles(replace(clip, frames=flat), 1)
    assert np.all(np.abs(np.degrees(angles[ok])) < 0.5)


def test_spin_poses_turn_points_as_the_image_turns():
    # a point beside the disc's centre, turned by the poses, lands where the image turned it
    clip = _turning_disc(3.0)
    cam = clip.cameras[0]
    centre = cam.unproject(np.array([[24.5, 32.5]]), np.array([4.0]))[0]
    trans = np.stack([cam.unproject(np.array([[24.5 + k, 32.5]]), np.array([4.0]))[0] - centre for k in range(9)])
    rots, t = spin_poses(clip, 0, centre, trans, np.radians(np.full(8, 3.0)))
    point = cam.unproject(np.array([[34.5, 32.5]]), np.array([4.0]))     # 10 px right of the centre
    uv, _ = cam.project(point @ rots[6].T + t[6])
    a = np.radians(18.0)                                                 # 6 frames x 3 degrees
    expected = np.array([24.5 + 6 + 10 * np.cos(a), 32.5 + 10 * np.sin(a)])
    np.testing.assert_allclose(uv[0], expected, atol=0.3)
    uv0, _ = cam.project(centre[None] @ rots[6].T + t[6])               # the centre follows its path
    np.testing.assert_allclose(uv0[0], [30.5, 32.5], atol=1e-6)


def test_spin_poses_roll_about_the_ground_under_a_camera_looking_down():
    # a camera 30 degrees above the horizon: the object rolls about the ray's horizontal part (a
    # ball on the ground), by the image's turn over cos 30 deg, so the turn's part along the line
    # of sight, which is all the image shows, is the image's turn
    from scipy.spatial.transform import Rotation

    from morphosim_gym.reconstruct.spin import WORLD_UP

    clip = _turning_disc(3.0)
    cam = Camera.look_at((0.0, -4.0 * np.cos(np.radians(30)), 4.0 * np.sin(np.radians(30))), (0.0, 0.0, 0.0),
                         width=SIZE, height=SIZE, fov_y_deg=50.0)
    clip = replace(clip, cameras=(cam,) * clip.num_frames)
    a = np.radians(3.0)
    ray = -cam.position / np.linalg.norm(cam.position)
    for up, axis in ((None, ray), (WORLD_UP, np.array([0.0, 1.0, 0.0]))):
        rots, _ = spin_poses(clip, 0, np.zeros(3), np.zeros((9, 3)), np.full(8, a), up=up)
        rv = Rotation.from_matrix(rots[1]).as_rotvec()
        np.testing.assert_allclose(rv / np.linalg.norm(rv), axis, atol=1e-9)
        np.testing.assert_allclose(rv @ ray, a, atol=1e-9)         # the image's turn about the line of sight


@pytest.mark.parametrize("steps, turns", [(4.0, True), (0.0, False), ([10.0, -4.0] * 6, False), (1.0, False)])
def test_only_a_steady_visible_turn_replaces_the_poses(steps, turns):
    # a steady 4 degrees a frame turns the poses; no turn, turns of either sign (a sheep's walking
    # legs: 36 degrees in all here) or a turn too small to matter (12 degrees) leave them as given
    from morphosim_gym.reconstruct.initialize import _spun

    clip = _turning_disc(steps, frames=13)
    eye, trans = np.tile(np.eye(3), (13, 1, 1)), np.zeros((13, 3))
    rots, _ = _spun(clip, 1, 0, InitConfig(), np.array([0.0, 0.0, 0.0]), (eye, trans))
    assert np.array_equal(rots, eye) != turns
    if turns:
        assert 0.75 * 48 < _turn_deg(rots[-1]) < 1.25 * 48


@pytest.fixture(scope="module")
def ball_clip():
    from morphosim_gym.priors import prepare_priors
    from morphosim_gym.reconstruct.pipeline import video_estimators

    clip = football_clip(64, 17)
    return clip, prepare_priors(clip, "estimated", estimators=video_estimators(clip))


def _turn_deg(rot: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(rot) - 1) / 2, -1, 1))))


def test_a_rolling_ball_starts_turning_as_it_rolls(ball_clip):
    # estimated priors: the flow's tracks turn the ball by a fraction of its roll; its pixels show it
    clip, est = ball_clip
    ball = next(i for i, n in est.labels.items() if n == "ball")
    truth = next(o.id for o in clip.ground_truth.objects if o.name == "ball")
    sel = clip.ground_truth.gaussians.object_ids == truth
    at = [clip.ground_truth.at(t / clip.fps).means[sel] for t in range(17)]
    true_rel = [kabsch(at[0], at[t])[0] for t in range(17)]        # frame 0 -> frame t
    spun = initialize(est, seed=0)
    plain = initialize(est, InitConfig(spin=False), seed=0)
    assert spun.dynamic[ball] and plain.dynamic[ball]

    def error(result) -> float:     # mean angle between its turns from frame 0 and the true ones
        rots = result.instance_poses[ball][0]
        return float(np.mean([_turn_deg(rots[t] @ rots[0].T @ true_rel[t].T) for t in range(17)]))

    assert _turn_deg(true_rel[8]) > 60
    # measured: 27 degrees with the roll about the ground's horizontal (35 with the line of sight
    # as the axis, 20 degrees from the true one; ECC reads 80% of the turn at 64 px), 101 without
    assert error(spun) < 32 and error(plain) > 2 * error(spun)
    # with the generator's exact tracks the tracks see the turn, about its true axis: kept
    exact = initialize(clip, seed=0).instance_poses[truth]
    kept = initialize(clip, InitConfig(spin=False), seed=0).instance_poses[truth]
    np.testing.assert_array_equal(exact[0], kept[0])
    assert _turn_deg(exact[0][0] @ exact[0][8].T) > 60


def test_an_object_that_does_not_turn_keeps_its_poses():
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=64, height=64, num_frames=13, detail=0.5),
                       reconstruction="oracle")
    clip = sim.generate_clip("The bus is moving from right to left", seed=0)
    bus = next(i for i, n in clip.labels.items() if n == "bus")
    spun = initialize(clip, seed=0).instance_poses[bus]
    plain = initialize(clip, InitConfig(spin=False), seed=0).instance_poses[bus]
    np.testing.assert_array_equal(spun[0], plain[0])
    np.testing.assert_array_equal(spun[1], plain[1])


def test_a_sliding_mug_is_not_spun_by_a_rotation_that_explains_nothing():
    """The real mug sliding across the table (estimated priors, 128 px, its outline not trimmed):
    its mask holds the table seen through its handle and a rim of table around it, and ECC's
    Euclidean search settles on a steady turn (35 degrees in all) that aligns its pixels worse
    than no turn does; the gain gate keeps it unturned. (With the trimmed outline of the default
    estimators ECC finds no turn here at all.)"""
    from morphosim_gym.generate.real_assets import asset_candidates
    from morphosim_gym.priors import default_estimators, prepare_priors
    from morphosim_gym.reconstruct.initialize import _decide_motion

    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
        if not asset_candidates("mug"):
            pytest.skip("needs a real mug asset (apt install sweethome3d-furniture)")
        sim = ms.MorphoSim(generation=ms.GenerationConfig(width=128, height=128, num_frames=49),
                           reconstruction="oracle")
        clip = sim.generate_clip("a blue mug slides slowly across the table from left to right", seed=0)
    est = prepare_priors(clip, "estimated", estimators=default_estimators(clip, rims=False))
    mug = next(i for i, n in est.labels.items() if n == "mug")
    ref = est.num_frames // 2

    def most_turned(cfg: InitConfig) -> float:
        dynamic, (rots, _) = _decide_motion(est, mug, ref, cfg, 5.0)
        assert dynamic
        return max(_turn_deg(r) for r in rots)

    assert most_turned(InitConfig()) < 5.0              # measured: 1.1
    assert most_turned(InitConfig(spin_gain=0.0)) > 20.0    # measured: 35.5


def test_tracks_lifted_by_a_bent_depth_prior_give_way_to_the_roll(ball_clip):
    # exact tracks, depth x a smooth +-20% field: the rigid fit to the tracks lifted by it turns the
    # ball by a fraction of its roll, about a wrong axis; the roll read from its pixels takes over
    from morphosim_gym.priors import corrupt_priors
    from morphosim_gym.reconstruct.lifting import instance_motion

    clip, _ = ball_clip
    warped = corrupt_priors(clip, seed=0, depth_field=0.2, depth_noise=0.0, mask_pixels=0, mask_drop=0.0,
                            track_noise=0.0, track_drop=0.0)
    ball = next(o.id for o in clip.ground_truth.objects if o.name == "ball")
    sel = clip.ground_truth.gaussians.object_ids == ball
    at = [clip.ground_truth.at(t / clip.fps).means[sel] for t in range(17)]
    true_rel = [kabsch(at[0], at[t])[0] for t in range(17)]

    def error(rots: np.ndarray) -> float:
        return float(np.mean([_turn_deg(rots[t] @ rots[0].T @ true_rel[t].T) for t in range(17)]))

    result = initialize(warped, seed=0)
    tracks = instance_motion(warped, ball, result.reference[ball])[0]
    # measured: 24 degrees against the tracks' 45
    assert error(result.instance_poses[ball][0]) < 0.7 * error(tracks)
