"""Gymnasium environments (installed as morphosim_gym.envs), registered on `import morphosim_gym`.

| id | task | rig | action |
|---|---|---|---|
| `MorphoSim/Track-v0` | keep the named moving object centred | pan-tilt camera on a tripod | pan, tilt, zoom rates [3] |
| `MorphoSim/Reach-v0` | intercept the moving object with the end-effector | kinematic 6-DoF arm | joint rates [6] |
| `MorphoSim/Find-v0` | find and centre the named object among distractors | free-flying camera | 6-DoF velocity [6] |

    import gymnasium as gym, morphosim_gym
    env = gym.make("MorphoSim/Track-v0", render_mode="rgb_array")
    obs, info = env.reset(seed=0, options={"edits": ["make the ball blue"]})

`ENTRY_POINTS` (task kind -> env class) is the one table behind the ids, `register_task` and
the benchmark's suites; every id's `vector_entry_point` (`vector_entry_of`) is the native
`MorphoSimVectorEnv`, which steps N worlds in one process and renders all their cameras in one
batched call. Every env takes the keyword arguments of `EnvConfig`. Registration
uses string entry points, so importing this package compiles no MuJoCo model and generates
no scene. The env classes, wrappers and the vector helper are imported lazily on first
attribute access.
"""

from __future__ import annotations

from typing import Any

from gymnasium.envs.registration import register, registry

__all__ = ["ENV_IDS", "ENTRY_POINTS", "env_id_of", "vector_entry_of", "TrackEnv", "ReachEnv", "FindEnv", "MorphoSimEnv",
           "MorphoSimVectorEnv", "EnvConfig", "LanguagePerturbation", "RGBObservation", "SensorEffects", "AxisRandomization", "make_vec",
           "register_task", "build_scenes", "ScenePoolError"]

ENTRY_POINTS = {
    "track": "morphosim_gym.envs.track:TrackEnv",
    "reach": "morphosim_gym.envs.reach:ReachEnv",
    "find": "morphosim_gym.envs.find:FindEnv",
}
"""Task kind -> the env class that runs it (string entry points: nothing is imported here)."""


def env_id_of(kind: str) -> str:
    """The registered id of a task kind's env ("track" -> "MorphoSim/Track-v0")."""
    return f"MorphoSim/{kind.capitalize()}-v0"


def vector_entry_of(kind: str) -> str:
    """The `vector_entry_point` of a task kind's ids: the native batched vector env
    (`gym.make_vec(id, n, vectorization_mode="vector_entry_point")`)."""
    return f"morphosim_gym.envs.native_vector:vector_{kind}"


ENV_IDS = tuple(env_id_of(kind) for kind in ENTRY_POINTS)

for _kind, _entry in ENTRY_POINTS.items():
    if env_id_of(_kind) not in registry:
        # No max_episode_steps: the clip ends the episode (truncation at its last frame), so a
        # changed control_hz or clip length never disagrees with a fixed step limit.
        register(id=env_id_of(_kind), entry_point=_entry, vector_entry_point=vector_entry_of(_kind),
                 disable_env_checker=False)

_LAZY = {
    "TrackEnv": "morphosim_gym.envs.track",
    "ReachEnv": "morphosim_gym.envs.reach",
    "FindEnv": "morphosim_gym.envs.find",
    "MorphoSimEnv": "morphosim_gym.envs.core",
    "EnvConfig": "morphosim_gym.envs.config",
    "LanguagePerturbation": "morphosim_gym.envs.wrappers",
    "RGBObservation": "morphosim_gym.envs.wrappers",
    "SensorEffects": "morphosim_gym.envs.sensor",
    "AxisRandomization": "morphosim_gym.envs.randomize",
    "make_vec": "morphosim_gym.envs.vector",
    "MorphoSimVectorEnv": "morphosim_gym.envs.native_vector",
    "register_task": "morphosim_gym.envs.vector",
    "build_scenes": "morphosim_gym.envs.pool",
    "ScenePoolError": "morphosim_gym.envs.pool",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
