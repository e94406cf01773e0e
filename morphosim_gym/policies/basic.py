"""Policies that ignore the observation: uniform random actions and all-zero actions."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
from gymnasium import spaces

from .protocol import Act

__all__ = ["random_policy", "zero_policy", "RANDOM_STREAM"]

RANDOM_STREAM = 0xAC7          # second word of the random policy's seed (keeps its draws apart from others)


def random_policy(env: Any, seed: int) -> Act:
    """Uniform random actions in the env's action box, drawn from `seed` (other action spaces:
    their own `sample()`, on a copy of the space seeded with `seed`)."""
    space = env.action_space
    if not isinstance(space, spaces.Box):
        own = copy.deepcopy(space)
        own.seed(int(seed))
        return lambda obs, info: own.sample()
    rng = np.random.default_rng([int(seed), RANDOM_STREAM])
    low, high = np.asarray(space.low, np.float64), np.asarray(space.high, np.float64)

    def act(obs: Any, info: dict) -> np.ndarray:
        return rng.uniform(low, high).astype(space.dtype)

    return act


def zero_policy(env: Any, seed: int) -> Act:
    """All-zero actions of the env's action shape (the seed is unused)."""
    space = env.action_space
    zeros = np.zeros(space.shape, dtype=space.dtype)
    return lambda obs, info: zeros.copy()
