"""Area-weighted, seeded, evenly spread samples on a mesh's surface with their normals and colours."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .mesh import MeshPart
from .texture import sample_texture

__all__ = ["SurfaceSamples", "sample_surface"]


@dataclass
class SurfaceSamples:
    """Points on a surface.

    Attributes:
        points: positions. [N, 3]
        normals: unit face normals (from the triangles' winding). [N, 3]
        colors: RGB in [0, 1]. [N, 3]
        opacities: the material opacity of each point's face (times its texture's alpha, when it has one). [N]
        area: the surface's total area (the in-plane density is N / area).
    """

    points: np.ndarray
    normals: np.ndarray
    colors: np.ndarray
    opacities: np.ndarray
    area: float


def sample_surface(parts: list[MeshPart], triangles: list[np.ndarray], n: int, seed: int = 0) -> SurfaceSamples:
    """`n` points spread evenly by area over every part's triangles (see `_stratified`).

    Args:
        parts: the materials (and UVs) of each part.
        triangles: each part's triangles in the frame wanted for the samples. [M_i, 3, 3]
        n: number of samples (>= 1).
        seed: the random seed (same inputs and seed give identical samples).
    """
    tris = np.concatenate(triangles).astype(np.float64)
    part_of = np.concatenate([np.full(len(t), i) for i, t in enumerate(triangles)])
    cross = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    double_area = np.linalg.norm(cross, axis=1)
    good = np.isfinite(double_area) & (double_area > 0)
    if not np.any(good):
        raise ValueError("Expected a mesh with some area, found only degenerate triangles")
    cdf = np.cumsum(np.where(good, double_area, 0.0))
    face, r1, r2 = _stratified(cdf, n, np.random.default_rng(seed))
    s = np.sqrt(r1)
    bary = np.stack([1 - s, s * (1 - r2), s * r2], axis=1)
    points = np.einsum("nk,nkd->nd", bary, tris[face])
    normals = cross[face] / double_area[face][:, None]
    colors = np.empty((n, 3), dtype=np.float32)
    opacities = np.empty(n, dtype=np.float32)
    offsets = np.cumsum([0] + [len(t) for t in triangles])
    for i, part in enumerate(parts):
        sel = np.flatnonzero(part_of[face] == i)
        if sel.size == 0:
            continue
        local = face[sel] - offsets[i]
        colors[sel] = _part_colors(part, local, bary[sel])
        opacities[sel] = part.opacity * _part_alpha(part, local, bary[sel])
    return SurfaceSamples(points, normals, np.clip(colors, 0, 1), opacities, float(cdf[-1] / 2))


_R2 = 1.32471795724474602596   # the plastic number: the R2 low-discrepancy sequence's generator


def _stratified(cdf: np.ndarray, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Face index and two unit numbers per sample, evenly spread rather than independently random.

    Sample i takes a random position in the i-th of n equal slices of the area CDF (jittered
    stratification: each face gets its area's share of the budget, within about one sample, with
    no moire on regular meshes), and the i-th point of the R2 sequence in the unit square, so the
    samples that share a face cover it evenly; a seeded random shift of the sequence (a
    Cranley-Patterson rotation) makes each seed a different, equally even pattern. Independent
    random samples clump and leave holes that show what lies behind a surface.
    """
    s1, s2 = rng.random(2)
    i = np.arange(n, dtype=np.float64)
    jitter = rng.random(n)
    face = np.minimum(np.searchsorted(cdf, (i + jitter) / n * cdf[-1], side="right"), len(cdf) - 1)
    r1 = np.mod(s1 + i / _R2, 1.0)
    r2 = np.mod(s2 + i / _R2**2, 1.0)
    return face, r1, r2


def _part_alpha(part: MeshPart, faces: np.ndarray, bary: np.ndarray) -> np.ndarray | float:
    """The texture's opacity at the samples (bilinear), or 1 for a part without texture alpha."""
    if part.alpha is None or part.uvs is None:
        return 1.0
    uv = np.einsum("nk,nkd->nd", bary, part.uvs[faces])
    return sample_texture(part.alpha[..., None], uv)[:, 0]


def _part_colors(part: MeshPart, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
    if part.texture is not None and part.uvs is not None:
        uv = np.einsum("nk,nkd->nd", bary, part.uvs[faces])
        return sample_texture(part.texture, uv)
    if part.face_colors is not None:
        return part.face_colors[faces]
    return np.broadcast_to(part.color, (len(faces), 3))
