"""Gaussians of a simple shaded object for edits that add one (swap, insertion, occluders).

The shapes are the scene layer's primitives, shaded with the scene's fixed sun
(`scene.lighting`) so that an inserted object matches the generated ones in one image.
Every object stands on its base: local z from 0 to its height, centred on x = y = 0.
"""

from __future__ import annotations

import numpy as np

from ..scene import Gaussians
from ..scene.lighting import AMBIENT, DIFFUSE, LIGHT_DIR
from ..scene.primitives import sample_shape

__all__ = ["SHAPE_OF", "shape_gaussians", "DEFAULT_COLOR"]

DEFAULT_COLOR = (0.62, 0.62, 0.6)
# category -> (primitive, its parameters for a unit-height object, height / width)
SHAPE_OF: dict[str, tuple[str, dict, float]] = {
    "ball": ("ellipsoid", {"radii": (0.5, 0.5, 0.5)}, 1.0),
    "sphere": ("ellipsoid", {"radii": (0.5, 0.5, 0.5)}, 1.0),
    "cube": ("box", {"size": (1.0, 1.0, 1.0)}, 1.0),
    "box": ("box", {"size": (1.0, 1.0, 1.0)}, 1.0),
    "block": ("box", {"size": (1.0, 1.0, 1.0)}, 1.0),
    "wall": ("box", {"size": (1.0, 0.2, 1.0)}, 1.0),
    "bottle": ("cylinder", {"radius": 0.5, "height": 1.0}, 2.5),
    "can": ("cylinder", {"radius": 0.5, "height": 1.0}, 1.4),
    "mug": ("cylinder", {"radius": 0.5, "height": 1.0}, 1.0),
    "cup": ("cylinder", {"radius": 0.5, "height": 1.0}, 1.0),
    "vase": ("cylinder", {"radius": 0.5, "height": 1.0}, 1.8),
    "cone": ("cone", {"radius": 0.5, "height": 1.0}, 1.0),
    "pyramid": ("pyramid", {"base": 1.0, "height": 1.0}, 1.0),
}


def shape_gaussians(category: str, width: float, color: tuple[float, float, float] | None, n: int,
                    rng: np.random.Generator, object_id: int, feature_dim: int = 0,
                    height: float | None = None) -> Gaussians:
    """`n` Gaussians of a `category` object `width` metres across (standing on z = 0; `height` metres
    tall, default the category's proportions), coloured `color` (shaded by the scene sun). Unknown
    categories get a box."""
    if not (np.isfinite(width) and width > 0):
        raise ValueError(f"Expected an object width > 0, found {width}")
    shape, params, aspect = SHAPE_OF.get(category, SHAPE_OF["box"])
    surf = sample_shape(shape, n, rng, **params)
    pts = surf.points - np.array([0.0, 0.0, surf.points[:, 2].min()])
    pts = pts / max(float(np.ptp(pts[:, 0])), 1e-9)             # unit width
    pts *= width
    if height is not None:
        aspect = height / width
    pts[:, 2] *= aspect
    rgb = np.asarray(color if color is not None else DEFAULT_COLOR, dtype=np.float64)
    shade = AMBIENT + DIFFUSE * np.clip(surf.normals @ LIGHT_DIR, 0.0, 1.0)
    colors = np.clip(rgb[None, :] * shade[:, None], 0.0, 1.0)
    spacing = width * max(aspect, 1.0) / max(np.sqrt(n), 1.0)
    m = len(pts)
    return Gaussians(means=pts, quats=np.tile([1.0, 0.0, 0.0, 0.0], (m, 1)), scales=np.full((m, 3), 0.6 * spacing),
                     opacities=np.full(m, 0.95), colors=colors, object_ids=np.full(m, object_id, dtype=np.int32),
                     features=np.zeros((m, feature_dim)) if feature_dim else None)
