"""Gaussian splatting: the public `render` / `rasterize` layer and its backends."""

from .api import BACKENDS, RenderOutput, backend_available, rasterize, render

__all__ = ["BACKENDS", "RenderOutput", "backend_available", "rasterize", "render"]
