"""Clip generators: the one protocol (`ClipGenerator`) and the registry `SimConfig.generator` names.

    generator = GENERATORS.create("procedural", sim_config)       # or "diffusion", or "module:factory"
    clip = generator.generate(plan, seed, prompt)

A factory takes the pipeline's configuration (a `SimConfig`, read duck-typed: `.generation`,
`.render_backend`, `.diffusion`) and returns a `ClipGenerator`. Built in:

| name | clips | ground truth |
|---|---|---|
| "procedural" | renders of a composed Gaussian scene (offline default) | yes (`compose`) |
| "diffusion" | CogVideoX with trajectory attention guidance on the planner's boxes (local weights) | no |

A ``"module:factory"`` name imports `module` and calls `factory(config)` (it runs that code).
"""

from __future__ import annotations

from typing import Any, Optional, Protocol, runtime_checkable

from ..registry import Registry
from ..scene import GeneratedClip

__all__ = ["ClipGenerator", "GENERATORS", "make_generator", "make_procedural"]


@runtime_checkable
class ClipGenerator(Protocol):
    """What turns a generate `Plan` into a `GeneratedClip` (the paper's "2D world generator").

    Attributes:
        name: the backend's name, recorded in the clip's info.

    A generator whose clips carry their ground-truth `Scene4D` may also offer
    ``compose(plan, seed, prompt) -> ComposedScene`` (the scene without rendering frames), which
    ``reconstruction="oracle"`` uses; one that can never give a ground truth sets the class
    attribute ``ground_truth = False`` so that ``reconstruction="oracle"`` is refused up front.
    Optional ``cache_settings() -> dict``: JSON-friendly settings that decide its clips (they
    enter the clip cache key).
    """

    name: str

    def generate(self, plan: Any, seed: int, prompt: Optional[str] = None) -> GeneratedClip:
        """The clip of a generate plan with this seed; `prompt` is the text recorded in the clip."""
        ...


def make_procedural(config: Any) -> ClipGenerator:
    """The procedural generator of a `SimConfig` (its `generation` and `render_backend`)."""
    from .procedural import ProceduralBackend

    return ProceduralBackend(config.generation, config.render_backend)


GENERATORS: Registry[ClipGenerator] = Registry("generator", ClipGenerator)
GENERATORS.register("procedural", make_procedural)
GENERATORS.register("diffusion", "morphosim_gym.generate.diffusion.planned:make_diffusion")


def make_generator(name: str, config: Any) -> ClipGenerator:
    """`GENERATORS.create(name, config)`."""
    return GENERATORS.create(name, config)
