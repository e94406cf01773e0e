"""Camera conversion between viser and our `Camera` (both ways, and against viser's own maths), and
the frame worker's coalescing."""

import math
import threading
import time

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.viewer import FrameWorker, camera_from_viewer, render_size, viewer_pose, viewer_view

CAMERAS = [
    ms.Camera.look_at((0, -4, 2), (0, 0, 0.5), 160, 90, 50),
    ms.Camera.look_at((3, 2, 1), (-1, 0.5, 0), 64, 128, 70),
    ms.Camera.look_at((0.5, -1, 6), (0, 0, 0), 100, 100, 30),     # looking almost straight down
]


@pytest.mark.parametrize("cam", CAMERAS)
def test_pose_round_trip(cam):
    wxyz, pos = viewer_pose(cam)
    back = camera_from_viewer(wxyz, pos, math.radians(cam.fov_y_deg), cam.width, cam.height)
    np.testing.assert_allclose(back.world_to_camera, cam.world_to_camera, atol=1e-9)
    assert back.fx == pytest.approx(cam.fx) and back.cy == pytest.approx(cam.cy)
    # a quaternion and its negative are the same rotation
    np.testing.assert_allclose(camera_from_viewer(-wxyz, pos, math.radians(cam.fov_y_deg), cam.width,
                                                  cam.height).world_to_camera, cam.world_to_camera, atol=1e-9)


def _viser_orientation(position, look_at, up):
    """The rotation viser's CameraHandle derives from position, look_at and up (`_update_wxyz`),
    rebuilt with viser's own transforms, as a wxyz quaternion."""
    import viser.transforms as tf

    z = np.asarray(look_at, float) - np.asarray(position, float)
    z /= np.linalg.norm(z)
    y = tf.SO3.exp(z * np.pi) @ np.asarray(up, float)
    y = y - np.dot(z, y) * z
    y /= np.linalg.norm(y)
    x = np.cross(y, z)
    return tf.SO3.from_matrix(np.stack([x, y, z], axis=1)).wxyz


@pytest.mark.parametrize("cam", CAMERAS)
def test_viewer_view_gives_viser_the_same_camera(cam):
    """Assigning `viewer_view(cam)` to a viser camera makes viser report a pose that converts back to `cam`."""
    view = viewer_view(cam, target=cam.position + 3.0 * cam.forward + [0.1, 0.0, 0.0])
    np.testing.assert_allclose(np.cross(view["look_at"] - view["position"], cam.forward), 0, atol=1e-9)
    wxyz = _viser_orientation(view["position"], view["look_at"], view["up_direction"])
    back = camera_from_viewer(wxyz, view["position"], view["fov"], cam.width, cam.height)
    np.testing.assert_allclose(back.world_to_camera, cam.world_to_camera, atol=1e-9)


def test_viser_quaternions_are_scalar_first_like_ours():
    import viser.transforms as tf

    from morphosim_gym.scene.rotations import quat_to_matrix

    q = np.array([0.3, -0.2, 0.9, 0.1])
    q /= np.linalg.norm(q)
    np.testing.assert_allclose(tf.SO3(q).as_matrix(), quat_to_matrix(q), atol=1e-12)


def test_axes_meaning():
    """viser's camera looks along its +z column and its image up is -y: a viewer camera at (0, -5, 0)
    turned to look along world +y sees a point ahead in the image centre and a higher point above it."""
    rot = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)   # columns: x right=+x, y down=-z, z fwd=+y
    from morphosim_gym.scene.rotations import matrix_to_quat

    cam = camera_from_viewer(matrix_to_quat(rot), (0, -5, 0), math.radians(60), 100, 100)
    uv, depth = cam.project(np.array([[0, 0, 0], [0, 0, 1.0], [1.0, 0, 0]]))
    np.testing.assert_allclose(uv[0], [50, 50])
    assert uv[1, 1] < 50 and uv[2, 0] > 50 and depth[0] == pytest.approx(5)


@pytest.mark.parametrize("aspect,long_side,expect", [
    (16 / 9, 512, (512, 288)), (0.5, 400, (200, 400)), (1.0, 100, (100, 100)),
    (1000.0, 64, (64, 16)), (float("nan"), 64, (64, 64)), (0.0, 64, (64, 64)),
])
def test_render_size(aspect, long_side, expect):
    assert render_size(aspect, long_side) == expect


def test_bad_viewer_cameras_are_rejected():
    with pytest.raises(ValueError, match="wxyz"):
        camera_from_viewer([0, 0, 0, 0], [0, 0, 0], 1.0, 10, 10)
    with pytest.raises(ValueError, match="position"):
        camera_from_viewer([1, 0, 0, 0], [0, np.nan, 0], 1.0, 10, 10)
    with pytest.raises(ValueError, match="fov_y"):
        camera_from_viewer([1, 0, 0, 0], [0, 0, 0], 3.5, 10, 10)


# ----------------------------------------------------------------------------- worker
def test_a_burst_of_requests_costs_one_render_of_the_latest():
    worker = FrameWorker()
    gate, started, ran = threading.Event(), threading.Event(), []
    worker.request("a", lambda: (started.set(), gate.wait(5), ran.append("first")))
    assert started.wait(5)                                  # the worker is busy with the first job
    for i in range(50):
        worker.request("a", lambda i=i: ran.append(i))      # a burst while it is busy
    worker.request("b", lambda: ran.append("b"))
    gate.set()
    assert worker.wait_idle(5)
    assert ran == ["first", 49, "b"]                        # only the newest of the burst, in request order
    assert worker.requested == 52 and worker.completed == 3 and worker.coalesced == 49
    worker.stop()
    assert not worker.alive


def test_a_failing_job_does_not_stop_the_worker():
    errors, ran = [], []
    worker = FrameWorker(on_error=lambda key, exc: errors.append((key, str(exc))))
    worker.request(1, lambda: 1 / 0)
    worker.request(2, lambda: ran.append(2))
    assert worker.wait_idle(5)
    assert errors == [(1, "division by zero")] and ran == [2] and worker.failed == 1
    worker.discard(3)
    worker.stop()
    worker.request(4, lambda: ran.append(4))                # ignored after stop
    time.sleep(0.05)
    assert ran == [2]


def test_requests_return_at_once_while_a_job_runs():
    worker = FrameWorker()
    gate = threading.Event()
    worker.request("slow", lambda: gate.wait(5))
    start = time.perf_counter()
    for i in range(100):
        worker.request(i % 3, lambda: None)
    assert time.perf_counter() - start < 0.5
    gate.set()
    assert worker.wait_idle(5)
    worker.stop()
