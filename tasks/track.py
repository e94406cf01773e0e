"""Track: keep a named moving object centred with a pan-tilt camera.

Start: the tripod stands at the scene's generation camera (or `camera.position`), facing
the scene; the camera is aimed at the target's start position plus a random pan and tilt
offset of up to `init_offset` half-fields of view each, at `fov_y_deg`.

Reward (sum of terms, in [-ctrl_cost, 1]):
  reward_centred = (1 - framing_weight) * c
  reward_framing = framing_weight * c * f
  reward_ctrl    = -ctrl_cost * mean(action^2)
with c = tolerance(d, (0, centre_radius), centre_margin, "long_tail") for d the distance of the target's
projected centre from the image centre in half-image units, and f = tolerance(size,
(size_min, size_max), size_margin) for size the target's apparent diameter as a fraction of
the image height (zoom changes it).

Success (episode level): the target was centred (d <= centre_radius and at least
`min_pixels` of it visible) on at least `success_fraction` of the steps so far.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from morphosim_gym.rig import PanTiltRig

from .base import Evaluation, Task, TaskView
from .rewards import tolerance

__all__ = ["TrackTask"]


class TrackTask(Task):
    """Keep the target centred in the pan-tilt camera's view (see the module docstring)."""

    kind = "track"
    task_camera = "eye"
    default_cameras = ("eye",)
    render_agent = False
    PARAMS = dict(
        fov_y_deg=30.0,          # start zoom (vertical field of view, degrees)
        fov_min_deg=12.0,        # zoom range
        fov_max_deg=50.0,
        max_pan_rate_deg=60.0,   # degrees per second at action +-1
        max_tilt_rate_deg=45.0,
        max_zoom_rate_deg=20.0,  # degrees of field of view per second at action +-1
        init_offset=0.6,         # start aim error, in half-fields of view (uniform per axis)
        centre_radius=0.15,      # "centred": within this many half-image units of the centre
        centre_margin=0.5,       # long-tailed: 0.55 at twice the radius, still > 0 across the image
        size_min=0.12,           # good apparent size (fraction of the image height)
        size_max=0.6,
        size_margin=0.15,
        framing_weight=0.2,
        ctrl_cost=0.02,
        success_fraction=0.7,
        min_pixels=4.0,
    )

    def _validate_params(self) -> None:
        p = self.params
        if not 0 < p["fov_min_deg"] <= p["fov_y_deg"] <= p["fov_max_deg"] < 180:
            raise ValueError(f"Expected 0 < fov_min_deg <= fov_y_deg <= fov_max_deg < 180, found "
                             f"{p['fov_min_deg']}, {p['fov_y_deg']}, {p['fov_max_deg']}")
        if not 0 <= p["framing_weight"] <= 1:
            raise ValueError(f"Expected framing_weight in [0, 1], found {p['framing_weight']}")
        if not 0 < p["success_fraction"] <= 1:
            raise ValueError(f"Expected success_fraction in (0, 1], found {p['success_fraction']}")
        if p["centre_radius"] <= 0 or p["ctrl_cost"] < 0:
            raise ValueError("Expected centre_radius > 0 and ctrl_cost >= 0, found "
                             f"{p['centre_radius']} and {p['ctrl_cost']}")

    def make_rig(self) -> PanTiltRig:
        p = self.params
        return PanTiltRig(fov_range=(p["fov_min_deg"], p["fov_max_deg"]),
                          max_pan_rate=math.radians(p["max_pan_rate_deg"]),
                          max_tilt_rate=math.radians(p["max_tilt_rate_deg"]),
                          max_zoom_rate=p["max_zoom_rate_deg"])

    def initialize_episode(self, world: Any, rig: PanTiltRig, rng: np.random.Generator,
                           camera: Mapping[str, Any]) -> None:
        p = self.params
        eye = camera.get("position", world.generation_camera.position)
        fov = camera.get("fov_y_deg", p["fov_y_deg"])
        rig.place(eye, world.focus, ground_z=world.ground_z, fov_deg=fov)
        self._eye = np.asarray(eye, dtype=np.float64).copy()
        half = math.radians(rig.fov) / 2
        offset = rng.uniform(-1.0, 1.0, 2) * p["init_offset"] * half
        aim = camera.get("look_at")
        if aim is None:
            aim = world.target_position(0.0)
            if aim is None:
                aim = world.focus
        else:
            offset = np.zeros(2)
        rig.aim_at(aim, offset)
        self._steps = 0
        self._centred = 0

    def change_view(self, world: Any, rig: PanTiltRig, fov_ratio: float, shift: np.ndarray) -> None:
        """The tripod moves with the generation camera (pan and tilt kept, pan 0 still facing the
        scene's focus, feet on the ground); the zoom's field of view scales (within the rig's range)."""
        if np.any(shift):
            q, fov = rig.qpos.copy(), rig.fov
            self._eye = self._eye + np.asarray(shift, dtype=np.float64)
            rig.place(self._eye, world.focus, ground_z=world.ground_z, fov_deg=fov)
            rig.set_joints(q)
        if fov_ratio != 1.0:
            rig.set_fov(rig.fov * fov_ratio)
        rig.forward()

    def measure(self, world: Any, rig: PanTiltRig, view: TaskView) -> dict[str, Any]:
        p = self.params
        target = world.target_position(view.t)
        d, z = self.pixel_offset(view.camera, target)
        pixels = int(np.count_nonzero(view.instance == world.target.id))
        size = 0.0
        if target is not None and z > view.camera.near:
            size = 2.0 * world.target_radius * view.camera.fy / z / view.camera.height
        centred = bool(pixels >= p["min_pixels"] and d <= p["centre_radius"])
        return {"target_offset": d, "target_pixels": pixels, "target_size": size, "centred": centred,
                "fov_y_deg": rig.fov}

    def evaluate(self, world: Any, rig: PanTiltRig, view: TaskView, action: np.ndarray) -> Evaluation:
        p = self.params
        m = self.measure(world, rig, view)
        c = tolerance(m["target_offset"], (0.0, p["centre_radius"]), p["centre_margin"], sigmoid="long_tail")
        f = tolerance(m["target_size"], (p["size_min"], p["size_max"]), p["size_margin"])
        w = p["framing_weight"]
        terms = {"reward_centred": (1.0 - w) * c, "reward_framing": w * c * f,
                 "reward_ctrl": self.ctrl_term(action, p["ctrl_cost"])}
        self._steps += 1
        self._centred += int(m["centred"])
        frac = self._centred / self._steps
        m["centred_fraction"] = frac
        return Evaluation(sum(terms.values()), terms, bool(frac >= p["success_fraction"]), False, m)

    def reset_metrics(self) -> dict[str, Any]:
        """Episode statistics at reset."""
        return {"centred_fraction": 0.0}
