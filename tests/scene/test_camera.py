"""Camera: look_at, intrinsics from field of view, and MuJoCo conversions both ways."""

import math

import mujoco
import numpy as np
import pytest

from morphosim_gym.scene import Camera


def test_look_at_projects_target_to_image_centre():
    cam = Camera.look_at(eye=(0, -4, 2), target=(0, 0, 0.5), width=128, height=96, fov_y_deg=60)
    uv, z = cam.project(np.array([0.0, 0.0, 0.5]))
    np.testing.assert_allclose(uv, [64.0, 48.0], atol=1e-9)
    assert z == pytest.approx(math.hypot(4, 1.5))
    # world +x is image right, world +z is image up (smaller row)
    uv_right, _ = cam.project(np.array([0.5, 0.0, 0.5]))
    uv_up, _ = cam.project(np.array([0.0, 0.0, 1.0]))
    assert uv_right[0] > 64 and abs(uv_right[1] - 48) < 1e-9
    assert uv_up[1] < 48


def test_intrinsics_from_fov():
    fx, fy, cx, cy = Camera.intrinsics_from_fov(200, 100, 90.0)
    assert fy == pytest.approx(50.0) and fx == fy and (cx, cy) == (100.0, 50.0)
    cam = Camera.look_at((1, 2, 3), (0, 0, 0), width=200, height=100, fov_y_deg=45)
    assert cam.fov_y_deg == pytest.approx(45.0)


def test_project_unproject_roundtrip():
    cam = Camera.look_at((3, -2, 1.5), (0, 0.5, 0), width=64, height=48, fov_y_deg=70)
    pts = np.random.default_rng(0).normal(size=(20, 3))
    uv, z = cam.project(pts)
    np.testing.assert_allclose(cam.unproject(uv, z), pts, atol=1e-9)
    centres = cam.pixel_centres()
    assert centres.shape == (48, 64, 2)
    np.testing.assert_array_equal(centres[2, 5], [5.5, 2.5])         # (x, y) of row 2, column 5


def test_project_point_is_project_to_the_bit():
    rng = np.random.default_rng(3)
    for _ in range(200):
        cam = Camera.look_at(rng.normal(0, 3, 3), rng.normal(0, 1, 3), width=84, height=64, fov_y_deg=55)
        p = rng.normal(0, 3, 3)
        uv, z = cam.project(p)
        got = cam.project_point(p)
        assert got == (float(uv[0]), float(uv[1]), float(z)) and all(type(v) is float for v in got)


@pytest.mark.parametrize("bad", [
    dict(eye=(0, 0, 0), target=(0, 0, 0)),
    dict(eye=(0, 0, 5), target=(0, 0, 0)),            # looking straight down with up=z
    dict(eye=(0, 0, 1), target=(1, 0, 0), fov_y_deg=0),
    dict(eye=(0, 0, 1), target=(1, 0, 0), fov_y_deg=180),
    dict(eye=(0, np.nan, 1), target=(1, 0, 0)),
    dict(eye=(0, 0, 1), target=(1, 0, 0), width=0),
])
def test_look_at_bad_input(bad):
    with pytest.raises(ValueError):
        Camera.look_at(**bad)


def test_rejects_non_rigid_pose():
    m = np.eye(4)
    m[0, 0] = 2.0
    with pytest.raises(ValueError, match="rigid"):
        Camera(64, 64, 50, 50, 32, 32, m)


MJCF = """
<mujoco>
  <worldbody>
    <body name="target" pos="0.3 0.8 0.4"><geom type="sphere" size="0.05"/></body>
    <body name="rig" pos="1.5 -2.0 1.2" euler="10 -20 35">
      <camera name="tracker" mode="targetbody" target="target" fovy="50"/>
      <camera name="fixed" pos="0.1 0 0.2" xyaxes="0 1 0 -0.5 0 1" fovy="70"/>
    </body>
  </worldbody>
</mujoco>
"""


