"""The fixed sun baked into surface colours: every generated object, setting and agent is shaded
with the same light so that they match in one image."""

from __future__ import annotations

import numpy as np

__all__ = ["LIGHT_DIR", "AMBIENT", "DIFFUSE"]

LIGHT_DIR = np.array([0.35, -0.45, 0.82]) / np.linalg.norm([0.35, -0.45, 0.82])   # unit vector towards the sun
AMBIENT = 0.74      # brightness of a surface facing away from the sun
DIFFUSE = 0.34      # extra brightness of a surface facing the sun (Lambertian)
