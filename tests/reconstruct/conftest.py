"""Shared clips of the reconstruction tests."""

import pytest

import morphosim_gym as ms

BALL_PROMPT = "A small, vibrant red rubber ball is bouncing from right to left"


def football_clip(size: int, frames: int) -> ms.GeneratedClip:
    """The example ball prompt on the real football of the Sweet Home 3D furniture (the procedural
    ball's stripes barely show a turn), with the generator's own priors; skips without the furniture."""
    from morphosim_gym.generate.real_assets import asset_candidates

    with pytest.MonkeyPatch.context() as mp:
        mp.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
        if "sweethome3d/blendswap-cc-by/ballonfoot" not in [a.id for a in asset_candidates("ball")]:
            pytest.skip("needs the Sweet Home 3D furniture (apt install sweethome3d-furniture)")
        sim = ms.MorphoSim(generation=ms.GenerationConfig(width=size, height=size, num_frames=frames),
                           reconstruction="oracle")
        return sim.generate_clip(BALL_PROMPT, seed=0)
