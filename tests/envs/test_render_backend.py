"""The envs render with `sim.config.render_backend`: "cpu" by default (bit-identical to a direct cpu
render of the env's request), "torch" when asked (its float depth differs from cpu's in the low bits),
gsplat refused at make where it cannot run."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from morphosim_gym.errors import BackendUnavailableError
from morphosim_gym.render import backend_available, render

from .conftest import FAST_SIM, PROMPT, make

KW = dict(prompt=PROMPT, scene_seed=0, width=16, height=16, depth=True)


def _direct(env, backend):
    """The observation camera's view rendered here from the env's own request."""
    sources, cams, background, sky = env.unwrapped._render_request(env.unwrapped.world.t)
    return render(sources, cams, background=background, sky=sky, backend=backend)


def test_default_envs_render_on_cpu_bit_identically():
    env = make("MorphoSim/Track-v0", **KW)
    try:
        obs, _ = env.reset(seed=0)
        assert env.unwrapped.render_backend == "cpu"
        out = _direct(env, "cpu")
        assert np.array_equal(obs["depth"], out.depth[0]) and np.array_equal(obs["rgb"], out.rgb_uint8()[0])
    finally:
        env.close()


def test_envs_render_with_the_sims_render_backend():
    cpu, ref = make("MorphoSim/Track-v0", **KW), make("MorphoSim/Track-v0", sim=replace(FAST_SIM, render_backend="torch"),
                                                     **KW)
    try:
        a, _ = cpu.reset(seed=0)
        b, _ = ref.reset(seed=0)
        assert ref.unwrapped.render_backend == "torch"
        # the reference renderer's float32 depth differs from the compiled kernel's in the last bits:
        # equal depths here would mean the env ignored render_backend
        assert not np.array_equal(a["depth"], b["depth"])
        np.testing.assert_allclose(a["depth"], b["depth"], rtol=1e-4, atol=1e-4)
        assert np.array_equal(b["depth"], _direct(ref, "torch").depth[0])
    finally:
        cpu.close()
        ref.close()


def test_native_vector_env_follows_the_sims_render_backend():
    from morphosim_gym.envs.native_vector import MorphoSimVectorEnv

    venv = MorphoSimVectorEnv(1, kind="track", sim=replace(FAST_SIM, render_backend="torch"), prompt=PROMPT, width=16,
                              height=16)
    try:
        assert venv.backend == "torch"
    finally:
        venv.close()


@pytest.mark.skipif(backend_available("gsplat"), reason="gsplat runs here")
def test_unavailable_render_backend_fails_at_make():
    with pytest.raises(BackendUnavailableError, match="gsplat"):
        make("MorphoSim/Track-v0", sim=replace(FAST_SIM, render_backend="gsplat"), **KW)
