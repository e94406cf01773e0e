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
from morphosim_gym.tasks import SceneRequest, Task, describe_object

from .suite import Perturbation, Suite

__all__ = ["EpisodeScene", "sample_episode", "template_values", "resolve_edits", "camera_option", "PALETTE",
           "PerturbationError"]

PALETTE = ("green", "blue", "red", "yellow", "purple", "orange", "white", "pink", "cyan", "brown")
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


def _color_word(description: str, noun: str) -> str:
    words = description.split()
    return " ".join(words[:-1]) if len(words) > 1 and words[-1] == noun else ""


def template_values(scene: Scene4D, task: Task, request: SceneRequest) -> dict[str, Optional[str]]:
    """Values of the edit template fields for this scene (None where the scene has no such thing)."""
    target = task.resolve_target(scene, request.target or None)
    described = {o.id: describe_object(o, scene) for o in scene.objects if o.role != "background"}
    target_desc = request.target_description or described[target.id]
    others = [o for o in scene.objects if o.role != "background" and o.id != target.id]
    distractor = others[0] if others else None
    taken = {d.split()[0] for d in described.values() if len(d.split()) > 1}
    taken.add(target_desc.split()[0])
    new_color = next((c for c in PALETTE if c not in taken), None)
    target_noun = target_desc.split()[-1]
    return {
        "target": target_desc,
        "target_noun": target_noun,
        "target_color": _color_word(target_desc, target_noun) or None,
        "distractor": described[distractor.id] if distractor else None,
        "distractor_noun": described[distractor.id].split()[-1] if distractor else None,
        "new_color": new_color,
    }


def resolve_edits(perturbation: Perturbation, values: dict[str, Optional[str]]) -> tuple[str, ...]:
    """The perturbation's edit texts with the template fields filled in; `PerturbationError` when the
    scene lacks a field an edit needs (e.g. {distractor} in a scene with one object)."""
    out = []
    for template in perturbation.edits:
        try:
            text = template.format(**{k: ("" if v is None else v) for k, v in values.items()})
        except (KeyError, IndexError, ValueError) as exc:
            raise PerturbationError(f"Edit template {template!r} cannot be filled: {exc}") from None
        missing = [k for k, v in values.items() if v is None and "{" + k + "}" in template]
        if missing:
            raise PerturbationError(f"Perturbation {perturbation.name!r} needs {{{missing[0]}}} in {template!r}, "
                                    f"but this scene has none (target: {values.get('target')!r})")
        out.append(" ".join(text.split()))
    return tuple(out)


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
