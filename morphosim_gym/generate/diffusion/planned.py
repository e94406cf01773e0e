"""The diffusion backend behind the `ClipGenerator` protocol: a generate `Plan` -> its prompt and the
trajectory planner's boxes -> a guided CogVideoX clip.

`PlannedDiffusionGenerator.generate(plan, seed, prompt)` has the procedural generator's signature.
It plans the scene exactly as the procedural path does (`compose_scene` with the same plan, seed
and `GenerationConfig`, resized to the model's clip: `DiffusionConfig.width`, `height`,
`num_frames`, `fps` and `fov_y_deg`), so each moving object's guidance boxes are the planner's
B_i (`PlannedTrajectory.boxes_normalized()`), and its motion tokens are the object's noun as the
prompt writes it. The clip is seen by the planner's first camera, fixed: the composed scene is
used for planning only (the clip has no ground truth; reconstruct it with ``reconstruction="fit"``).

Settings come from `SimConfig.diffusion` (`DiffusionConfig`: local weights, device, steps,
guidance); weights are read from `weights_path` with local files only, never downloaded.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Any, Optional

import numpy as np

from ...scene import GeneratedClip
from ..compose import ComposedScene, GenerationConfig, compose_scene
from .backend import DiffusionClipBackend, DiffusionConfig
from .priors import PriorEstimators
from .targets import GuidanceTarget

__all__ = ["PlannedDiffusionGenerator", "make_diffusion", "planning_config", "guidance_targets", "scene_text",
           "motion_word"]


def planning_config(generation: Optional[GenerationConfig], diffusion: DiffusionConfig) -> GenerationConfig:
    """The procedural planner's settings at the diffusion model's clip size, length, fps and field of view."""
    return dataclasses.replace(generation or GenerationConfig(), num_frames=diffusion.num_frames,
                               width=diffusion.width, height=diffusion.height, fps=diffusion.fps,
                               fov_y_deg=diffusion.fov_y_deg)


def scene_text(plan: Any, prompt: str) -> str:
    """The part of `prompt` that describes the scene: follow-up edits ("...; then make it blue") cut off."""
    text = prompt
    for follow in getattr(plan, "then", ()):
        at = text.lower().rfind(follow.text.lower())
        if at > 0:
            text = text[:at]
    text = re.sub(r"(?:[\s,;.]|\band\b|\bthen\b)+$", "", text, flags=re.IGNORECASE)
    return text.strip() or prompt.strip()


def motion_word(prompt: str, noun: str) -> Optional[str]:
    """The form of `noun` the prompt writes (the noun, a plural, or None when absent)."""
    low = prompt.lower()
    forms = [noun, noun + "s", noun + "es"] + ([noun[:-1] + "ies"] if noun.endswith("y") else [])
    for form in forms:
        if re.search(r"(?<!\w)" + re.escape(form.lower()) + r"(?!\w)", low):
            return form
    return None


def _union(boxes: list[np.ndarray]) -> np.ndarray:
    b = np.stack(boxes)
    return np.concatenate([b[:, :, :2].min(axis=0), b[:, :, 2:].max(axis=0)], axis=1)


def _inside(boxes: np.ndarray, width: int, height: int) -> np.ndarray:
    """Boxes clipped to the image, each at least one pixel wide and high."""
    b = np.clip(boxes, 0.0, 1.0)
    min_w, min_h = 1.0 / width, 1.0 / height
    for lo, hi, m in ((0, 2, min_w), (1, 3, min_h)):
        thin = b[:, hi] - b[:, lo] < m
        b[thin, lo] = np.clip(b[thin, lo], 0.0, 1.0 - m)
        b[thin, hi] = b[thin, lo] + m
    return b


def guidance_targets(plan: Any, composed: ComposedScene, prompt: str) -> tuple[list[GuidanceTarget], list[str]]:
    """One `GuidanceTarget` per moving object of the plan: its noun's tokens and the planner's boxes.

    Several instances of one object ("two balls") share their words, so they get one target whose
    box per frame is the union of theirs. Returns (targets, names of moving objects left unguided
    because the prompt does not write their noun).
    """
    targets, unguided = [], []
    for spec in plan.objects:
        names = [spec.name] if spec.count == 1 else [f"{spec.name} {k + 1}" for k in range(spec.count)]
        trajs = [composed.trajectories[n] for n in names if n in composed.trajectories]
        if not trajs:
            continue
        word = motion_word(prompt, spec.noun)
        if word is None:
            unguided.append(spec.name)
            continue
        width, height = trajs[0].width, trajs[0].height
        boxes = _inside(_union([t.boxes_normalized() for t in trajs]), width, height)
        targets.append(GuidanceTarget([word], boxes, label=spec.name))
    return targets, unguided


class PlannedDiffusionGenerator:
    """The diffusion clip backend as a `ClipGenerator` (see the module docstring).

    Args:
        config: `DiffusionConfig` (its weights_path is checked now, the weights load on first use).
        generation: the pipeline's `GenerationConfig` (the planner's detail, assets...); its size,
            length, fps and field of view are replaced by the model's.
        pipeline, priors: as for `DiffusionClipBackend` (a built pipeline instead of weights; depth,
            masks and tracks estimators).
    """

    name = "diffusion"
    ground_truth = False

    def __init__(self, config: DiffusionConfig | None = None, generation: GenerationConfig | None = None, *,
                 pipeline: Any = None, priors: PriorEstimators | None = None) -> None:
        self.config = config or DiffusionConfig()
        self.planning = planning_config(generation, self.config)
        self.backend = DiffusionClipBackend(self.config, pipeline=pipeline, priors=priors)

    def plan(self, plan: Any, seed: int, prompt: Optional[str] = None) -> tuple[ComposedScene, list[GuidanceTarget],
                                                                                 list[str], str]:
        """(the planner's composed scene, guidance targets, unguided objects, the model's prompt)."""
        text = scene_text(plan, prompt if prompt is not None else plan.text)
        # the generated view is one fixed camera: plan in it (camera motion is not steered)
        still = dataclasses.replace(plan, camera=None, then=()) if plan.camera is not None else plan
        composed = compose_scene(still, seed, self.planning, text)
        targets, unguided = guidance_targets(plan, composed, text)
        return composed, targets, unguided, text

    def generate(self, plan: Any, seed: int, prompt: Optional[str] = None) -> GeneratedClip:
        """A guided clip of a generate plan: frames from the model, the planner's fixed camera, priors
        from the backend's estimators, no ground truth; `info` adds the plan, the planner's
        trajectories and which objects went unguided."""
        if getattr(plan, "mode", None) != "generate":
            raise ValueError(f"Expected a generate plan, found mode {getattr(plan, 'mode', None)!r}")
        composed, targets, unguided, text = self.plan(plan, seed, prompt)
        clip = self.backend.generate(text, targets, seed=seed, camera=composed.cameras[0])
        clip.info.update({
            "plan": plan.to_dict() if hasattr(plan, "to_dict") else None,
            "setting": composed.setting.name,
            "trajectories": {name: tr.to_dict() for name, tr in composed.trajectories.items()},
            "guidance_boxes": "trajectory planner (compose_scene), normalised, clipped to the image",
            "unguided": unguided,
            "camera_motion": None if plan.camera is None else plan.camera.motion,
        })
        if prompt is not None:
            clip.prompt = prompt
        return clip

    def cache_settings(self) -> dict:
        """What decides the clips besides plan and seed (enters `MorphoSim`'s clip cache key)."""
        return {"diffusion": self.config.to_dict(), "planning": dataclasses.asdict(self.planning)}


def make_diffusion(config: Any) -> PlannedDiffusionGenerator:
    """The diffusion generator of a `SimConfig` (its `diffusion` settings and `generation`)."""
    diffusion = getattr(config, "diffusion", None)
    return PlannedDiffusionGenerator(diffusion if diffusion is not None else DiffusionConfig(),
                                     getattr(config, "generation", None))
