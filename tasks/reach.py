"""Reach: bring the arm's end-effector to a moving object (interception).

Scene scale: the default scene distribution is tabletop objects (balls, cubes, mugs...)
moving on a table, and the arm is scaled to the scene rather than the scene to the arm:
its base stands on the target's resting surface behind the target's path (seen from the
generation camera), turned towards the path, and its shoulder-to-fingertip reach is
`reach_factor` times the farthest point of the path from the shoulder (at least
`min_reach_radii` target radii). So every point the target visits is reachable, in any
scene (a prompt with a bus gets a crane-sized arm).

Start: ready pose (arm raised above the base, gripper pointing forward and down) plus
uniform joint noise of
`init_noise` rad. The third-person camera "scene" looks at the arm and the path from the
generation camera's side, `view_azimuth_deg` around and `view_elevation_deg` up (or from
the `camera` override).

Reward (sum of terms, in [-ctrl_cost, 1]):
  reward_reach = tolerance(dist, (0, success_distance), reach_margin * reach)
  reward_ctrl  = -ctrl_cost * mean(action^2)
with dist the distance from the end-effector site to the target's centre and
success_distance = target radius + success_margin * reach.

Success: dist <= success_distance at some step (the episode terminates then when the env
has `terminate_on_success`).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from morphosim_gym.rig import ArmRig
from morphosim_gym.scene.camera import Camera

from .base import Evaluation, Task, TaskView
from .rewards import tolerance

__all__ = ["ReachTask"]


class ReachTask(Task):
    """Intercept the target with the end-effector (see the module docstring)."""

    kind = "reach"
    task_camera = "scene"
    default_cameras = ("scene",)
    render_agent = True
    PARAMS = dict(
        reach_factor=1.3,          # arm reach / farthest path point from the shoulder
        min_reach_radii=4.0,       # the reach is at least this many target radii
        standoff_radii=2.5,        # base distance behind the path, in target radii (plus half the path)
        max_joint_rate_deg=90.0,   # degrees per second at action +-1
        init_noise=0.15,           # rad, uniform per joint around the home pose
        success_margin=0.05,       # success distance = target radius + this * reach
        reach_margin=0.5,          # tolerance margin, in reaches
        ctrl_cost=0.02,
        view_fov_deg=50.0,
        view_azimuth_deg=40.0,
        view_elevation_deg=30.0,
    )

    def _validate_params(self) -> None:
        p = self.params
        if p["reach_factor"] < 1.0:
            raise ValueError(f"Expected reach_factor >= 1 (the path must be reachable), found {p['reach_factor']}")
        if p["ctrl_cost"] < 0 or p["success_margin"] < 0 or p["reach_margin"] <= 0:
            raise ValueError("Expected ctrl_cost >= 0, success_margin >= 0 and reach_margin > 0")
        if not 0 < p["view_fov_deg"] < 180:
            raise ValueError(f"Expected view_fov_deg in (0, 180), found {p['view_fov_deg']}")

    def make_rig(self) -> ArmRig:
        return ArmRig(max_joint_rate=math.radians(self.params["max_joint_rate_deg"]))

    def initialize_episode(self, world: Any, rig: ArmRig, rng: np.random.Generator,
                           camera: Mapping[str, Any]) -> None:
        p = self.params
        path = world.target_path(25)
        rad = max(world.target_radius, 1e-3)
        mid = path.mean(axis=0)
        away = mid[:2] - world.generation_camera.position[:2]
        away = away / max(np.linalg.norm(away), 1e-9)
        along = np.abs((path[:, :2] - mid[:2]) @ away).max()
        base = np.array([mid[0] + away[0] * (along + p["standoff_radii"] * rad),
                         mid[1] + away[1] * (along + p["standoff_radii"] * rad), world.target_floor])
        reach = p["min_reach_radii"] * rad
        shoulder_frac = ArmRig.nominal_shoulder / ArmRig.nominal_reach
        for _ in range(8):                                   # the shoulder height depends on the reach
            shoulder = base + np.array([0.0, 0.0, shoulder_frac * reach])
            reach = max(p["reach_factor"] * float(np.linalg.norm(path - shoulder, axis=1).max()),
                        p["min_reach_radii"] * rad)
        rig.place(base, mid, reach)
        q = ArmRig.home + rng.uniform(-1.0, 1.0, 6) * p["init_noise"]
        rig.set_joints(q)
        rig.forward()
        self.success_distance = rad + p["success_margin"] * reach
        self._reached = False
        # third-person view of the arm and the path
        if "position" in camera or "look_at" in camera:
            look = camera.get("look_at", mid)
            eye = camera.get("position", world.generation_camera.position)
        else:
            pts = np.vstack([path, base, base + np.array([0.0, 0.0, 0.9 * reach])])
            look = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
            radius = float(np.linalg.norm(pts - look, axis=1).max()) + rad
            dist = radius / math.sin(math.radians(p["view_fov_deg"]) / 2) * 0.9
            back = world.generation_camera.position[:2] - look[:2]
            az = math.atan2(back[1], back[0]) + math.radians(p["view_azimuth_deg"])
            el = math.radians(p["view_elevation_deg"])
            eye = look + dist * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        fov = camera.get("fov_y_deg", p["view_fov_deg"])
        rig.set_world_camera("scene", Camera.look_at(eye, look, 16, 16, fov))
        rig.forward()

    def change_view(self, world: Any, rig: ArmRig, fov_ratio: float, shift: np.ndarray) -> None:
        """The third-person camera moves by `shift` (looking the same way); its field of view scales
        (clipped to (1, 170) degrees)."""
        cam = rig.camera("scene", 16, 16)
        eye = cam.position + np.asarray(shift, dtype=np.float64)
        fov = float(np.clip(cam.fov_y_deg * fov_ratio, 1.0, 170.0))
        rig.set_world_camera("scene", Camera.look_at(eye, eye + cam.camera_to_world[:3, 2], 16, 16, fov))
        rig.forward()

    def measure(self, world: Any, rig: ArmRig, view: TaskView) -> dict[str, Any]:
        target = world.target_position(view.t)
        ee = rig.end_effector()
        dist = float(np.linalg.norm(ee - target)) if target is not None else float("inf")
        return {"distance": dist, "success_distance": self.success_distance, "reach": rig.reach,
                "end_effector": ee, "target_visible_pixels": int(np.count_nonzero(view.instance == world.target.id))}

    def evaluate(self, world: Any, rig: ArmRig, view: TaskView, action: np.ndarray) -> Evaluation:
        p = self.params
        m = self.measure(world, rig, view)
        dist = m["distance"]
        near = tolerance(dist, (0.0, self.success_distance), p["reach_margin"] * rig.reach) if math.isfinite(dist) else 0.0
        terms = {"reward_reach": near, "reward_ctrl": self.ctrl_term(action, p["ctrl_cost"])}
        hit = bool(dist <= self.success_distance)
        self._reached = self._reached or hit
        m["reached_now"] = hit
        return Evaluation(sum(terms.values()), terms, self._reached, hit, m)

    def reset_metrics(self) -> dict[str, Any]:
        """Episode statistics at reset."""
        return {"reached_now": False}
