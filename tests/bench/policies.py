"""Policies that misbehave, for the bad-input tests (loaded by the runner as tests.bench.policies:NAME)."""

import numpy as np


def raises_at_step_3(env, seed):
    """A policy whose act() raises on its fourth call."""
    calls = [0]

    def act(obs, info):
        calls[0] += 1
        if calls[0] > 3:
            raise RuntimeError("policy exploded")
        return np.zeros(env.action_space.shape, np.float32)

    return act


def wrong_shape(env, seed):
    """Actions with one value too many."""
    return lambda obs, info: np.zeros(env.action_space.shape[0] + 1, np.float32)


def nan_action(env, seed):
    """Actions with a NaN."""
    return lambda obs, info: np.full(env.action_space.shape, np.nan, np.float32)


def factory_raises(env, seed):
    """A factory that cannot build its policy."""
    raise FileNotFoundError("no checkpoint at /nonexistent/model.pt")
