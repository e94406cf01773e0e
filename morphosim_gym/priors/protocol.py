"""The one protocol every prior estimator implements, and the plan boxes masks are labelled from."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from ..scene.camera import Camera

__all__ = ["BoxTrack", "PlanTarget", "PriorEstimators"]


@runtime_checkable
class BoxTrack(Protocol):
    """Something the plan says moves: a label and one normalised (x0, y0, x1, y1) box per frame."""

    label: str
    boxes: np.ndarray


@dataclass(frozen=True, eq=False)
class PlanTarget:
    """A `BoxTrack` read from a clip's info (the planned trajectory of one object).

    Attributes:
        label: the object's name ("bus").
        boxes: [T, 4] normalised (x0, y0, x1, y1), x right, y down.
    """

    label: str
    boxes: np.ndarray


@runtime_checkable
class PriorEstimators(Protocol):
    """Depth, instance masks and point tracks of a clip; return None to skip a prior."""

    def depth(self, frames: np.ndarray, camera: Camera | Sequence[Camera],
              masks: np.ndarray | None = None) -> np.ndarray | None:
        """frames [T, H, W, 3] uint8, one camera or one per frame, optional [T, H, W] instance
        masks (-1 background) -> [T, H, W] float32 camera-z depth (0 where unknown).
        An implementation may also take `labels` ({mask id: label}) and `sizes` ({planned
        object name: `sizes.ObjectSize`}) keywords; `prepare_priors` passes them only to one
        that does."""

    def masks(self, frames: np.ndarray, attention: np.ndarray | None,
              targets: Sequence[BoxTrack], cameras: Sequence[Camera] | None = None,
              ) -> tuple[np.ndarray, dict[int, str]] | None:
        """frames [T, H, W, 3], attention [N_targets, T_lat, H_lat, W_lat] (or None), the
        plan's moving objects, optionally the per-frame cameras ->
        ([T, H, W] int32 instance ids, -1 background; {id: label})."""

    def tracks(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """frames [T, H, W, 3] -> (tracks [P, T, 2] float32 pixel x, y; visible [P, T] bool)."""
