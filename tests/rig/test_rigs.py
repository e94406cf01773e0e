"""Rigs: MJCF loading, placement and scaling, kinematics to cameras, agent Gaussians."""

import math

import mujoco
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.rig import AGENT_OBJECT_ID, RIG_DIR, AgentSkin, ArmRig, FreeCameraRig, PanTiltRig, geom_part


@pytest.mark.parametrize("name", ["pan_tilt.xml", "free_camera.xml", "arm6.xml"])
def test_mjcf_files_ship_in_the_package_and_compile(name):
    path = RIG_DIR / name
    assert path.exists()
    model = mujoco.MjModel.from_xml_path(str(path))
    assert model.ncam >= 1
    # kinematic rigs: nothing collides, nothing is simulated
    assert np.all(model.geom_contype == 0) and np.all(model.geom_conaffinity == 0)


@pytest.mark.parametrize("point", [(0.3, 2.0, 0.2), (-1.5, 1.0, 1.2), (0.0, 3.0, -0.4)])
def test_pan_tilt_aims_its_camera_at_a_point(point):
    rig = PanTiltRig()
    rig.place(eye=(0.2, -1.0, 1.0), facing=(0.0, 1.0, 0.5))
    rig.aim_at(point)
    cam = rig.camera("eye", 64, 48)
    uv, z = cam.project(np.asarray(point))
    assert z > 0
    np.testing.assert_allclose(uv, [32.0, 24.0], atol=1e-6)


def test_pan_tilt_action_signs_limits_and_zoom():
    rig = PanTiltRig()
    rig.place(eye=(0, 0, 1.0), facing=(0, 1, 1.0))
    f0 = rig.camera("eye", 32, 32).forward
    rig.apply(np.array([1.0, 0.0, 0.0]), 0.1)          # positive pan turns left (towards -x when facing +y)
    assert rig.camera("eye", 32, 32).forward[0] < f0[0] - 0.05
    rig.apply(np.array([0.0, 1.0, 0.0]), 0.1)          # positive tilt looks up
    assert rig.camera("eye", 32, 32).forward[2] > 0.05
    for _ in range(100):
        rig.apply(np.array([1.0, 1.0, 1.0]), 0.1)
    lo, hi = rig.joint_range[:, 0], rig.joint_range[:, 1]
    assert np.all(rig.qpos <= hi + 1e-12) and np.all(rig.qpos >= lo - 1e-12)
    assert rig.fov == pytest.approx(rig.fov_range[0])  # zoomed all the way in
    lo_b, hi_b = rig.proprio_bounds()
    p = rig.proprio()
    assert p.shape == (6,) and np.all(p >= lo_b) and np.all(p <= hi_b)


def test_camera_of_a_rig_matches_camera_from_mujoco_camera():
    rig = ArmRig()
    rig.place((0.1, 0.2, 0.0), (0.0, -1.0, 0.0), reach=0.5)
    rig.set_joints([0.3, 0.4, 0.5, 0.1, 0.2, 0.3])
    rig.forward()
    a = rig.camera("wrist", 40, 30)
    b = ms.Camera.from_mujoco_camera(rig.model, rig.data, "wrist", 40, 30, near=a.near)
    assert a == b


def test_fast_mujoco_camera_equals_the_validated_one():
    from morphosim_gym.rig.base import mujoco_camera

    rig = FreeCameraRig()
    rng = np.random.default_rng(0)
    for _ in range(5):
        rig.place(rng.normal(size=3), rng.normal(size=3) + 3, centre=(0, 0, 0), extent=1.0, roll=rng.normal())
        i = rig.model.camera("eye").id
        for w, h in ((64, 48), (84, 84)):
            fast = mujoco_camera(rig.data.cam_xpos[i], rig.data.cam_xmat[i], 55.0, w, h, 0.02)
            slow = ms.Camera.from_mujoco(rig.data.cam_xpos[i], rig.data.cam_xmat[i], 55.0, w, h, near=0.02)
            assert fast == slow and repr(fast) == repr(slow)
            assert not fast.world_to_camera.flags.writeable


