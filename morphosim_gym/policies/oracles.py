"""The `oracle` policy: a scripted controller per task kind, reading the true target position from the env.

They are yardsticks, not learners: each reads `env.unwrapped.world.target_position(t)` (the
ground truth of the scene, after any edit) and the rig's state, and steers with a simple
feedback law. So a suite is meaningful without a trained model: the oracle shows what a
perfect perceiver achieves under each perturbation (a removed target, for instance, still
defeats it), the random policy what chance gives.
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from .task import task_kind

__all__ = ["oracle_policy", "TrackOracle", "ReachOracle", "FindOracle", "ORACLES", "make_oracle"]


def _unit_clip(v: np.ndarray) -> np.ndarray:
    """Scale a command so its largest component is within [-1, 1] (keeps its direction)."""
    m = float(np.max(np.abs(v))) if v.size else 0.0
    return v / m if m > 1.0 else v


class _Oracle:
    """Shared plumbing: the env's world, rig and control period."""

    lookahead = 1.0            # control periods ahead at which the target position is read

    def __init__(self, env: Any) -> None:
        self.env = env.unwrapped
        self.dt = float(self.env.dt)

    def target_ahead(self, steps: Optional[float] = None) -> Optional[np.ndarray]:
        """The target's true position `steps` control periods from now (None if it was removed)."""
        world = self.env.world
        t = min(world.t + (self.lookahead if steps is None else steps) * self.dt, world.duration)
        return world.target_position(t)

    def __call__(self, obs: Any, info: dict) -> np.ndarray:
        raise NotImplementedError


class TrackOracle(_Oracle):
    """Pan and tilt so the camera points at where the target will be after this step; zoom to keep
    its apparent size in the task's good range."""

    def __call__(self, obs: Any, info: dict) -> np.ndarray:
        rig = self.env.rig
        action = np.zeros(3, dtype=np.float32)
        target = self.target_ahead()
        if target is None:
            return action
        pan, tilt = rig.aim_angles(target)
        q = rig.qpos
        rates = np.array([pan - q[0], tilt - q[1]]) / self.dt / rig.max_rates[:2]
        action[:2] = np.clip(rates, -1.0, 1.0)
        size = float(info.get("target_size", 0.0))
        p = self.env.task.params
        if size > 0.0:
            goal = 0.5 * (p["size_min"] + p["size_max"])
            action[2] = float(np.clip(2.0 * (goal - size) / goal, -1.0, 1.0))
        return action


class ReachOracle(_Oracle):
    """Move the end-effector towards the target by damped least squares on the arm's Jacobian
    (computed on a private copy of the MuJoCo state, so the env's own state is untouched)."""

    lookahead = 2.0
    damping = 0.05             # in reaches

    def __init__(self, env: Any) -> None:
        super().__init__(env)
        import mujoco

        rig = self.env.rig
        self._mj = mujoco
        self._data = mujoco.MjData(rig.model)
        self._site = mujoco.mj_name2id(rig.model, mujoco.mjtObj.mjOBJ_SITE, rig.site_name)
        ids = [mujoco.mj_name2id(rig.model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in rig.joint_names]
        self._dofs = np.array([int(rig.model.jnt_dofadr[j]) for j in ids])

    def __call__(self, obs: Any, info: dict) -> np.ndarray:
        rig = self.env.rig
        target = self.target_ahead()
        if target is None:
            return np.zeros(rig.action_dim, dtype=np.float32)
        mj, d = self._mj, self._data
        d.qpos[:] = rig.data.qpos
        mj.mj_kinematics(rig.model, d)
        mj.mj_comPos(rig.model, d)
        jac = np.zeros((3, rig.model.nv))
        mj.mj_jacSite(rig.model, d, jac, None, self._site)
        j = jac[:, self._dofs]
        err = target - d.site_xpos[self._site]
        lam = self.damping * rig.reach
        dq = j.T @ np.linalg.solve(j @ j.T + lam * lam * np.eye(3), err)
        return _unit_clip(dq / self.dt / rig.max_joint_rate).astype(np.float32)


class FindOracle(_Oracle):
    """Turn the camera towards the target (yaw and pitch, roll level), then fly towards it until it
    covers a comfortable share of the image; rise when something hides it or it stays small."""

    area_goal = 0.03           # fraction of the image the target should cover (success needs 0.01)
    min_radii = 3.0            # closest approach, in target radii

    def __call__(self, obs: Any, info: dict) -> np.ndarray:
        env, rig = self.env, self.env.rig
        action = np.zeros(6, dtype=np.float32)
        target = self.target_ahead()
        if target is None:
            return action
        cam = rig.camera("eye", 64, 64)
        c2w = cam.camera_to_world
        rel = c2w[:3, :3].T @ (target - cam.position)          # camera frame: x right, y down, z forward
        x, y, z = rel
        yaw_err = math.atan2(-x, z)                              # positive turns left
        pitch_err = math.atan2(-y, math.hypot(x, z))             # positive looks up
        turn = rig.max_turn_rate * self.dt
        action[3] = np.clip(yaw_err / turn, -1.0, 1.0)
        action[4] = np.clip(pitch_err / turn, -1.0, 1.0)
        right = c2w[:3, 0]
        action[5] = np.clip(math.asin(float(np.clip(right[2], -1.0, 1.0))) / turn, -1.0, 1.0)  # level the horizon
        off = math.hypot(yaw_err, pitch_err)
        if off < math.radians(20.0) and z > 0:
            # approach while the target covers too little of the image, never closer than a few radii
            room = float(np.linalg.norm(rel)) - self.min_radii * max(env.world.target_radius, 1e-3)
            step = rig.max_speed * env.world.extent * self.dt
            area = float(info.get("target_area", 0.0))
            want = 1.0 if area < self.area_goal else 0.0
            action[1] = min(want, max(room / step, 0.0))
            if want and (room < step or info.get("target_pixels", 1) == 0):
                action[2] = 1.0                                  # close but small or hidden: rise to see over
        return action


ORACLES = {"track": TrackOracle, "reach": ReachOracle, "find": FindOracle}


def make_oracle(env: Any) -> _Oracle:
    """The oracle of the env's task kind."""
    kind = task_kind(env, "the oracle policy")
    if kind not in ORACLES:
        raise ValueError(f"Expected an env whose task kind is in {sorted(ORACLES)}, found {kind!r}")
    return ORACLES[kind](env)


def oracle_policy(env: Any, seed: int) -> _Oracle:
    """The scripted oracle of the env's task (deterministic; the seed is unused)."""
    return make_oracle(env)