def _model():
    model = mujoco.MjModel.from_xml_string(MJCF)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def test_from_mujoco_looks_at_target_body():
    model, data = _model()
    cam = Camera.from_mujoco_camera(model, data, "tracker", width=80, height=60)
    uv, z = cam.project(data.body("target").xpos)
    np.testing.assert_allclose(uv, [40.0, 30.0], atol=1e-6)
    assert z > 0
    assert cam.fov_y_deg == pytest.approx(50.0)
    # MuJoCo camera axes: x right, y up, -z forward; ours: x right, y down, +z forward
    xmat = data.cam_xmat[model.camera("tracker").id].reshape(3, 3)
    np.testing.assert_allclose(cam.forward, -xmat[:, 2], atol=1e-12)
    np.testing.assert_allclose(cam.camera_to_world[:3, 1], -xmat[:, 1], atol=1e-12)


def test_mujoco_roundtrip_both_ways():
    model, data = _model()
    cid = model.camera("fixed").id
    cam = Camera.from_mujoco_camera(model, data, cid, width=64, height=64)
    pos, xmat, fovy = cam.to_mujoco()
    np.testing.assert_allclose(pos, data.cam_xpos[cid], atol=1e-12)
    np.testing.assert_allclose(xmat, data.cam_xmat[cid], atol=1e-12)
    assert fovy == pytest.approx(model.cam_fovy[cid])

    # our camera -> an MJCF camera -> MuJoCo kinematics -> the same pose
    ours = Camera.look_at(eye=(2.0, -3.0, 1.5), target=(0.2, 0.1, 0.3), width=96, height=72, fov_y_deg=55)
    pos, xmat, fovy = ours.to_mujoco()
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, xmat)
    xml = (f'<mujoco><worldbody><camera name="c" pos="{pos[0]} {pos[1]} {pos[2]}" '
           f'quat="{quat[0]} {quat[1]} {quat[2]} {quat[3]}" fovy="{fovy}"/></worldbody></mujoco>')
    m2 = mujoco.MjModel.from_xml_string(xml)
    d2 = mujoco.MjData(m2)
    mujoco.mj_forward(m2, d2)
    back = Camera.from_mujoco_camera(m2, d2, "c", width=96, height=72)
    np.testing.assert_allclose(back.world_to_camera, ours.world_to_camera, atol=1e-9)
    assert back.fy == pytest.approx(ours.fy)


def test_unknown_mujoco_camera_names_the_cameras():
    model, data = _model()
    with pytest.raises(ValueError, match="tracker"):
        Camera.from_mujoco_camera(model, data, "nope", 32, 32)


def test_orbit_keeps_distance_to_centre():
    cam = Camera.look_at((0, -4, 2), (0, 0, 0.5), 64, 64)
    o = cam.orbit(30.0, center=(0, 0, 0.5))
    assert np.linalg.norm(o.position - [0, 0, 0.5]) == pytest.approx(np.linalg.norm(cam.position - [0, 0, 0.5]))
    uv, _ = o.project(np.array([0.0, 0.0, 0.5]))
    np.testing.assert_allclose(uv, [32, 32], atol=1e-9)


def test_dict_roundtrip_exact():
    cam = Camera.look_at((0.1, -4.3, 2.2), (0, 0.2, 0.5), 84, 84, 61.3)
    assert Camera.from_dict(cam.to_dict()) == cam


def test_camera_path_fixed_orbit_pan_dolly():
    from types import SimpleNamespace

    from morphosim_gym.scene.camera import camera_path

    base = Camera.look_at((0, -4, 2), (0, 0, 0.5), 32, 32, 60)
    centre = np.array([0.0, 0.0, 0.5])
    assert camera_path(None, base, centre, 5) == [base] * 5
    orbit = camera_path(SimpleNamespace(motion="orbit", direction="clockwise", speed=1.0), base, centre, 5)
    assert len(orbit) == 5
    np.testing.assert_allclose(orbit[0].position, base.position, atol=1e-12)
    np.testing.assert_allclose([np.linalg.norm(c.position - centre) for c in orbit],
                               np.linalg.norm(base.position - centre))
    pan = camera_path(SimpleNamespace(motion="pan", direction="left", speed=1.0), base, centre, 3)
    np.testing.assert_allclose([c.position for c in pan], [base.position] * 3, atol=1e-12)
    dolly = camera_path(SimpleNamespace(motion="dolly", direction="in", speed=1.0), base, centre, 3)
    assert np.linalg.norm(dolly[-1].position - centre) < np.linalg.norm(base.position - centre)
    with pytest.raises(ValueError, match="camera motion"):
        camera_path(SimpleNamespace(motion="spin", direction=None, speed=1.0), base, centre, 3)
