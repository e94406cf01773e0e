"""The trajectory planner: the paper's key points, boxes, velocities and velocity-scaled spacing."""

import math

import numpy as np
import pytest

from morphosim_gym.generate.trajectory import (MotionRequest, displacement_scale, plan_trajectory,
                                               travel_fraction)
from morphosim_gym.scene import Camera

CAM = Camera.look_at((0, -8, 3), (0, 0, 0.5), 128, 128, 50)
HALF = np.array([0.5, 0.25, 0.3])


def _plan(**kw):
    req = MotionRequest(**kw)
    return plan_trajectory(req, [CAM], 49, 8.0, HALF, (0.0, 0.0, 0.0))


def test_lambda_increases_with_speed_and_saturates():
    speeds = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0]
    scales = [displacement_scale(s) for s in speeds]
    assert all(a < b for a, b in zip(scales, scales[1:]))
    assert travel_fraction(1.0) == pytest.approx(0.45, abs=1e-3)
    assert travel_fraction(100.0) < 0.86


def test_quickly_spaces_boxes_farther_than_slowly():
    slow = _plan(direction=(1, 0, 0), speed=0.5)
    fast = _plan(direction=(1, 0, 0), speed=2.0)
    d_slow = np.linalg.norm(slow.keypoints[-1] - slow.keypoints[0])
    d_fast = np.linalg.norm(fast.keypoints[-1] - fast.keypoints[0])
    assert d_fast >= 1.5 * d_slow
    assert np.all(fast.velocities > slow.velocities)
    # box centres advance by the key point step (the paper's spacing)
    cx = (fast.boxes[:, 0] + fast.boxes[:, 2]) / 2
    assert np.all(np.diff(cx) > 0)


@pytest.mark.parametrize("direction,image_sign", [((1, 0, 0), (1, 0)), ((-1, 0, 0), (-1, 0)),
                                                  ((0, -1, 0), (0, 1)), ((0, 1, 0), (0, -1))])
def test_image_direction_follows_world_direction(direction, image_sign):
    tr = _plan(direction=direction)
    disp = tr.keypoints[-1] - tr.keypoints[0]
    want = np.array(image_sign, dtype=float)
    assert disp @ want / np.linalg.norm(disp) > 0.95


def test_paths_stay_on_screen():
    for path in ("straight", "bounce", "zigzag", "oscillate"):
        tr = _plan(path=path, direction=(1, 0, 0), speed=6.0)
        assert tr.boxes[:, :2].min() >= -1.0 and tr.boxes[:, 2].max() <= 129 and tr.boxes[:, 3].max() <= 129, path


def test_boxes_contain_the_projected_anchor():
    tr = _plan(direction=(-1, 0, 0))
    kp = tr.keypoints
    assert np.all((tr.boxes[:, 0] <= kp[:, 0]) & (kp[:, 0] <= tr.boxes[:, 2]))
    uv, _ = CAM.project(tr.positions)
    np.testing.assert_allclose(uv, kp, atol=1e-6)          # lifting to the ground inverts the projection


def test_bounce_leaves_the_ground_and_lands():
    tr = _plan(path="bounce", direction=(1, 0, 0))
    z = tr.positions[:, 2]
    assert z.max() > 0.3 and z[0] == pytest.approx(0.0, abs=1e-9) and z[-1] == pytest.approx(0.0, abs=1e-6)


def test_circle_clockwise_seen_from_above():
    for cw in (True, False):
        tr = _plan(path="circle", clockwise=cw)
        p = tr.positions[:, :2] - tr.positions[:, :2].mean(0)
        d = np.diff(p, axis=0)
        cross = p[:-1, 0] * d[:, 1] - p[:-1, 1] * d[:, 0]   # z of the angular momentum
        assert (np.mean(cross) < 0) == cw


def test_to_landmark_arrives_and_stops():
    tr = _plan(path="to", end=(1.5, 0.5, 0.0))
    assert np.linalg.norm(tr.positions[-1, :2] - [1.5, 0.5]) < 1e-6
    fast = _plan(path="to", end=(1.5, 0.5, 0.0), speed=3.0)
    arrived = np.flatnonzero(np.linalg.norm(fast.positions[:, :2] - [1.5, 0.5], axis=1) < 1e-6)
    assert arrived[0] < 48          # quick: arrives before the end of the clip, then stays


def test_stop_stays_and_headings_face_motion():
    still = _plan(path="stop")
    assert np.ptp(still.positions, axis=0).max() < 1e-9
    tr = _plan(direction=(-1, 0, 0))
    assert abs(abs(tr.headings[10]) - math.pi) < 1e-6


@pytest.mark.parametrize("kw,msg", [(dict(path="fly"), "path"), (dict(speed=0.0), "speed"),
                                    (dict(direction=(0, 0, 0)), "direction"), (dict(path="to"), "end")])
def test_bad_requests(kw, msg):
    with pytest.raises(ValueError, match=msg):
        MotionRequest(**kw)
