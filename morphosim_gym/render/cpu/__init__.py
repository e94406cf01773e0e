"""Compiled CPU splatting backend (numba): forward and hand-written backward.

Public entry points (twins of `morphosim_gym.render.reference.rasterize_torch`, same rules):

* `rasterize_numpy` -- forward only, float32, numpy in and out, no torch import: the
  observation path of the environments.
* `rasterize_cpu` -- torch tensors, differentiable through a `torch.autograd.Function` whose
  backward is hand written; float32, or float64 for gradient checks (kernels are compiled per
  dtype; float64 uses exact `exp`/`log`).

Pipeline, per camera (modules):

1. `projection.project_forward` -- EWA projection of every Gaussian (near-plane and opacity
   culling, Jacobian clamp, +0.3 blur, opacity-aware extent) into one 64-byte record, plus its
   16x16-tile rectangle and per-chunk tile counts. Branch-free, vectorised over blocks of 512
   Gaussians held field by field.
2. `binning.bin_offsets`, `binning.bin_fill` -- counting sort into per-tile lists (index order);
   `binning.plan_tiles` orders tiles longest list first.
3. `forward.raster_forward` -- per tile (threads claim tiles dynamically): stable radix sort of
   the list by the float bits of camera z (`binning.sort_segment`), then front-to-back
   compositing Gaussian by Gaussian over the rows of its box, 16 pixels wide, with per-row
   bit masks of pixels still compositing. Saves, for the backward pass, each pixel's final
   transmittance and stop position.
4. `backward.raster_backward` -> `backward.reduce_entries` -> `projection.project_backward` --
   the same front-to-back loop computes per-entry gradients of the 2D records (no division to
   undo transmittance: the remaining sum comes from the saved outputs), summed per Gaussian
   in list order, then chained to means, quats (through the normalisation), scales, opacities,
   colours and features.

Behaviour worth knowing:

* A Gaussian whose centre is at or behind a camera's near plane is culled (as in the
  reference), even when its extent reaches in front: a camera behind everything, or inside
  Gaussians whose centres are closer than `near`, renders the background. Empty scenes, scenes
  off-screen, N = 0 and D = 0 are fine. Gaussians whose footprint overflows or is degenerate
  (non-finite conic), or whose colour / feature is not finite, are culled; no input that is
  finite gives NaN.
* Forward outputs are bit-identical run to run and for any thread count; so are gradients
  (per-entry rows summed in a fixed order).
* `rasterize_numpy` keeps grow-only scratch buffers per Python thread (about 80 bytes per
  Gaussian); outputs are always fresh arrays.
* In float32, list positions are kept as floats: at most 2^24 - 1 Gaussians may overlap one
  16x16 tile (a ValueError says so).
* Kernels are cached on disk by numba (`cache=True`); `_cache` clears this package's cache
  entries when any of its sources change (numba would otherwise keep stale code compiled in
  from another module).
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
