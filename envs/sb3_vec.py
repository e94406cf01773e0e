"""`SB3VecEnv`: our native vector env (`MorphoSimVectorEnv`) as a Stable-Baselines3 `VecEnv`, so SB3
algorithms step all N worlds with one batched render per step instead of N single envs under
SB3's `DummyVecEnv` / `SubprocVecEnv`.

Needs stable-baselines3 (the `train` extra); importing this module without it raises an
ImportError that says so. SB3's conventions are kept: `step_wait` resets an env in the same
step it ends (its info holds "terminal_observation" and "TimeLimit.truncated"), `seed(s)` seeds
env i with s + i at the next `reset()`, infos are one dict per env. Env i then gives exactly what
`DummyVecEnv` of single envs gives (tests/envs/test_sb3_vec.py).
"""

from __future__ import annotations

from typing import Any, Iterable, Optional, Sequence

import numpy as np

try:
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv
except ImportError as exc:                              # pragma: no cover - depends on the install
    raise ImportError("Expected stable-baselines3 for morphosim_gym.envs.sb3_vec, found it missing; "
                      "pip install 'morphosim-gym[train]'") from exc

from .native_vector import MorphoSimVectorEnv

__all__ = ["SB3VecEnv", "split_infos"]


class SB3VecEnv(VecEnv):
    """A `MorphoSimVectorEnv` behind SB3's `VecEnv` interface.

    Args:
        venv: the native vector env (e.g. `make_vec(id, 8, vectorization_mode="vector", ...)`).
        obs_key: keep only this key of the observation dict (e.g. "rgb" for `CnnPolicy`, as the
            `RGBObservation` wrapper does for single envs); None keeps the dict.

    Examples:
        >>> from morphosim_gym.envs import make_vec
        >>> venv = SB3VecEnv(make_vec("MorphoSim/Track-v0", 8, vectorization_mode="vector"), obs_key="rgb")  # doctest: +SKIP
        >>> model = PPO("CnnPolicy", VecFrameStack(venv, 3))  # doctest: +SKIP
    """

    def __init__(self, venv: MorphoSimVectorEnv, obs_key: Optional[str] = None) -> None:
        if not isinstance(venv, MorphoSimVectorEnv):
            raise ValueError(f"Expected a MorphoSimVectorEnv, found {type(venv).__name__}")
        space = venv.single_observation_space
        if obs_key is not None:
            if not hasattr(space, "spaces") or obs_key not in space.spaces:
                raise ValueError(f"Expected obs_key among the observation keys {sorted(getattr(space, 'spaces', {}))}, "
                                 f"found {obs_key!r}")
            space = space.spaces[obs_key]
        self.venv = venv
        self.obs_key = obs_key
        self._actions: Optional[np.ndarray] = None
        super().__init__(venv.num_envs, space, venv.single_action_space)
        self.render_mode = venv.render_mode

    # ------------------------------------------------------------------ stepping
    def reset(self) -> Any:
        seeds = list(self._seeds) if any(s is not None for s in self._seeds) else None
        options = [dict(o) if o else None for o in self._options]
        obs, infos = self.venv.reset(seed=seeds, options=options if any(options) else None)
        self.reset_infos = split_infos(infos, self.num_envs)
        self._reset_seeds()
        self._reset_options()
        return self._select(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> tuple[Any, np.ndarray, np.ndarray, list[dict]]:
        if self._actions is None:
            raise RuntimeError("Expected step_async(actions) before step_wait(), found no actions")
        actions, self._actions = self._actions, None
        obs, rewards, terms, truncs, infos = self.venv.step(actions)
        dones = terms | truncs
        per_env = split_infos(infos, self.num_envs)
        obs = self._select(obs)
        for i in range(self.num_envs):                     # as DummyVecEnv: on every step
            per_env[i]["TimeLimit.truncated"] = bool(truncs[i] and not terms[i])
        if dones.any():
            for i in np.flatnonzero(dones):
                per_env[i]["terminal_observation"] = _item(obs, int(i))
            new, reset_infos = self.venv.reset(options={"reset_mask": dones})   # SB3 resets in the same step
            new = self._select(new)
            fresh = split_infos(reset_infos, self.num_envs)
            for i in np.flatnonzero(dones):
                self.reset_infos[i] = fresh[i]
            obs = _merge(obs, new, dones)
        return obs, rewards.astype(np.float32), dones, per_env

    def _select(self, obs: Any) -> Any:
        return obs[self.obs_key] if self.obs_key is not None else obs

    # ------------------------------------------------------------------ per-env access
    def get_attr(self, attr_name: str, indices: Any = None) -> list:
        return [getattr(self.venv.envs[i], attr_name) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        for i in self._get_indices(indices):
            setattr(self.venv.envs[i], attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any) -> list:
        return [getattr(self.venv.envs[i], method_name)(*method_args, **method_kwargs)
                for i in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]       # the batch holds plain MorphoSimEnvs

    def get_images(self) -> Sequence[Optional[np.ndarray]]:
        return [env.render() for env in self.venv.envs]

    def close(self) -> None:
        self.venv.close()

    def _get_indices(self, indices: Any) -> Iterable[int]:
        if indices is None:
            return range(self.num_envs)
        if isinstance(indices, (int, np.integer)):
            return [int(indices)]
        return [int(i) for i in indices]


def split_infos(infos: dict, n: int) -> list[dict]:
    """A Gymnasium vector info dict (values with `_key` masks, nested dicts alike) as one dict per env."""
    out: list[dict] = [{} for _ in range(n)]
    for key, value in infos.items():
        if isinstance(key, str) and key.startswith("_"):
            continue
        mask = infos.get(f"_{key}")
        subs = split_infos(value, n) if isinstance(value, dict) else None
        for i in range(n):
            if mask is None or mask[i]:
                v = subs[i] if subs is not None else value[i]
                out[i][key] = v.item() if isinstance(v, np.generic) else v
    return out


def _item(obs: Any, i: int) -> Any:
    if isinstance(obs, dict):
        return {k: v[i].copy() for k, v in obs.items()}
    return obs[i].copy()


def _merge(obs: Any, new: Any, mask: np.ndarray) -> Any:
    """`obs` with the rows of `mask` taken from `new` (a fresh array)."""
    if isinstance(obs, dict):
        return {k: _merge(obs[k], new[k], mask) for k in obs}
    out = np.array(obs, copy=True)
    out[mask] = new[mask]
    return out
