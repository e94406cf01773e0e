"""Gaussian splatting: the public `render` / `rasterize` layer and its backends."""

from .api import BACKENDS, PendingRender, RenderOutput, backend_available, rasterize, render, render_batch, submit_batch

__all__ = ["BACKENDS", "PendingRender", "RenderOutput", "backend_available", "rasterize", "render", "render_batch",
           "submit_batch"]
