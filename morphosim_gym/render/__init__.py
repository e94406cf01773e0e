"""Gaussian splatting: the public `render` / `rasterize` layer and its backends."""

from .api import BACKENDS, RenderOutput, backend_available, rasterize, render, render_batch

__all__ = ["BACKENDS", "RenderOutput", "backend_available", "rasterize", "render", "render_batch"]
