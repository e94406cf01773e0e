"""Gymnasium environments (installed as morphosim_gym.envs), registered on `import morphosim_gym`.

| id | task | rig | action |
|---|---|---|---|
| `MorphoSim/Track-v0` | keep the named moving object centred | pan-tilt camera on a tripod | pan, tilt, zoom rates [3] |
| `MorphoSim/Reach-v0` | intercept the moving object with the end-effector | kinematic 6-DoF arm | joint rates [6] |
| `MorphoSim/Find-v0` | find and centre the named object among distractors | free-flying camera | 6-DoF velocity [6] |

    import gymnasium as gym, morphosim_gym
    env = gym.make("MorphoSim/Track-v0", render_mode="rgb_array")
    obs, info = env.reset(seed=0, options={"edits": ["make the ball blue"]})

Registration uses string entry points, so importing this package compiles no MuJoCo model
and generates no scene. The env classes, wrappers and the vector helper are imported
lazily on first attribute access.
"""

from __future__ import annotations

from typing import Any

from gymnasium.envs.registration import register, registry

__all__ = ["ENV_IDS", "TrackEnv", "ReachEnv", "FindEnv", "MorphoSimEnv", "LanguagePerturbation", "RGBObservation",
           "make_vec", "register_task"]

ENV_IDS = ("MorphoSim/Track-v0", "MorphoSim/Reach-v0", "MorphoSim/Find-v0")

_ENTRY = {
    "MorphoSim/Track-v0": "morphosim_gym.envs.track:TrackEnv",
    "MorphoSim/Reach-v0": "morphosim_gym.envs.reach:ReachEnv",
    "MorphoSim/Find-v0": "morphosim_gym.envs.find:FindEnv",
}

for _id, _entry in _ENTRY.items():
    if _id not in registry:
        # No max_episode_steps: the clip ends the episode (truncation at its last frame), so a
        # changed control_hz or clip length never disagrees with a fixed step limit.
        register(id=_id, entry_point=_entry, disable_env_checker=False)

_LAZY = {
    "TrackEnv": "morphosim_gym.envs.track",
    "ReachEnv": "morphosim_gym.envs.reach",
    "FindEnv": "morphosim_gym.envs.find",
    "MorphoSimEnv": "morphosim_gym.envs.core",
    "LanguagePerturbation": "morphosim_gym.envs.wrappers",
    "RGBObservation": "morphosim_gym.envs.wrappers",
    "make_vec": "morphosim_gym.envs.vector",
    "register_task": "morphosim_gym.envs.vector",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
