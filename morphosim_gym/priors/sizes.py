"""Size priors from the category: how tall things are in the real world, and how they move.

`CATEGORY_SIZES` holds, per category the procedural generator builds, its height and longest
side in metres and its mobility (the generator's own numbers: a test checks them against its
builders). `planned_sizes` reads a clip's plan (`info["plan"]["objects"]`: category and
scale) into the size each planned object has in the scene, with the generator's visibility
floor (no object smaller than `MIN_RELATIVE_SIZE` of the largest). `size_depth` turns a mask's
pixel height and an object's real height into a camera depth: what fixes the depth scale of
an object that stands on no ground (a fish in the water, a ball in the air).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from ..scene.camera import Camera

__all__ = ["CATEGORY_SIZES", "MIN_RELATIVE_SIZE", "ObjectSize", "pixel_rows", "planned_sizes", "size_depth"]

MIN_RELATIVE_SIZE = 0.3     # the generator's visibility floor (generate/compose.py)


@dataclass(frozen=True)
class ObjectSize:
    """Real-world size of an object.

    Attributes:
        height: vertical extent, metres.
        longest: longest horizontal side, metres.
        mobility: "ground", "float", "swim", "air" or "fixed".
    """

    height: float
    longest: float
    mobility: str = "ground"

    def scaled(self, factor: float) -> "ObjectSize":
        return ObjectSize(self.height * factor, self.longest * factor, self.mobility)


def _s(height: float, longest: float, mobility: str = "ground") -> ObjectSize:
    return ObjectSize(height, longest, mobility)


CATEGORY_SIZES: dict[str, ObjectSize] = {
    "airplane": _s(1.3, 5.5, "air"), "apple": _s(0.09, 0.08), "ball": _s(0.26, 0.26), "banana": _s(0.07, 0.19),
    "bicycle": _s(1.02, 1.82), "bird": _s(0.2, 0.55, "air"), "boat": _s(2.05, 3.22, "float"),
    "book": _s(0.04, 0.22), "bottle": _s(0.26, 0.07), "bowl": _s(0.13, 0.19), "box": _s(0.28, 0.4),
    "bus": _s(2.3, 6.02), "car": _s(1.31, 3.2), "cat": _s(0.53, 0.59), "chair": _s(0.97, 0.45),
    "cone": _s(0.5, 0.36), "cow": _s(1.62, 1.88), "cube": _s(0.09, 0.09), "cup": _s(0.09, 0.09),
    "dog": _s(0.77, 1.01), "duck": _s(0.32, 0.44, "float"), "elephant": _s(2.9, 3.33),
    "fish": _s(0.29, 0.63, "swim"), "horse": _s(2.05, 2.19), "house": _s(4.03, 7.31, "fixed"),
    "lamp": _s(0.56, 0.3, "fixed"), "motorcycle": _s(1.07, 1.96), "mug": _s(0.1, 0.13),
    "person": _s(1.74, 0.56), "plate": _s(0.02, 0.28, "fixed"), "robot": _s(1.26, 0.72),
    "rock": _s(0.44, 0.75, "fixed"), "seaweed": _s(1.03, 0.33, "fixed"), "sheep": _s(1.07, 1.33),
    "snowboarder": _s(1.74, 1.5), "table": _s(0.75, 1.4, "fixed"), "train": _s(2.84, 8.98),
    "tree": _s(3.8, 1.99, "fixed"), "truck": _s(2.5, 5.01), "vase": _s(0.34, 0.18),
}
"""Category -> its size in the procedural generator's library (metres)."""


def planned_sizes(info: dict[str, Any]) -> dict[str, ObjectSize]:
    """Planned object name -> its size in the scene: the category's size times the plan's
    scale, grown to the visibility floor. Objects of unknown categories are left out (they
    still count for nothing in the floor)."""
    objects = ((info or {}).get("plan") or {}).get("objects") or []
    out: dict[str, ObjectSize] = {}
    for o in objects:
        base = CATEGORY_SIZES.get(str(o.get("category") or o.get("noun") or ""))
        if base is None:
            continue
        scale = float(o.get("scale") or 1.0)
        out[str(o.get("name"))] = base.scaled(scale if np.isfinite(scale) and scale > 0 else 1.0)
    if not out:
        return out
    largest = max(max(s.height, s.longest) for s in out.values())
    floor = MIN_RELATIVE_SIZE * largest
    return {n: (s.scaled(floor / max(s.height, s.longest)) if max(s.height, s.longest) < floor else s)
            for n, s in out.items()}


def _look_down(camera: Camera, row: float, col: float) -> float:
    """Angle (radians) below the horizontal of the ray through pixel (row, col), world z-up."""
    d_cam = np.array([(col - camera.cx) / camera.fx, (row - camera.cy) / camera.fy, 1.0])
    d = camera.camera_to_world[:3, :3] @ d_cam
    return float(np.arcsin(np.clip(-d[2] / np.linalg.norm(d), -1.0, 1.0)))


def size_depth(mask: np.ndarray, camera: Camera, size: ObjectSize | float, min_rows: int = 3,
               blocked: np.ndarray | None = None) -> float | None:
    """Camera depth at which an object of this size covers the rows of `mask` [H, W]: its height
    seen at the ray's angle below the horizontal (theta) plus its depth extent seen from above
    (an upright box `height` tall and min(height, longest) deep spans about
    fy (height cos theta + depth sin theta) / z rows); a bare float is a height alone (theta
    ignored). None when the mask is cut by the image border or, below or above it, by `blocked`
    [H, W] pixels (another object in front: its pixel height is not the object's), or spans
    under `min_rows` rows."""
    height = size.height if isinstance(size, ObjectSize) else float(size)
    if not np.isfinite(height) or height <= 0:
        return None
    rows = pixel_rows(mask, min_rows, blocked)
    if rows is None:
        return None
    extent = height
    if isinstance(size, ObjectSize):
        r, c = np.nonzero(mask)
        theta = _look_down(camera, float(r.mean()) + 0.5, float(c.mean()) + 0.5)
        extent = height * np.cos(theta) + min(size.height, size.longest) * abs(np.sin(theta))
    return float(camera.fy * extent / rows)


def pixel_rows(mask: np.ndarray, min_rows: int = 3, blocked: np.ndarray | None = None) -> int | None:
    """How many rows a mask [H, W] spans, when they are the whole object's: None when it is cut
    by the image border or, below or above it, by `blocked` [H, W] pixels (another object in
    front: more than a tenth of a 2-px ring around it), or spans under `min_rows` rows."""
    rows = np.flatnonzero(mask.any(axis=1))
    if len(rows) < min_rows:
        return None
    if rows[0] == 0 or rows[-1] == mask.shape[0] - 1 or mask[:, 0].any() or mask[:, -1].any():
        return None
    if blocked is not None:
        k = np.ones((3, 3), np.uint8)
        ring = cv2.dilate(mask.astype(np.uint8), k, iterations=2).astype(bool) & ~mask
        if (ring & blocked).sum() > 0.1 * ring.sum():
            return None
    return int(rows[-1] - rows[0] + 1)
