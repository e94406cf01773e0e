"""The three rigs of the environments: pan-tilt camera on a tripod, free-flying camera, 6-DoF arm.

Each rig turns a normalised action in [-1, 1]^k into joint or body velocities, integrates
them kinematically for one control period, and reports proprioception. Placement is
relative to a scene: the env passes positions in world metres and a scale derived from
the scene (see each `place`).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .base import Rig, yaw_quat

__all__ = ["PanTiltRig", "FreeCameraRig", "ArmRig", "RIGS"]


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    if n < 1e-12:
        raise ValueError("Expected a non-zero direction, found a zero vector")
    return v / n


class PanTiltRig(Rig):
    """Pan-tilt camera on a tripod (`pan_tilt.xml`): yaw (pan), pitch (tilt) and zoom (field of view).

    Action [3] in [-1, 1]: pan rate, tilt rate, zoom rate, scaled by `max_pan_rate`,
    `max_tilt_rate` (rad/s) and `max_zoom_rate` (degrees of vertical field of view per
    second; positive zooms in). Positive pan turns left (counter-clockwise seen from above),
    positive tilt looks up.

    Proprio [6]: pan (rad), tilt (rad), zoom in [-1, 1] (-1 widest, +1 narrowest), and the
    last applied rates normalised to [-1, 1].
    """

    xml = "pan_tilt.xml"
    root_body = "mount"
    action_dim = 3
    proprio_dim = 6
    camera_name = "eye"

    def __init__(self, fov_range: tuple[float, float] = (12.0, 50.0), max_pan_rate: float = math.radians(60),
                 max_tilt_rate: float = math.radians(45), max_zoom_rate: float = 20.0, **kw) -> None:
        super().__init__(**kw)
        lo, hi = float(fov_range[0]), float(fov_range[1])
        if not 0.0 < lo < hi < 180.0:
            raise ValueError(f"Expected fov_range (lo, hi) with 0 < lo < hi < 180 degrees, found {fov_range!r}")
        self.fov_range = (lo, hi)
        self.max_rates = np.array([max_pan_rate, max_tilt_rate, max_zoom_rate], dtype=np.float64)
        self._cam = self._id("camera", self.camera_name)
        self._last = np.zeros(3)

    @property
    def fov(self) -> float:
        """Current vertical field of view, degrees."""
        return float(self.model.cam_fovy[self._cam])

    def set_fov(self, fov_deg: float) -> None:
        """Set the zoom (vertical field of view, degrees, clipped to `fov_range`)."""
        lo, hi = self.fov_range
        self.model.cam_fovy[self._cam] = min(max(float(fov_deg), lo), hi)

    def place(self, eye: Sequence[float], facing: Sequence[float], ground_z: float = 0.0, scale: float | None = None,
              fov_deg: float = 30.0) -> None:
        """Stand the tripod so that its camera is at `eye` and pan 0 faces `facing` horizontally;
        the rig is scaled so its feet reach `ground_z` (or by `scale`)."""
        eye = np.asarray(eye, dtype=np.float64)
        d = np.asarray(facing, dtype=np.float64) - eye
        yaw = math.atan2(-d[0], d[1]) if np.hypot(d[0], d[1]) > 1e-9 else 0.0   # body +y towards `facing`
        s = float(scale) if scale is not None else max(float(eye[2] - ground_z), 1e-3)
        super().place(eye, yaw_quat(yaw), s)
        self._yaw0 = yaw
        self.set_joints([0.0, 0.0])
        self.set_fov(fov_deg)
        self._last = np.zeros(3)
        self.forward()

    def aim_angles(self, point: Sequence[float]) -> tuple[float, float]:
        """(pan, tilt) that point the camera at a world point (before clipping to joint ranges)."""
        p = np.asarray(point, dtype=np.float64) - self.data.xpos[self._root]
        c, s = math.cos(-self._yaw0), math.sin(-self._yaw0)
        x, y, z = c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]          # into the mount's frame
        return math.atan2(-x, y), math.atan2(z, math.hypot(x, y))

    def aim_at(self, point: Sequence[float], offset: Sequence[float] = (0.0, 0.0)) -> None:
        """Point the camera at a world point, plus (pan, tilt) offsets in radians."""
        pan, tilt = self.aim_angles(point)
        self.set_joints([pan + offset[0], tilt + offset[1]])
        self.forward()

    def apply(self, action: np.ndarray, dt: float) -> None:
        """Integrate a normalised action [3] for `dt` seconds."""
        rates = np.asarray(action, dtype=np.float64) * self.max_rates
        self.integrate_joints(rates[:2], dt)
        self.set_fov(self.fov - rates[2] * dt)
        self._last = np.asarray(action, dtype=np.float64).copy()
        self.forward()

    def proprio_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) [6] of `proprio`."""
        r = self.joint_range
        return (np.array([r[0, 0], r[1, 0], -1, -1, -1, -1], np.float32),
                np.array([r[0, 1], r[1, 1], 1, 1, 1, 1], np.float32))

    def proprio(self) -> np.ndarray:
        """[6] float32: pan, tilt, zoom in [-1, 1], last normalised rates."""
        lo, hi = self.fov_range
        zoom = 1.0 - 2.0 * (self.fov - lo) / (hi - lo)
        q = self.qpos
        return np.array([q[0], q[1], zoom, *self._last], dtype=np.float32)


