"""Small, fast env settings for the env tests."""

import gymnasium as gym
import pytest

import morphosim_gym  # noqa: F401  (registers the ids)
from morphosim_gym.envs import ENV_IDS

FAST = dict(width=32, height=32, detail=0.25)
PROMPT = "a red ball moves from left to right"


def make(env_id: str, **kwargs) -> gym.Env:
    """gym.make with small images and light scenes unless overridden."""
    return gym.make(env_id, **{**FAST, **kwargs})


@pytest.fixture(params=ENV_IDS)
def env_id(request) -> str:
    return request.param
