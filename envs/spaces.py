"""The env's spaces: the observation dict built from rendered views (`rgb`, and `depth`,
`segmentation`, per observed camera; `proprio` from the rig; the first camera's keys have no
suffix, each other camera `name` adds `_name`), and the action `Box` with its check."""

from __future__ import annotations

from typing import Any, Mapping, Optional, Sequence

import numpy as np
from gymnasium import spaces

from morphosim_gym.render.cpu.uint8 import to_uint8
from morphosim_gym.rig import AGENT_OBJECT_ID

__all__ = ["Observations", "observed_cameras", "action_space", "check_action"]


def observed_cameras(cameras: Optional[Sequence[str]], default: Sequence[str], rig_cameras: Sequence[str]) -> tuple:
    """The cameras to observe: `cameras` (None: `default`), checked against the rig's camera names."""
    cams = tuple(cameras) if cameras is not None else tuple(default)
    if not cams or len(set(cams)) != len(cams):
        raise ValueError(f"Expected one or more distinct camera names, found {cameras!r}")
    for c in cams:
        if c not in rig_cameras:
            raise ValueError(f"Expected cameras of the rig {rig_cameras}, found {c!r}")
    return cams


class Observations:
    """Builds observations from rendered views and the rig's proprioception.

    Args:
        cameras: the observed cameras, in order.
        width, height: image size, pixels.
        depth, segmentation: add those images.
        rig: the rig (`proprio_bounds()`, `proprio_dim`).

    Attributes:
        space: the `Dict` observation space.
    """

    def __init__(self, cameras: Sequence[str], width: int, height: int, depth: bool, segmentation: bool,
                 rig: Any) -> None:
        self.cameras = tuple(cameras)
        self._depth, self._segmentation = depth, segmentation
        self._keys = [(name, *(k + ("" if i == 0 else f"_{name}") for k in ("rgb", "depth", "segmentation")))
                      for i, name in enumerate(self.cameras)]
        obs: dict[str, spaces.Space] = {}
        for _, rgb, dep, seg in self._keys:
            obs[rgb] = spaces.Box(0, 255, (height, width, 3), np.uint8)
            if depth:
                obs[dep] = spaces.Box(0.0, np.inf, (height, width), np.float32)
            if segmentation:
                obs[seg] = spaces.Box(-1, AGENT_OBJECT_ID, (height, width), np.int32)
        low, high = rig.proprio_bounds()
        obs["proprio"] = spaces.Box(low, high, (rig.proprio_dim,), np.float32)
        self.space = spaces.Dict(obs)

    def __call__(self, views: Mapping[str, tuple], proprio: np.ndarray) -> dict[str, np.ndarray]:
        """The observation of `views` (camera name -> (camera, rgb, depth, instance)) and `proprio`."""
        obs: dict[str, np.ndarray] = {}
        for name, rgb_key, depth_key, seg_key in self._keys:
            _, rgb, depth, inst = views[name]
            obs[rgb_key] = to_uint8(rgb)
            if self._depth:
                obs[depth_key] = np.array(depth, dtype=np.float32)
            if self._segmentation:
                obs[seg_key] = np.array(inst, dtype=np.int32)
        obs["proprio"] = proprio
        return obs


def action_space(rig: Any) -> spaces.Box:
    """`Box(-1, 1, (rig.action_dim,), float32)`."""
    return spaces.Box(-1.0, 1.0, (rig.action_dim,), np.float32)


def check_action(action: Any, shape: tuple) -> np.ndarray:
    """The action as float64 clipped to [-1, 1]; `ValueError` for a wrong shape or a NaN / inf (the
    step is then not taken)."""
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"Expected an action of shape {shape}, found {action!r}") from exc
    if a.shape != shape:
        raise ValueError(f"Expected an action of shape {shape}, found shape {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = np.flatnonzero(~np.isfinite(a)).tolist()
        raise ValueError(f"Expected finite action values, found NaN or inf at indices {bad}; the step was "
                         "not taken")
    return np.clip(a, -1.0, 1.0)          # out-of-range values are clipped to the Box