class FreeCameraRig(Rig):
    """Free-flying camera (`free_camera.xml`) under 6-DoF velocity control.

    Action [6] in [-1, 1]: velocity right, forward, up in the camera body's frame (scaled by
    `max_speed` x the rig's scene scale, m/s), then yaw, pitch, roll rates (scaled by
    `max_turn_rate`, rad/s; yaw about the body's up axis, positive to the left; pitch about
    its right axis, positive up; roll about its forward axis). The position is kept inside
    an axis-aligned box (`bounds`).

    Proprio [15]: position relative to the workspace centre divided by the workspace scale
    [3], the first two columns of the body's rotation matrix [6] (a continuous orientation),
    the last normalised action [6].
    """

    xml = "free_camera.xml"
    root_body = "drone"
    action_dim = 6
    proprio_dim = 15
    camera_name = "eye"
    POSITION_LIMIT = 10.0

    def __init__(self, max_speed: float = 0.5, max_turn_rate: float = math.radians(60), **kw) -> None:
        super().__init__(**kw)
        self.max_speed = float(max_speed)
        self.max_turn_rate = float(max_turn_rate)
        self._centre = np.zeros(3)
        self._extent = 1.0
        self.bounds = np.array([[-np.inf] * 3, [np.inf] * 3])
        self._last = np.zeros(6)
        self._qvel = np.zeros(6)

    def place(self, position: Sequence[float], look_at: Sequence[float], centre: Sequence[float], extent: float,
              bounds: np.ndarray | None = None, roll: float = 0.0) -> None:
        """Put the camera at `position` looking at `look_at`. `extent` (metres) is the workspace
        scale: speeds and the body's size follow it; `bounds` [2, 3] clip the position."""
        self._centre = np.asarray(centre, dtype=np.float64)
        self._extent = float(extent)
        super().place((0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), 0.15 * self._extent)
        if bounds is not None:
            self.bounds = np.asarray(bounds, dtype=np.float64).reshape(2, 3)
        self.set_pose(position, look_at, roll)
        self._last = np.zeros(6)

    def set_pose(self, position: Sequence[float], look_at: Sequence[float], roll: float = 0.0) -> None:
        """Body at `position` with its forward (+y) axis towards `look_at` and z up (then `roll`)."""
        p = np.asarray(position, dtype=np.float64)
        fwd = _unit(np.asarray(look_at, dtype=np.float64) - p)
        right = np.cross(fwd, [0.0, 0.0, 1.0])
        if np.linalg.norm(right) < 1e-6:
            right = np.array([1.0, 0.0, 0.0])
        right = _unit(right)
        up = np.cross(right, fwd)
        if roll:
            c, s = math.cos(roll), math.sin(roll)
            right, up = c * right + s * up, -s * right + c * up
        rot = np.stack([right, fwd, up], axis=1)                  # columns: body x, y, z in world
        q = np.empty(4)
        self._mj.mju_mat2Quat(q, rot.reshape(9))
        self.data.qpos[:3] = np.clip(p, self.bounds[0], self.bounds[1])
        self.data.qpos[3:7] = q
        self.forward()

    def apply(self, action: np.ndarray, dt: float) -> None:
        """Integrate a normalised action [6] for `dt` seconds."""
        a = np.asarray(action, dtype=np.float64)
        rot = self.data.xmat[self._root].reshape(3, 3)
        v_body = a[:3] * self.max_speed * self._extent
        # body angular velocity about (x right, y forward, z up): pitch about x, roll about y, yaw about z
        w_body = np.array([a[4], a[5], a[3]]) * self.max_turn_rate
        self._qvel[:3] = rot @ v_body
        self._qvel[3:] = w_body
        self._mj.mj_integratePos(self.model, self.data.qpos, self._qvel, float(dt))
        self.data.qpos[:3] = np.clip(self.data.qpos[:3], self.bounds[0], self.bounds[1])
        self._last = a.copy()
        self.forward()

    @property
    def position(self) -> np.ndarray:
        """[3] body position (a copy)."""
        return self.data.qpos[:3].copy()

    def proprio_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) [15] of `proprio` (positions within `POSITION_LIMIT` workspace scales)."""
        hi = np.concatenate([np.full(3, self.POSITION_LIMIT), np.ones(12)]).astype(np.float32)
        return -hi, hi

    def proprio(self) -> np.ndarray:
        """[15] float32: relative position, orientation (two rotation columns), last action."""
        rot = self.data.xmat[self._root].reshape(3, 3)
        rel = np.clip((self.data.qpos[:3] - self._centre) / self._extent, -self.POSITION_LIMIT, self.POSITION_LIMIT)
        return np.concatenate([rel, rot[:, 0], rot[:, 1], self._last]).astype(np.float32)


class ArmRig(Rig):
    """Kinematic 6-DoF arm (`arm6.xml`) with a wrist camera and an end-effector site.

    Action [6] in [-1, 1]: joint velocities (base yaw, shoulder, elbow, forearm roll, wrist
    pitch, wrist roll) scaled by `max_joint_rate` (rad/s), integrated and clipped to the
    joint ranges.

    Proprio [15]: joint angles [6] (rad), last normalised joint rates [6], end-effector
    position relative to the base divided by the arm's reach [3].
    """

    xml = "arm6.xml"
    root_body = "base"
    action_dim = 6
    proprio_dim = 15
    camera_name = "wrist"
    site_name = "end_effector"
    nominal_reach = 0.95            # shoulder to fingertips at nominal size
    nominal_shoulder = 0.14         # shoulder height above the base at nominal size
    home = np.array([0.0, -0.2, 0.6, 0.0, 0.9, 0.0])    # ready pose: arm raised, gripper forward and down

    def __init__(self, max_joint_rate: float = math.radians(90), **kw) -> None:
        super().__init__(**kw)
        self.max_joint_rate = float(max_joint_rate)
        self._last = np.zeros(6)
        self._site = self._id("site", self.site_name)

    def place(self, base: Sequence[float], facing: Sequence[float], reach: float) -> None:
        """Put the base at `base` (metres), turned so the arm's front (-y at zero yaw) faces
        `facing`, scaled so the shoulder-to-fingertip reach is `reach` metres; home pose."""
        base = np.asarray(base, dtype=np.float64)
        d = np.asarray(facing, dtype=np.float64) - base
        yaw = math.atan2(d[0], -d[1]) if np.hypot(d[0], d[1]) > 1e-9 else 0.0     # body -y towards `facing`
        super().place(base, yaw_quat(yaw), float(reach) / self.nominal_reach)
        self.set_joints(self.home)
        self._last = np.zeros(6)
        self.forward()

    @property
    def reach(self) -> float:
        """Shoulder-to-fingertip reach in metres at the current scale."""
        return self.nominal_reach * self.scale

    @property
    def shoulder(self) -> np.ndarray:
        """[3] world position of the shoulder joint."""
        return self.body_position("link2")

    def end_effector(self) -> np.ndarray:
        """[3] world position of the end-effector site."""
        return self.data.site_xpos[self._site].copy()

    def apply(self, action: np.ndarray, dt: float) -> None:
        """Integrate a normalised action [6] for `dt` seconds."""
        a = np.asarray(action, dtype=np.float64)
        self.integrate_joints(a * self.max_joint_rate, dt)
        self._last = a.copy()
        self.forward()

    def proprio_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) [15] of `proprio`."""
        r = self.joint_range
        reach = 1.0 + self.nominal_shoulder / self.nominal_reach
        return (np.concatenate([r[:, 0], -np.ones(6), np.full(3, -reach)]).astype(np.float32),
                np.concatenate([r[:, 1], np.ones(6), np.full(3, reach)]).astype(np.float32))

    def proprio(self) -> np.ndarray:
        """[15] float32: joint angles, last normalised rates, relative end-effector position."""
        rel = (self.end_effector() - self.data.xpos[self._root]) / self.reach
        return np.concatenate([self.qpos, self._last, rel]).astype(np.float32)


RIGS = {"pan_tilt": PanTiltRig, "free_camera": FreeCameraRig, "arm": ArmRig}