def test_arm_scaling_sets_the_reach_and_the_ready_pose_is_raised():
    for reach in (0.3, 3.0):
        arm = ArmRig()
        arm.place((1.0, 2.0, 0.5), (1.0, 0.0, 0.5), reach=reach)
        assert arm.reach == pytest.approx(reach)
        shoulder = arm.shoulder
        assert shoulder[2] - 0.5 == pytest.approx(reach * ArmRig.nominal_shoulder / ArmRig.nominal_reach)
        # fully stretched upwards the fingertips are ~ one reach from the shoulder
        arm.set_joints(np.zeros(6))
        arm.forward()
        assert np.linalg.norm(arm.end_effector() - shoulder) == pytest.approx(reach, rel=0.06)


def test_arm_faces_the_point_it_is_placed_towards():
    arm = ArmRig()
    arm.place((0.0, 1.0, 0.0), facing=(0.0, 0.0, 0.0), reach=1.0)
    arm.set_joints([0, 1.2, 0.3, 0, 0, 0])                # lean forward
    arm.forward()
    assert arm.end_effector()[1] < 1.0 - 0.5             # towards the facing point (-y)


def test_arm_action_integrates_joint_rates_within_limits():
    arm = ArmRig(max_joint_rate=math.radians(90))
    arm.place((0, 0, 0), (0, -1, 0), reach=1.0)
    q0 = arm.qpos
    arm.apply(np.array([1.0, 0, 0, 0, 0, -1.0]), 0.1)
    dq = arm.qpos - q0
    np.testing.assert_allclose(dq, [math.radians(9), 0, 0, 0, 0, -math.radians(9)], atol=1e-12)
    for _ in range(200):
        arm.apply(np.ones(6), 0.1)
    np.testing.assert_allclose(arm.qpos, arm.joint_range[:, 1])


def test_free_camera_looks_where_placed_and_moves_in_its_own_frame():
    rig = FreeCameraRig(max_speed=0.5, max_turn_rate=math.radians(60))
    rig.place((0.0, -2.0, 1.0), look_at=(0.0, 0.0, 0.5), centre=(0, 0, 0.5), extent=2.0)
    cam = rig.camera("eye", 64, 64)
    uv, _ = cam.project(np.array([0.0, 0.0, 0.5]))
    np.testing.assert_allclose(uv, [32, 32], atol=0.5)   # the eye sits a little ahead of the body origin
    p0 = rig.position
    rig.apply(np.array([0.0, 1.0, 0.0, 0, 0, 0]), 0.5)   # forward: along the view direction
    step = rig.position - p0
    assert np.linalg.norm(step) == pytest.approx(0.5 * 2.0 * 0.5)
    assert float(step @ cam.forward) > 0.99 * np.linalg.norm(step)
    rig.apply(np.array([0.0, 0.0, 0.0, 1.0, 0, 0]), 0.5)  # positive yaw turns left
    assert rig.camera("eye", 64, 64).forward[0] < -0.2
    q = rig.data.qpos[3:7]
    assert np.linalg.norm(q) == pytest.approx(1.0)


def test_free_camera_stays_in_its_bounds():
    rig = FreeCameraRig()
    bounds = np.array([[-1.0, -1.0, 0.1], [1.0, 1.0, 2.0]])
    rig.place((0, 0, 1), (0, 1, 1), centre=(0, 0, 1), extent=1.0, bounds=bounds)
    for _ in range(50):
        rig.apply(np.array([0, 1.0, -1.0, 0, 0, 0]), 0.5)
    assert np.all(rig.position >= bounds[0] - 1e-12) and np.all(rig.position <= bounds[1] + 1e-12)


def test_unknown_camera_name_lists_the_cameras():
    with pytest.raises(ValueError, match="wrist"):
        ArmRig().camera("nope", 16, 16)


@pytest.mark.parametrize("geom_type,size", [(2, [0.1, 0, 0]), (3, [0.05, 0.2, 0]), (4, [0.1, 0.2, 0.3]),
                                            (5, [0.05, 0.1, 0]), (6, [0.1, 0.2, 0.3])])
