"""The features of a dataset recorded from a MorphoSim env, named as LeRobot names them.

| feature | dtype | shape | from |
|---|---|---|---|
| `observation.images.<camera>` | video | [H, W, 3] | `obs["rgb"]` (first camera), `obs["rgb_<camera>"]` |
| `observation.state` | float32 | [P] | `obs["proprio"]` |
| `action` | float32 | [A] | the action applied at this frame |
| `next.reward` | float32 | [1] | the step's reward |
| `next.done` | bool | [1] | terminated or truncated after the step |
| `next.truncated` | bool | [1] | truncated after the step |
| `next.success` | bool | [1] | `info["success"]` after the step |

plus LeRobot's own `timestamp`, `frame_index`, `episode_index`, `index`, `task_index`. Depth and
segmentation observations are not recorded.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Optional, Sequence

import numpy as np

__all__ = ["FrameSchema", "DEFAULT_FEATURES", "IMAGE_PREFIX", "STATE", "ACTION", "SCALARS"]

IMAGE_PREFIX = "observation.images."
STATE = "observation.state"
ACTION = "action"
SCALARS = {"next.reward": "float32", "next.done": "bool", "next.truncated": "bool", "next.success": "bool"}
DEFAULT_FEATURES = {
    "timestamp": {"dtype": "float32", "shape": [1], "names": None},
    "frame_index": {"dtype": "int64", "shape": [1], "names": None},
    "episode_index": {"dtype": "int64", "shape": [1], "names": None},
    "index": {"dtype": "int64", "shape": [1], "names": None},
    "task_index": {"dtype": "int64", "shape": [1], "names": None},
}


@dataclass(frozen=True)
class FrameSchema:
    """What one frame holds.

    Attributes:
        cameras: (observation key, camera name) per recorded camera, in order.
        height, width: image size, pixels.
        state_dim, action_dim: sizes of `observation.state` and `action`.
        state_names, action_names: a name per dimension.
    """

    cameras: tuple[tuple[str, str], ...]
    height: int
    width: int
    state_dim: int
    action_dim: int
    state_names: tuple[str, ...] = ()
    action_names: tuple[str, ...] = ()

    @classmethod
    def from_env(cls, env: Any) -> "FrameSchema":
        """The schema of a MorphoSim env (its observed cameras, proprio and action sizes)."""
        from morphosim_gym.envs.spaces import observed_cameras

        u = env.unwrapped
        names = observed_cameras(u.config.cameras, u.task.default_cameras, u.rig.camera_names)
        keys = [("rgb" if i == 0 else f"rgb_{n}", n) for i, n in enumerate(names)]
        h, w, _ = env.observation_space["rgb"].shape
        p, a = env.observation_space["proprio"].shape[0], env.action_space.shape[0]
        return cls(tuple(keys), int(h), int(w), int(p), int(a),
                   tuple(getattr(u.rig, "proprio_names", None) or [f"proprio_{i}" for i in range(p)]),
                   tuple(getattr(u.rig, "action_names", None) or [f"action_{i}" for i in range(a)]))

    @property
    def video_keys(self) -> list[str]:
        return [IMAGE_PREFIX + name for _, name in self.cameras]

    def features(self, video_infos: Optional[Mapping[str, dict]] = None) -> dict[str, dict]:
        """`info.json`'s `features` (video `info` blocks from `video_infos` by key)."""
        out: dict[str, dict] = {}
        for key in self.video_keys:
            out[key] = {"dtype": "video", "shape": [self.height, self.width, 3],
                        "names": ["height", "width", "channels"], "info": dict((video_infos or {}).get(key, {}))}
        out[STATE] = {"dtype": "float32", "shape": [self.state_dim], "names": list(self.state_names)}
        out[ACTION] = {"dtype": "float32", "shape": [self.action_dim], "names": list(self.action_names)}
        for key, dtype in SCALARS.items():
            out[key] = {"dtype": dtype, "shape": [1], "names": None}
        out.update({k: dict(v) for k, v in DEFAULT_FEATURES.items()})
        return out

    def check(self, observations: Mapping[str, np.ndarray], actions: np.ndarray, where: str) -> None:
        """Raise a clear error when an episode's arrays do not fit the schema."""
        want: dict[str, Sequence[int]] = {k: (self.height, self.width, 3) for k, _ in self.cameras}
        want["proprio"] = (self.state_dim,)
        for k, shape in want.items():
            if k not in observations:
                raise ValueError(f"Expected observation {k!r} in {where}, found keys {sorted(observations)}")
            if tuple(observations[k].shape[1:]) != tuple(shape):
                raise ValueError(f"Expected {k!r} frames of shape {tuple(shape)} in {where}, found "
                                 f"{tuple(observations[k].shape[1:])}")
        if actions.ndim != 2 or actions.shape[1] != self.action_dim:
            raise ValueError(f"Expected actions [T, {self.action_dim}] in {where}, found {actions.shape}")
