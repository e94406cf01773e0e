"""Reshaping planned trajectories over time: falls under gravity and second motion stages.

- `fall`: a straight downward motion of something that neither flies nor swims is a fall: it starts
  `drop` metres above its rest height and accelerates (constant acceleration, landing at 60 % of the
  clip) until it rests on the surface under it, where it stays: it never sinks into it.
- `second_stage`: "the ball rolls left then stops / reverses / speeds up". Stop and reverse: the
  whole planned path plays over the first half of the clip (twice the planned pace, so that the
  first stage is seen in full), then the object stays where it arrived, or goes back along it. Speed:
  the first half of the path at the planned pace, then `factor` times faster.

Both return a new `PlannedTrajectory` whose key points, boxes and velocities are projected again
from the new world positions (lambdas, the planner's spacing factors, are kept).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..scene import Camera
from .trajectory import PlannedTrajectory, _project_boxes

__all__ = ["FALL_HEIGHTS", "FALL_LANDING", "fall_drop", "is_fall", "fall", "second_stage"]

FALL_LANDING = 0.6          # fraction of the clip at which a fall reaches the surface
FALL_HEIGHTS = 1.0          # a fall starts this many object heights above the surface


def is_fall(direction: Sequence[float] | None, path: str, mobility: str) -> bool:
    """A straight motion straight down of an object that rests on a surface."""
    return (path == "straight" and direction is not None and float(direction[2]) < -0.95
            and mobility not in ("air", "swim", "float"))


def fall_drop(half: Sequence[float]) -> float:
    """How high above its rest height a fall starts, metres (`FALL_HEIGHTS` object heights)."""
    return FALL_HEIGHTS * 2.0 * float(half[2])


def _reproject(traj: PlannedTrajectory, pos: np.ndarray, headings: np.ndarray, spins: np.ndarray,
               cameras: Sequence[Camera], half: np.ndarray, anchor_is_base: bool) -> PlannedTrajectory:
    kp = cameras[0].project(pos)[0]
    fps = 1.0 / float(traj.times[1] - traj.times[0]) if len(traj.times) > 1 else 1.0
    disp = np.vstack([np.diff(kp, axis=0), np.zeros((1, 2))])
    boxes = _project_boxes(cameras, pos, headings, half, anchor_is_base, np.abs(disp) / 2)
    v = np.linalg.norm(np.diff(kp, axis=0), axis=1) * fps
    return replace(traj, keypoints=kp, boxes=boxes, velocities=v, positions=pos, headings=headings, spins=spins)


def fall(traj: PlannedTrajectory, rest_z: float, drop: float, cameras: Sequence[Camera],
         half: Sequence[float]) -> PlannedTrajectory:
    """The trajectory of a fall from `drop` metres above `rest_z` onto it (x, y of the first frame)."""
    T = len(traj.positions)
    tau = np.arange(T) / max(T - 1, 1) / FALL_LANDING
    pos = np.repeat(traj.positions[:1], T, axis=0).astype(np.float64)
    pos[:, 2] = rest_z + drop * np.clip(1.0 - tau ** 2, 0.0, 1.0)
    headings = np.repeat(traj.headings[:1], T)
    spins = np.zeros(T)
    return _reproject(traj, pos, headings, spins, cameras, np.asarray(half, dtype=np.float64), True)


def _frame_map(op: Any, T: int) -> np.ndarray:
    """Fractional frame of the first stage shown at each frame of the clip."""
    mid = (T - 1) / 2.0
    i = np.arange(T, dtype=np.float64)
    after = i > mid
    if op.op == "stop":               # the whole planned path over the first half, then still
        return np.minimum(2 * i, T - 1.0)
    if op.op == "reverse":            # the whole path out over the first half, back over the second
        return np.where(after, np.maximum(2 * (T - 1 - i), 0.0), 2 * i)
    if op.op == "speed":
        factor = float(op.factor if op.factor is not None else op.speed)
        return np.where(after, np.minimum(mid + (i - mid) * factor, T - 1.0), i)
    raise ValueError(f"Expected a second stage in ('stop', 'reverse', 'speed'), found {op.op!r}")


def _sample(a: np.ndarray, frames: np.ndarray) -> np.ndarray:
    lo = np.floor(frames).astype(int)
    hi = np.minimum(lo + 1, len(a) - 1)
    w = (frames - lo).reshape((-1,) + (1,) * (a.ndim - 1))
    return a[lo] * (1 - w) + a[hi] * w


def second_stage(traj: PlannedTrajectory, op: Any, cameras: Sequence[Camera], half: Sequence[float],
                 anchor_is_base: bool) -> PlannedTrajectory:
    """The first half of `traj`, then its second stage (`op`: a stop, reverse or speed `EditOp`)."""
    frames = _frame_map(op, len(traj.positions))
    spins = _sample(traj.spins, frames) if len(traj.spins) else traj.spins
    return _reproject(traj, _sample(traj.positions, frames), _sample(traj.headings, frames), spins, cameras,
                      np.asarray(half, dtype=np.float64), anchor_is_base)
