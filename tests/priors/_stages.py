"""A generated clip's estimated priors with one stage of the default estimators on and off."""

import dataclasses

import morphosim_gym as ms
from morphosim_gym.priors import default_estimators, prepare_priors


def with_and_without(prompt: str, stage: str, size: int = 64, frames: int = 9, **others: bool):
    """(clip, its estimated priors with `stage` on, with it off); asserts the stage is on by
    default. `others`: other stages set so in both (another stage that does the same job)."""
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=size, height=size, num_frames=frames))
    clip = sim.generate_clip(prompt, 0)
    est = dataclasses.replace(default_estimators(clip), **others)
    assert getattr(est, stage), f"{stage} is not on by default"
    off = dataclasses.replace(est, **{stage: False})
    return clip, prepare_priors(clip, "estimated", estimators=est), prepare_priors(clip, "estimated", estimators=off)
