"""Find: fly a free camera to find the object the instruction names and centre it.

Start: the camera is on a ring around the scene's focus point at `start_distance` x the
generation camera's distance (uniform in the range), at the generation camera's height
above the focus (x `start_height`), at a random azimuth, and then turned away from the
focus by a random yaw of `init_yaw_min_deg`..`init_yaw_max_deg` to either side, so the
target usually starts out of view. The position stays in a box around the focus
(`bound_radius` x the generation distance horizontally, from just above the ground to
`bound_height` x the generation distance).

Reward (sum of terms, in [-ctrl_cost, 1]):
  reward_facing  = facing_weight * tolerance(angle, (0, facing_angle_deg), pi / 2)
  reward_centred = centre_weight * visible * tolerance(d, (0, centre_radius), 1)
  reward_size    = size_weight * visible * tolerance(area, (min_area, 1), min_area)
  reward_ctrl    = -ctrl_cost * mean(action^2)
with angle between the camera's axis and the direction to the target's centre, d the
distance of the target's visible pixels' centroid from the image centre (half-image units)
and area the fraction of the image its visible pixels cover.

Success: the target is visible, centred (d <= centre_radius) and large enough
(area >= min_area) for `hold_steps` consecutive steps (latched; the episode terminates then
when the env has `terminate_on_success`).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from morphosim_gym.rig import FreeCameraRig

from .base import Evaluation, Task, TaskView
from .rewards import tolerance

__all__ = ["FindTask"]


class FindTask(Task):
    """Find and centre the named object (see the module docstring)."""

    kind = "find"
    task_camera = "eye"
    default_cameras = ("eye",)
    render_agent = False
    PARAMS = dict(
        fov_y_deg=60.0,
        max_speed=0.5,            # generation distances per second at action +-1
        max_turn_rate_deg=60.0,   # degrees per second at action +-1
        start_distance_min=0.9,   # start radius, in generation-camera distances
        start_distance_max=1.2,
        start_height=1.0,         # start height above the focus, in generation-camera heights
        init_yaw_min_deg=45.0,    # start yaw away from the focus, either side
        init_yaw_max_deg=150.0,
        bound_radius=2.0,
        bound_height=1.5,
        facing_angle_deg=10.0,
        facing_weight=0.2,
        centre_weight=0.5,
        size_weight=0.3,
        centre_radius=0.2,
        min_area=0.01,
        hold_steps=2.0,
        ctrl_cost=0.02,
    )

    def _validate_params(self) -> None:
        p = self.params
        w = p["facing_weight"] + p["centre_weight"] + p["size_weight"]
        if min(p["facing_weight"], p["centre_weight"], p["size_weight"]) < 0 or abs(w - 1.0) > 1e-6:
            raise ValueError(f"Expected non-negative facing/centre/size weights summing to 1, found sum {w}")
        if not 0 <= p["init_yaw_min_deg"] <= p["init_yaw_max_deg"] <= 180:
            raise ValueError("Expected 0 <= init_yaw_min_deg <= init_yaw_max_deg <= 180")
        if p["hold_steps"] < 1 or p["min_area"] <= 0 or p["ctrl_cost"] < 0:
            raise ValueError("Expected hold_steps >= 1, min_area > 0 and ctrl_cost >= 0")
        if not 0 < p["start_distance_min"] <= p["start_distance_max"]:
            raise ValueError("Expected 0 < start_distance_min <= start_distance_max")

    def make_rig(self) -> FreeCameraRig:
        return FreeCameraRig(max_speed=self.params["max_speed"],
                             max_turn_rate=math.radians(self.params["max_turn_rate_deg"]))

    def initialize_episode(self, world: Any, rig: FreeCameraRig, rng: np.random.Generator,
                           camera: Mapping[str, Any]) -> None:
        p = self.params
        focus = world.focus
        gen = world.generation_camera.position
        ext = world.extent
        height = max(float(gen[2] - focus[2]), 0.05 * ext)
        r = rng.uniform(p["start_distance_min"], p["start_distance_max"]) * math.hypot(*(gen[:2] - focus[:2]))
        az = rng.uniform(-math.pi, math.pi)
        yaw = math.radians(rng.uniform(p["init_yaw_min_deg"], p["init_yaw_max_deg"])) * (1 if rng.random() < 0.5 else -1)
        pos = focus + np.array([r * math.cos(az), r * math.sin(az), height * p["start_height"]])
        d = focus - pos
        c, s = math.cos(yaw), math.sin(yaw)
        look = pos + np.array([c * d[0] - s * d[1], s * d[0] + c * d[1], d[2]])
        bounds = np.array([[focus[0] - p["bound_radius"] * ext, focus[1] - p["bound_radius"] * ext,
                            world.ground_z + 0.03 * ext],
                           [focus[0] + p["bound_radius"] * ext, focus[1] + p["bound_radius"] * ext,
                            focus[2] + p["bound_height"] * ext]])
        if "position" in camera or "look_at" in camera:
            pos = camera.get("position", pos)
            look = camera.get("look_at", focus)
        rig.place(pos, look, centre=focus, extent=ext, bounds=bounds)
        rig.set_camera_fov("eye", camera.get("fov_y_deg", p["fov_y_deg"]))
        rig.forward()
        self._held = 0
        self._found = False

    def change_view(self, world: Any, rig: FreeCameraRig, fov_ratio: float, shift: np.ndarray) -> None:
        """The free camera moves by `shift` (orientation kept, within its bounds); its field of view
        scales (clipped to (1, 170) degrees)."""
        if np.any(shift):
            rig.data.qpos[:3] = np.clip(rig.data.qpos[:3] + np.asarray(shift, dtype=np.float64), *rig.bounds)
        if fov_ratio != 1.0:
            fov = rig.camera("eye", 16, 16).fov_y_deg
            rig.set_camera_fov("eye", float(np.clip(fov * fov_ratio, 1.0, 170.0)))
        rig.forward()

    def measure(self, world: Any, rig: FreeCameraRig, view: TaskView) -> dict[str, Any]:
        p = self.params
        target = world.target_position(view.t)
        if target is None:
            angle = math.pi
        else:
            to = target - view.camera.position
            n = float(np.linalg.norm(to))
            angle = math.acos(float(np.clip(view.camera.forward @ to / max(n, 1e-12), -1.0, 1.0)))
        count, d, area = self.mask_stats(view.instance, world.target.id)
        found = bool(count > 0 and d <= p["centre_radius"] and area >= p["min_area"])
        return {"target_angle": angle, "target_pixels": count, "target_offset": d, "target_area": area,
                "found_now": found}

    def evaluate(self, world: Any, rig: FreeCameraRig, view: TaskView, action: np.ndarray) -> Evaluation:
        p = self.params
        m = self.measure(world, rig, view)
        visible = 1.0 if m["target_pixels"] > 0 else 0.0
        terms = {
            "reward_facing": p["facing_weight"] * tolerance(m["target_angle"], (0.0, math.radians(p["facing_angle_deg"])),
                                                            math.pi / 2),
            "reward_centred": p["centre_weight"] * visible * tolerance(m["target_offset"], (0.0, p["centre_radius"]), 1.0),
            "reward_size": p["size_weight"] * visible * tolerance(m["target_area"], (p["min_area"], 1.0), p["min_area"]),
            "reward_ctrl": self.ctrl_term(action, p["ctrl_cost"]),
        }
        self._held = self._held + 1 if m["found_now"] else 0
        newly = self._held >= p["hold_steps"] and not self._found
        self._found = self._found or self._held >= p["hold_steps"]
        m["held_steps"] = self._held
        return Evaluation(sum(terms.values()), terms, self._found, bool(newly or self._found), m)

    def reset_metrics(self) -> dict[str, Any]:
        """Episode statistics at reset."""
        return {"held_steps": 0}
