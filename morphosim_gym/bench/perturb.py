"""From a suite's seed and perturbation to what the env is given: prompt, scene seed, edits, camera.

Everything here is a pure function of (suite, perturbation, seed) and the generated scene, so
an episode is the same on any worker, and a perturbed episode differs from its base twin
only by the perturbation.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from morphosim_gym.errors import EditError
from morphosim_gym.scene import Scene4D
from morphosim_gym.tasks import SceneRequest
from morphosim_gym.tasks.axes import PALETTE, AxisNotApplicable, fill_templates, template_values

from .suite import Perturbation, Suite

__all__ = ["EpisodeScene", "sample_episode", "template_values", "resolve_edits", "camera_option", "PALETTE",
           "PerturbationError"]

_SALT = 0xBE7C          # separates the suite's scene draws from every other use of the seed


class PerturbationError(EditError):
    """A perturbation that cannot be applied to this episode's scene."""


@dataclass(frozen=True)
class EpisodeScene:
    """The scene of an episode: the drawn request (prompt, target) and the generation seed."""

    request: SceneRequest
    scene_seed: int


def sample_episode(suite: Suite, seed: int) -> EpisodeScene:
    """The scene draw of episode `seed` of a suite (the same for every perturbation and policy)."""
    rng = np.random.default_rng([int(seed), _SALT])
    request = suite.task.scenes.sample(rng)
    return EpisodeScene(request, int(rng.integers(2 ** 31 - 1)))


def resolve_edits(perturbation: Perturbation, values: dict[str, Optional[str]]) -> tuple[str, ...]:
    """The perturbation's edit texts with the template fields filled in; `PerturbationError` when the
    scene lacks a field an edit needs (e.g. {distractor} in a scene with one object)."""
    try:
        return fill_templates(perturbation.name, perturbation.edits, values)
    except AxisNotApplicable as exc:
        raise PerturbationError(str(exc)) from None


def camera_option(perturbation: Perturbation, scene: Scene4D) -> dict[str, Any]:
    """The env's reset `camera` option of a camera shift ({} without one): the generation camera
    orbited about the scene centre (and moved along its distance), and/or a field of view."""
    shift = perturbation.camera
    if shift is None:
        return {}
    out: dict[str, Any] = {}
    if shift.moves:
        centre = scene.centre()
        cam = scene.camera.orbit(shift.orbit_deg, centre, shift.pitch_deg)
        out["position"] = (centre + shift.distance_scale * (cam.position - centre)).tolist()
    if shift.fov_y_deg is not None:
        out["fov_y_deg"] = shift.fov_y_deg
    return out