def test_geom_parts_stay_inside_the_geom(geom_type, size):
    from morphosim_gym.scene.parts import parts_to_gaussians

    part = geom_part(geom_type, np.array(size))
    cloud = parts_to_gaussians([part], 400, (0.5, 0.5, 0.5), np.random.default_rng(0), shade=False)
    p = cloud.means
    s = np.array(size)
    if geom_type == 2:
        assert np.allclose(np.linalg.norm(p, axis=1), s[0], atol=1e-6)
    elif geom_type == 3:        # capsule along z: radius s0, half-length s1
        r = np.hypot(p[:, 0], p[:, 1])
        assert r.max() <= s[0] + 1e-6 and np.abs(p[:, 2]).max() <= s[1] + s[0] + 1e-6
        assert np.abs(p[:, 2]).max() > s[1]
    elif geom_type == 5:        # cylinder along z, centred
        assert np.abs(p[:, 2]).max() <= s[1] + 1e-6 and p[:, 2].min() < -0.9 * s[1]
    elif geom_type == 6:
        assert np.all(np.abs(p) <= s + 1e-6)
    assert geom_part(0, np.ones(3)) is None             # planes are not drawn


def test_agent_skin_follows_the_geoms_and_scales():
    arm = ArmRig()
    arm.place((0, 0, 0), (0, -1, 0), reach=0.95)
    g1 = arm.gaussians()
    assert np.all(g1.object_ids == AGENT_OBJECT_ID)
    arm.place((5.0, 0, 0), (5.0, -1, 0), reach=2 * 0.95)
    g2 = arm.gaussians()
    ext1 = np.ptp(g1.means, axis=0)
    ext2 = np.ptp(g2.means, axis=0)
    np.testing.assert_allclose(ext2, 2 * ext1, rtol=1e-4, atol=1e-5)
    np.testing.assert_allclose(g2.scales, 2 * g1.scales, rtol=1e-5)
    assert abs(g2.means[:, 0].mean() - 5.0) < 0.1
    # every Gaussian lies on its own geom: within the geom's bounding radius of its centre
    skin = AgentSkin(arm.model, geom_size=arm._nominal["geom_size"])
    g = skin.gaussians(arm.data, arm.scale)
    owner = skin._geom_of
    radius = arm.model.geom_size.sum(axis=1)              # bounds every primitive's extent from its centre
    d = np.linalg.norm(g.means - arm.data.geom_xpos[owner], axis=1)
    assert np.all(d <= radius[owner] * 1.01 + 1e-6)


def test_third_person_camera_sees_the_arm():
    arm = ArmRig()
    arm.place((0, 0, 0), (0, -1, 0), reach=1.0)
    cam = ms.Camera.look_at((2.5, -2.5, 1.5), (0, 0, 0.5), 64, 64, 50)
    arm.set_world_camera("scene", cam)
    arm.forward()
    seen = arm.camera("scene", 64, 64)
    np.testing.assert_allclose(seen.world_to_camera, cam.world_to_camera, atol=1e-9)
    out = ms.render(arm.gaussians(), seen)
    assert np.count_nonzero(out.instance == AGENT_OBJECT_ID) > 50


def test_skin_kernel_matches_a_numpy_reference():
    from morphosim_gym.scene.lighting import AMBIENT, DIFFUSE, LIGHT_DIR
    from morphosim_gym.scene.rotations import matrix_to_quat, quat_multiply

    arm = ArmRig()
    arm.place((0.2, 0.1, 0.0), (0, -1, 0), reach=0.7)
    arm.set_joints([0.4, 0.8, -1.1, 2.0, 0.3, -2.5])
    arm.forward()
    skin = AgentSkin(arm.model, geom_size=arm._nominal["geom_size"])
    g = skin.gaussians(arm.data, arm.scale)
    rot = arm.data.geom_xmat.reshape(-1, 3, 3)[skin._geom_of]
    means = np.einsum("mij,mj->mi", rot, skin._means * arm.scale) + arm.data.geom_xpos[skin._geom_of]
    quats = quat_multiply(matrix_to_quat(rot), skin._quats)
    quats *= np.sign(np.sum(quats * g.quats, axis=1, keepdims=True))      # q and -q are one rotation
    light = AMBIENT + DIFFUSE * np.clip(np.einsum("mij,mj->mi", rot, skin._normals) @ LIGHT_DIR, 0, 1)
    np.testing.assert_allclose(g.means, means, atol=1e-5)
    np.testing.assert_allclose(g.quats, quats, atol=1e-5)
    np.testing.assert_allclose(g.colors, np.clip(skin._albedo * light[:, None], 0, 1), atol=1e-5)
