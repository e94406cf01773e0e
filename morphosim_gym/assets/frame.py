"""From a file's frame to the object frame: z-up, metres, real-world size, centred on its base.

Object frame (as the procedural builders): x forward, y left, z up, the base's centre at the
origin. A y-up file's front (+z) faces -y here, towards a camera on the -y side.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Union

import numpy as np

from .record import AssetRecord

__all__ = ["UP_ROTATIONS", "SizeSpec", "file_to_z_up", "object_transform", "target_extents"]

SizeSpec = Union[None, float, Sequence[float]]  # noqa: UP007 - a runtime alias   # None: the asset's own size; float: longest side; 3: extents

# up axis -> rotation taking the file's frame to z-up (row-major 3x3)
UP_ROTATIONS: dict[str, np.ndarray] = {
    "z": np.eye(3),
    "y": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),     # (x, y, z) -> (x, -z, y)
    "-y": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),    # (x, y, z) -> (x, z, -y)
}


def file_to_z_up(record: AssetRecord) -> np.ndarray:
    """The linear map [3, 3] from file coordinates to z-up ones: the model rotation, then the up axis,
    then the unit scale."""
    rot = np.eye(3) if record.model_rotation is None else np.asarray(record.model_rotation, float).reshape(3, 3)
    return UP_ROTATIONS[record.up_axis] @ rot * record.unit_scale


def target_extents(native: np.ndarray, record_size: Sequence[float] | None, size_m: SizeSpec) -> np.ndarray:
    """Extents (x, y, z) in metres the object gets.

    Args:
        native: the z-up extents of the file times its unit scale. [3]
        record_size: the index's real-world size, or None.
        size_m: None (the real-world size, else native), a float (the longest side; proportions
            kept) or three extents.
    """
    native = np.maximum(np.asarray(native, dtype=np.float64), 1e-9)
    base = native if record_size is None else np.asarray(record_size, dtype=np.float64)
    if size_m is None:
        return base
    if np.isscalar(size_m):
        size = float(size_m)
        if not size > 0:
            raise ValueError(f"Expected size_m > 0, found {size_m!r}")
        return base * (size / base.max())
    ext = np.asarray(size_m, dtype=np.float64)
    if ext.shape != (3,) or not np.all(ext > 0):
        raise ValueError(f"Expected size_m as a positive number or 3 positive extents, found {size_m!r}")
    return ext


def object_transform(points: np.ndarray, record: AssetRecord, size_m: SizeSpec) -> tuple[np.ndarray, np.ndarray]:
    """(A [3, 3], t [3]) such that `points @ A.T + t` is the object frame: z-up, scaled per axis to
    the target extents, base centred at the origin.

    Args:
        points: file-frame positions used for the bounds (mesh vertices or Gaussian means). [N, 3]
    """
    lin = file_to_z_up(record)
    p = points.reshape(-1, 3) @ lin.T
    lo, hi = p.min(axis=0), p.max(axis=0)
    native = hi - lo
    ext = target_extents(native, record.size_m, size_m)
    scale = np.where(native > 1e-9, ext / np.maximum(native, 1e-12), 1.0)
    if np.any(native <= 1e-9):   # a flat object: keep its flat axis flat, scale it like the others
        scale = np.where(native > 1e-9, scale, scale[native > 1e-9].mean() if np.any(native > 1e-9) else 1.0)
    A = np.diag(scale) @ lin
    centre = (lo + hi) / 2 * scale
    t = np.array([-centre[0], -centre[1], -lo[2] * scale[2]])
    return A, t
