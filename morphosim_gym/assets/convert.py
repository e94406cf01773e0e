"""Mesh (or 3DGS splat) -> `Gaussians` in the object frame.

A mesh becomes flat Gaussians on its surface: area-weighted seeded samples, each a disc in the
face's plane (thin along the normal, in-plane size from the sample density), coloured by the
texture at the sample's UV (bilinear) or the material's diffuse colour.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scene.gaussians import Gaussians
from ..scene.rotations import matrix_to_quat, quat_multiply
from .frame import file_to_z_up, object_transform, target_extents
from .mesh import MeshPart
from .record import AssetRecord
from .surface import sample_surface

__all__ = ["ConversionParams", "mesh_to_gaussians", "normals_to_quats", "splat_to_object"]


@dataclass(frozen=True)
class ConversionParams:
    """How an asset becomes Gaussians (all of it is part of the cache key).

    Attributes:
        budget: number of Gaussians for a mesh; the most kept from a splat.
        size_m: None (the asset's real-world size), a float (longest side, metres) or 3 extents.
        seed: the sampling seed.
        opacity: peak opacity of a mesh's Gaussians (times the material's opacity).
        spread: in-plane standard deviation as a multiple of the mean sample spacing sqrt(area / N).
        thickness: standard deviation along the normal as a fraction of the in-plane one.
    """

    budget: int = 20000
    size_m: float | tuple[float, float, float] | None = None
    seed: int = 0
    opacity: float = 0.95
    spread: float = 0.6
    thickness: float = 0.1

    def __post_init__(self) -> None:
        if int(self.budget) < 1:
            raise ValueError(f"Expected budget >= 1 Gaussians, found {self.budget!r}")
        if not 0 < self.opacity <= 1:
            raise ValueError(f"Expected opacity in (0, 1], found {self.opacity!r}")
        if self.spread <= 0 or self.thickness <= 0:
            raise ValueError(f"Expected spread and thickness > 0, found {self.spread!r}, {self.thickness!r}")
        if self.size_m is not None and not np.isscalar(self.size_m):
            object.__setattr__(self, "size_m", tuple(float(s) for s in self.size_m))

    def key(self) -> dict:
        """The parameters as a JSON-ready dict."""
        return {"budget": int(self.budget), "size_m": self.size_m, "seed": int(self.seed), "opacity": self.opacity,
                "spread": self.spread, "thickness": self.thickness}


def normals_to_quats(normals: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) rotating the local z axis onto each unit normal. [N, 3] -> [N, 4]"""
    n = np.asarray(normals, dtype=np.float64)
    q = np.stack([1.0 + n[:, 2], -n[:, 1], n[:, 0], np.zeros(len(n))], axis=1)   # half-way rotation z -> n
    flip = q[:, 0] < 1e-9                                                           # n = -z: turn about x
    q[flip] = (0.0, 1.0, 0.0, 0.0)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def mesh_to_gaussians(parts: list[MeshPart], record: AssetRecord, params: ConversionParams) -> Gaussians:
    """Flat Gaussians on the surface of a mesh, in the object frame (z-up, sized, base at the origin).

    Args:
        parts: the mesh's triangles and materials in the file's frame.
        record: the asset (up axis, unit, model rotation, real-world size).
        params: budget, size, seed, opacity and Gaussian shape.

    Returns:
        `params.budget` Gaussians.
    """
    corners = np.concatenate([p.triangles.reshape(-1, 3) for p in parts])
    finite = np.all(np.isfinite(corners), axis=1)
    if not np.any(finite):
        raise ValueError(f"Expected finite vertices in {record.file_label}, found none")
    A, t = object_transform(corners[finite], record, params.size_m)
    tris = [np.nan_to_num(p.triangles) @ A.T + t for p in parts]
    n = int(params.budget)
    s = sample_surface(parts, tris, n, params.seed)
    sigma = params.spread * np.sqrt(s.area / n)
    scales = np.empty((n, 3), dtype=np.float64)
    scales[:, :2] = sigma
    scales[:, 2] = max(sigma * params.thickness, 1e-6)
    return Gaussians(means=s.points, quats=normals_to_quats(s.normals), scales=np.maximum(scales, 1e-6),
                     opacities=np.clip(s.opacities * params.opacity, 0.05, 1.0), colors=s.colors)


def splat_to_object(g: Gaussians, record: AssetRecord, params: ConversionParams) -> Gaussians:
    """A 3DGS splat in the object frame: rotated to z-up, scaled uniformly (a splat cannot stretch
    exactly; the largest ratio of target to native extents wins), base centred, at most
    `params.budget` Gaussians (a seeded subset)."""
    g = g.numpy()
    if len(g) > params.budget:
        keep = np.sort(np.random.default_rng(params.seed).choice(len(g), int(params.budget), replace=False))
        g = g.subset(keep)
    rot = file_to_z_up(record) / record.unit_scale
    means = g.means.astype(np.float64) @ rot.T * record.unit_scale
    lo, hi = means.min(axis=0), means.max(axis=0)
    native = hi - lo
    ext = target_extents(native, record.size_m, params.size_m)
    s = float(np.max(ext / np.maximum(native, 1e-12)))
    means = (means - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])) * s
    quats = quat_multiply(np.broadcast_to(matrix_to_quat(rot), g.quats.shape), g.quats)
    return Gaussians(means=means, quats=quats, scales=np.maximum(g.scales * s * record.unit_scale, 1e-9),
                     opacities=g.opacities, colors=g.colors)
