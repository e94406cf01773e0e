"""Fixtures of the viewer tests: a small generator and sessions on generated scenes."""

import pytest

import morphosim_gym as ms

SMALL = ms.GenerationConfig(width=64, height=64, num_frames=13, detail=0.5)
BALL = "a red ball bounces from right to left"
BUS = "a bus drives down a road from left to right"


@pytest.fixture(scope="session")
def small_sim():
    """Oracle reconstruction (instant scenes), small clips."""
    return ms.MorphoSim(reconstruction="oracle", generation=SMALL)


@pytest.fixture(scope="session")
def ball_scene(small_sim):
    return small_sim.generate(BALL, seed=0)


@pytest.fixture
def session(small_sim, ball_scene):
    from morphosim_gym.viewer import ViewerSession

    return ViewerSession(ball_scene, sim=small_sim)
