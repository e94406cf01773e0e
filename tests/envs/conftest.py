"""Small, fast env settings for the env tests."""

import gymnasium as gym
import pytest

import morphosim_gym as ms  # (importing registers the ids)
from morphosim_gym.envs import ENV_IDS

FAST_SIM = ms.SimConfig(reconstruction="oracle", generation=ms.GenerationConfig(detail=0.25))
FAST = dict(width=32, height=32, sim=FAST_SIM)
PROMPT = "a red ball moves from left to right"


def make(env_id: str, **kwargs) -> gym.Env:
    """gym.make with small images and light scenes unless overridden."""
    return gym.make(env_id, **{**FAST, **kwargs})


@pytest.fixture(params=ENV_IDS)
def env_id(request) -> str:
    return request.param
