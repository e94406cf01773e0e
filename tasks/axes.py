"""The perturbation axes: one registry of name -> language edit template(s), for suites and randomisation.

    from morphosim_gym.tasks.axes import AXES, axis_edits, template_values
    values = template_values(scene, task, request)        # what the templates' fields are in this scene
    axis_edits(AXES["target_size"], values)                # ("make the red ball twice as big",)

Every axis is a language edit (`MorphoSim.edit` sentences), so each works at reset
(`options={"edits": [...]}`) and mid-episode (`LanguagePerturbation`); the field-of-view and
camera-height edits move the task's camera mid-episode too (`Task.change_view`). `camera_shift` is
the one axis that moves the rig's view by a camera shift instead (the reset `camera` option at `at: 0`;
`MorphoSimEnv.move_camera` before step k for `at: k`). Template fields:
`{target}` ("red ball"), `{target_noun}`, `{target_color}`, `{distractor}` (the first other
object, "blue cube"), `{distractor_noun}`, `{new_color}` (a colour no object has), `{ground}` (the
first background object's name), `{swap_noun}` (a shape the target is not). An axis whose field the
scene lacks (no distractor) does not apply: `axis_edits` raises `AxisNotApplicable` naming the field,
which the benchmark records as that episode's error.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping, Optional

from .base import describe_object

__all__ = ["Axis", "AXES", "AXIS_FAMILIES", "AxisNotApplicable", "axis_edits", "fill_templates", "template_values", "TEMPLATE_FIELDS",
           "PALETTE", "SWAP_NOUNS"]

PALETTE = ("green", "blue", "red", "yellow", "purple", "orange", "white", "pink", "cyan", "brown")
SWAP_NOUNS = ("cube", "ball", "bottle", "box")
TEMPLATE_FIELDS = ("target", "target_noun", "target_color", "distractor", "distractor_noun", "new_color", "ground",
                   "swap_noun")
AXIS_FAMILIES = ("object", "distractor", "motion", "lighting", "background", "camera", "sensor")


class AxisNotApplicable(ValueError):
    """An axis that does not apply to this scene (it names a field the scene lacks)."""


@dataclass(frozen=True)
class Axis:
    """One perturbation axis.

    Attributes:
        name: the registry key (and a suite's perturbation name).
        family: one of `AXIS_FAMILIES` (for reports and held-out splits).
        edits: language edit templates, applied in order.
        camera: the reset camera shift (keys of `bench.suite.CameraShift`) instead of / besides edits.
        at: 0 = at reset; k = before the k-th step.
        description: what changes.
    """

    name: str
    family: str
    edits: tuple[str, ...] = ()
    camera: Optional[Mapping[str, float]] = None
    at: int = 0
    description: str = ""
    fields: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        if self.family not in AXIS_FAMILIES:
            raise ValueError(f"Expected an axis family in {AXIS_FAMILIES}, found {self.family!r}")
        used = tuple(f for f in TEMPLATE_FIELDS if any("{" + f + "}" in t for t in self.edits))
        object.__setattr__(self, "fields", used)


def _axes(*items: Axis) -> dict[str, Axis]:
    return {a.name: a for a in items}


AXES: dict[str, Axis] = _axes(
    # today's eight
    Axis("recolor_target", "object", ("make the {target} {new_color}",), description="the target's colour"),
    Axis("recolor_distractor", "distractor", ("make the {distractor} {new_color}",),
         description="the distractor's colour"),
    Axis("remove_distractor", "distractor", ("delete the {distractor}",), description="the distractor deleted"),
    Axis("extract_target", "background", ("extract the {target}",),
         description="everything but the target deleted (ground and distractors)"),
    Axis("reverse_target_mid", "motion", ("reverse the motion of the {target}",), at=20,
         description="the target's motion plays backwards from step 20 on"),
    Axis("redirect_target", "motion", ("make the {target} move towards the camera",),
         description="the target heads towards the camera"),
    Axis("speed_up_target", "motion", ("make the {target} move twice as fast",), description="the target twice as fast"),
    Axis("camera_shift", "camera", camera={"orbit_deg": 25.0}, description="the tripod 25 degrees around the scene"),
    # the new axes
    Axis("target_size", "object", ("make the {target} twice as big",), description="the target twice as big"),
    Axis("swap_target", "object", ("replace the {target} with a {swap_noun}",),
         description="the target becomes another shape (same place, size, motion, id)"),
    Axis("target_texture", "object", ("make the {target} checkered",), description="a checker pattern on the target"),
    Axis("target_material", "object", ("make the {target} metallic",),
         description="a metallic look (contrast and sheen) on the target"),
    Axis("insert_distractor", "distractor", ("add a {new_color} cube next to the {target}",),
         description="a new cube beside the target"),
    Axis("distractor_motion", "distractor", ("make the {distractor} move left",),
         description="the (still) distractor starts moving left"),
    Axis("occlusion", "distractor", ("put a box between the camera and the {target}",),
         description="a box between the generation camera and the target's start"),
    Axis("time_offset", "motion", ("delay the {target}'s motion by 1 second",),
         description="the target starts moving 1 s later"),
    Axis("light_dim", "lighting", ("dim the lights",), description="every colour at 60%"),
    Axis("light_warm", "lighting", ("make the light warmer",), description="a warmer colour temperature"),
    Axis("light_direction", "lighting", ("light the scene from the left",),
         description="the light comes from the left (a brightness ramp)"),
    Axis("sky_sunset", "background", ("make the sky a sunset",), description="a sunset sky behind the scene"),
    Axis("ground_color", "background", ("make the {ground} {new_color}",), description="the ground's colour"),
    Axis("ground_texture", "background", ("make the {ground} striped",), description="stripes on the ground"),
    Axis("setting_snow", "background", ("move the scene to snow",),
         description="the setting becomes snow (ground colour and sky)"),
    Axis("camera_fov", "camera", ("widen the field of view",), description="the start field of view 1.3x wider"),
    Axis("camera_height", "camera", ("raise the camera by 0.5 metres",),
         description="the camera 0.5 m higher, looking at the same point"),
    Axis("sensor_noise", "sensor", ("add sensor noise",), description="Gaussian pixel noise (sigma 20 of 255)"),
    Axis("sensor_blur", "sensor", ("blur the images",), description="Gaussian blur of the images"),
    Axis("sensor_jpeg", "sensor", ("compress the images",), description="JPEG compression at quality 50"),
)


def _color_word(description: str, noun: str) -> str:
    words = description.split()
    return " ".join(words[:-1]) if len(words) > 1 and words[-1] == noun else ""


def template_values(scene: Any, task: Any, request: Any) -> dict[str, Optional[str]]:
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
    ground = next((o.name for o in scene.objects if o.role == "background"), None)
    return {
        "target": target_desc,
        "target_noun": target_noun,
        "target_color": _color_word(target_desc, target_noun) or None,
        "distractor": described[distractor.id] if distractor else None,
        "distractor_noun": described[distractor.id].split()[-1] if distractor else None,
        "new_color": new_color,
        "ground": ground,
        "swap_noun": next(n for n in SWAP_NOUNS if n != target_noun),
    }


def fill_templates(name: str, templates: tuple[str, ...], values: Mapping[str, Optional[str]]) -> tuple[str, ...]:
    """The templates with the fields filled in; `AxisNotApplicable` naming a field the scene lacks."""
    out = []
    for template in templates:
        missing = [k for k, v in values.items() if v is None and "{" + k + "}" in template]
        if missing:
            raise AxisNotApplicable(f"Perturbation {name!r} needs {{{missing[0]}}} in {template!r}, but this scene "
                                    f"has none (target: {values.get('target')!r})")
        try:
            text = template.format(**{k: ("" if v is None else v) for k, v in values.items()})
        except (KeyError, IndexError, ValueError) as exc:
            raise AxisNotApplicable(f"Edit template {template!r} cannot be filled: {exc}") from None
        out.append(" ".join(text.split()))
    return tuple(out)


def axis_edits(axis: Axis, values: Mapping[str, Optional[str]]) -> tuple[str, ...]:
    """The axis's edit sentences for a scene's template values (see `fill_templates`)."""
    return fill_templates(axis.name, axis.edits, values)
