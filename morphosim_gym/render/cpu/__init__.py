"""Compiled CPU splatting backend (numba): forward and hand-written backward.

`rasterize_numpy` is the forward-only float32 hot path on numpy arrays (env observations);
`rasterize_cpu` is the differentiable torch entry point (float32 or float64).
"""

from ._cache import _source_hash, invalidate_stale_cache

invalidate_stale_cache(_source_hash)

from .pipeline import rasterize_numpy  # noqa: E402


def __getattr__(name):
    # `rasterize_cpu` needs torch; import it lazily so the numpy hot path never imports torch
    if name == "rasterize_cpu":
        from .autograd import rasterize_cpu

        return rasterize_cpu
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["rasterize_numpy", "rasterize_cpu"]
