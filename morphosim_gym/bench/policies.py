"""Policies for benchmark sweeps: the factory protocol, loading `module:callable`, built-ins.

A policy factory is any callable `factory(env, seed) -> act`, called once per episode with the
episode's env (after nothing else touched it) and the episode's policy seed; `act(obs, info)`
returns an action for the env's action space. The runner calls the factory again for every
episode, so a policy carries no state from one episode to the next, and a perturbed episode
sees the same policy seed as its base twin.

    def make_policy(env, seed):
        model = load_my_model()                    # cache it at module level in real code
        return lambda obs, info: model.predict(obs, deterministic=True)[0]

    morphosim bench track --policy my_pkg.policies:make_policy

Built-ins: `random` (uniform actions from the seed), `oracle` (a scripted controller per
task that reads the true target position; see `oracles.py`) and `color` (finds the target in
the image by the instruction's colour word, Track and Find; see `color_policy.py`).
"""

from __future__ import annotations

import importlib
from typing import Any, Callable

import numpy as np

from .oracles import make_oracle

__all__ = ["PolicyFactory", "Act", "BUILTIN_POLICIES", "load_policy", "random_policy", "oracle_policy"]

Act = Callable[[Any, dict], Any]
PolicyFactory = Callable[[Any, int], Act]

BUILTIN_POLICIES = {
    "random": "morphosim_gym.bench.policies:random_policy",
    "oracle": "morphosim_gym.bench.policies:oracle_policy",
    "color": "morphosim_gym.bench.color_policy:color_policy",
}


def random_policy(env: Any, seed: int) -> Act:
    """Uniform random actions in the env's action box, drawn from `seed`."""
    rng = np.random.default_rng([int(seed), 0xAC7])
    space = env.action_space
    low, high = np.asarray(space.low, np.float64), np.asarray(space.high, np.float64)

    def act(obs: Any, info: dict) -> np.ndarray:
        return rng.uniform(low, high).astype(space.dtype)

    return act


def oracle_policy(env: Any, seed: int) -> Act:
    """The scripted oracle of the env's task (deterministic; the seed is unused)."""
    return make_oracle(env)


def load_policy(spec: str) -> PolicyFactory:
    """The policy factory named by `spec`: a built-in name ("random", "oracle") or "module:callable"."""
    if not isinstance(spec, str) or not spec.strip():
        raise ValueError(f"Expected a policy as 'module:callable' or one of {sorted(BUILTIN_POLICIES)}, found {spec!r}")
    target = BUILTIN_POLICIES.get(spec, spec)
    module_name, sep, attr = target.partition(":")
    if not sep or not module_name or not attr:
        raise ValueError(f"Expected a policy as 'module:callable' or one of {sorted(BUILTIN_POLICIES)}, found {spec!r}")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ValueError(f"Could not import the policy module {module_name!r} of {spec!r}: {exc}") from None
    obj: Any = module
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"Expected {module_name!r} to define {attr!r} (policy {spec!r}), found no {part!r}")
        obj = getattr(obj, part)
    if not callable(obj):
        raise ValueError(f"Expected policy {spec!r} to be callable as factory(env, seed), found {type(obj).__name__}")
    return obj
