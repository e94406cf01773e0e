"""Labels for a video's estimated masks from its prompt: the moving regions get the prompt's first
noun, the setting the prompt's setting.

A video has no plan boxes, so `RGBPriorEstimators` labels every moving region "object".
`video_estimators(clip)` wraps it for clips read from a video (`info["backend"] == "video"`)
with a prompt: the same priors, the labels renamed. All moving regions are one instance (a
crowd of walkers is one "person" object); the other nouns of the prompt are not located.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..priors import RGBPriorEstimators
from ..priors.protocol import BoxTrack
from ..scene import Camera, GeneratedClip

__all__ = ["PromptLabels", "prompt_labels", "video_estimators"]

UNLABELLED = "object"          # RGBPriorEstimators' label of a moving region without a plan


@dataclass(frozen=True)
class PromptLabels:
    """What a prompt names: the moving objects' label and the setting's."""

    objects: tuple[str, ...] = ()
    setting: str = "ground"

    @property
    def object_label(self) -> str:
        return self.objects[0] if self.objects else UNLABELLED


def prompt_labels(prompt: str) -> PromptLabels:
    """The rule parser's object names and setting of `prompt` (`ms.CommandError` for text it cannot parse)."""
    from ..language import parse

    plan = parse(prompt)
    return PromptLabels(tuple(o.name for o in plan.objects), str(plan.setting or "ground"))


@dataclass(frozen=True)
class _RelabelledEstimators:
    """`RGBPriorEstimators` whose unlabelled moving regions take `labels.object_label`."""

    labels: PromptLabels
    inner: RGBPriorEstimators = field(default_factory=RGBPriorEstimators)

    def depth(self, frames: np.ndarray, camera: Camera | Sequence[Camera],
              masks: np.ndarray | None = None) -> np.ndarray | None:
        return self.inner.depth(frames, camera, masks=masks)

    def masks(self, frames: np.ndarray, attention: np.ndarray | None, targets: Sequence[BoxTrack],
              cameras: Sequence[Camera] | None = None) -> tuple[np.ndarray, dict[int, str]] | None:
        out = self.inner.masks(frames, attention, targets, cameras=cameras)
        if out is None:
            return None
        ids, names = out
        return ids, {k: (self.labels.object_label if v == UNLABELLED else v) for k, v in names.items()}

    def tracks(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        return self.inner.tracks(frames)


def video_estimators(clip: GeneratedClip) -> _RelabelledEstimators | None:
    """The prior estimators of a video clip with a prompt (None for other clips: the default applies)."""
    if clip.info.get("backend") != "video" or not clip.prompt:
        return None
    labels = prompt_labels(clip.prompt)
    return _RelabelledEstimators(labels, RGBPriorEstimators(setting_label=labels.setting))
