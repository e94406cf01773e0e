"""Compiled CPU splatting backend (numba): forward and hand-written backward.

`rasterize_numpy` is the forward-only float32 hot path on numpy arrays (env observations);
`rasterize_cpu` is the differentiable torch entry point (float32 or float64).
"""

from .pipeline import rasterize_numpy

__all__ = ["rasterize_numpy"]
