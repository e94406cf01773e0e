"""Surface samplers for shaped primitives, in a primitive's own unit frame.

Each sampler returns `Surface(points [n, 3], normals [n, 3], uv [n, 2])` with points spread
evenly (stratified) over the surface; `uv` are surface coordinates in [0, 1]^2 that
procedural textures read. `area(...)` gives the surface area used to share a Gaussian
budget between the parts of an object.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

__all__ = ["Surface", "SHAPES", "sample_shape", "shape_area", "split_counts"]


@dataclass
class Surface:
    """Points on a surface with outward unit normals and texture coordinates."""

    points: np.ndarray
    normals: np.ndarray
    uv: np.ndarray


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _stratified(n: int, rng: np.random.Generator) -> np.ndarray:
    """n points in [0, 1]^2, one per cell of a near-square jittered grid (even coverage)."""
    cols = max(1, int(math.ceil(math.sqrt(n))))
    rows = max(1, int(math.ceil(n / cols)))
    cells = rng.permutation(rows * cols)[:n]
    r, c = np.divmod(cells, cols)
    return np.c_[(c + rng.random(n)) / cols, (r + rng.random(n)) / rows]


# ------------------------------------------------------------------ samplers
def ellipsoid(n: int, rng: np.random.Generator, radii=(1.0, 1.0, 1.0), z_min: float = -1.0) -> Surface:
    """Ellipsoid with semi-axes `radii`, keeping the part with unit-sphere z >= z_min (z_min=0: a dome)."""
    u = _stratified(n, rng)
    z = z_min + (1.0 - z_min) * u[:, 1]          # uniform in z is uniform in area on the unit sphere
    phi = 2 * math.pi * u[:, 0]
    s = np.sqrt(np.clip(1 - z * z, 0, 1))
    unit = np.c_[s * np.cos(phi), s * np.sin(phi), z]
    a = np.asarray(radii, dtype=np.float64)
    return Surface(unit * a, _unit(unit / a), np.c_[u[:, 0], (z + 1) / 2])


def box(n: int, rng: np.random.Generator, size=(1.0, 1.0, 1.0), faces: str = "xXyYzZ") -> Surface:
    """Axis-aligned box centred at the origin with full edge lengths `size`; `faces` picks which of
    the six faces (-x, +x, -y, +y, -z, +z as x X y Y z Z) are sampled."""
    sx, sy, sz = size
    table = {"x": (0, -1), "X": (0, 1), "y": (1, -1), "Y": (1, 1), "z": (2, -1), "Z": (2, 1)}
    dims = np.array(size, dtype=np.float64)
    chosen = [table[f] for f in faces]
    areas = np.array([dims[(ax + 1) % 3] * dims[(ax + 2) % 3] for ax, _ in chosen])
    counts = split_counts(n, areas)
    pts, nrm, uvs = [], [], []
    for (ax, sign), k in zip(chosen, counts):
        if k == 0:
            continue
        u = _stratified(k, rng)
        p = np.zeros((k, 3))
        a1, a2 = (ax + 1) % 3, (ax + 2) % 3
        p[:, ax] = sign * dims[ax] / 2
        p[:, a1] = (u[:, 0] - 0.5) * dims[a1]
        p[:, a2] = (u[:, 1] - 0.5) * dims[a2]
        nn = np.zeros((k, 3))
        nn[:, ax] = sign
        pts.append(p)
        nrm.append(nn)
        uvs.append(u)
    return Surface(np.concatenate(pts), np.concatenate(nrm), np.concatenate(uvs))


def cylinder(n: int, rng: np.random.Generator, radius: float = 1.0, height: float = 1.0, caps: str = "tb",
             radius_top: float | None = None) -> Surface:
    """Cylinder (or truncated cone with `radius_top`) along z from 0 to `height`; `caps` 't'/'b'."""
    r0, r1 = radius, radius if radius_top is None else radius_top
    slant = math.hypot(height, r0 - r1)
    side = math.pi * (r0 + r1) * slant
    areas = [side, math.pi * r1 * r1 if "t" in caps else 0.0, math.pi * r0 * r0 if "b" in caps else 0.0]
    k_side, k_top, k_bot = split_counts(n, np.array(areas))
    u = _stratified(k_side, rng)
    phi = 2 * math.pi * u[:, 0]
    # area-uniform along a cone's slant: radius varies linearly, density ~ radius
    if abs(r0 - r1) > 1e-9:
        h = (np.sqrt(r0 ** 2 + u[:, 1] * (r1 ** 2 - r0 ** 2)) - r0) / (r1 - r0)
    else:
        h = u[:, 1]
    r = r0 + (r1 - r0) * h
    pts = [np.c_[r * np.cos(phi), r * np.sin(phi), h * height]]
    nz = (r0 - r1) / slant
    nrm = [_unit(np.c_[np.cos(phi) * height / slant, np.sin(phi) * height / slant, np.full(k_side, nz)])]
    uvs = [np.c_[u[:, 0], h]]
    for k, rad, z, sign in ((k_top, r1, height, 1.0), (k_bot, r0, 0.0, -1.0)):
        if k:
            d = disc(k, rng, rad)
            pts.append(d.points + [0, 0, z])
            nrm.append(d.normals * sign)
            uvs.append(d.uv)
    return Surface(np.concatenate(pts), np.concatenate(nrm), np.concatenate(uvs))


def cone(n: int, rng: np.random.Generator, radius: float = 1.0, height: float = 1.0, base: bool = True) -> Surface:
    """Cone with its base disc at z=0 and apex at z=height."""
    return cylinder(n, rng, radius, height, caps="b" if base else "", radius_top=0.0)


def disc(n: int, rng: np.random.Generator, radius: float = 1.0) -> Surface:
    """Flat disc in the z=0 plane, normal +z."""
    u = _stratified(n, rng)
    r = radius * np.sqrt(u[:, 1])
    phi = 2 * math.pi * u[:, 0]
    return Surface(np.c_[r * np.cos(phi), r * np.sin(phi), np.zeros(n)], np.tile([0.0, 0, 1], (n, 1)), u)


def plane(n: int, rng: np.random.Generator, size=(1.0, 1.0)) -> Surface:
    """Rectangle in the z=0 plane centred at the origin, normal +z."""
    u = _stratified(n, rng)
    return Surface(np.c_[(u[:, 0] - 0.5) * size[0], (u[:, 1] - 0.5) * size[1], np.zeros(n)],
                   np.tile([0.0, 0, 1], (n, 1)), u)


def torus(n: int, rng: np.random.Generator, major: float = 1.0, minor: float = 0.25) -> Surface:
    """Torus around the z axis."""
    u = _stratified(n, rng)
    # rejection-free area weighting: density ~ (R + r cos v); sample v by inverse transform on a grid
    grid = np.linspace(0, 2 * math.pi, 512)
    cdf = np.cumsum(major + minor * np.cos(grid))
    cdf = (cdf - cdf[0]) / (cdf[-1] - cdf[0])
    v = np.interp(u[:, 1], cdf, grid)
    phi = 2 * math.pi * u[:, 0]
    ring = major + minor * np.cos(v)
    pts = np.c_[ring * np.cos(phi), ring * np.sin(phi), minor * np.sin(v)]
    nrm = np.c_[np.cos(v) * np.cos(phi), np.cos(v) * np.sin(phi), np.sin(v)]
    return Surface(pts, nrm, np.c_[u[:, 0], v / (2 * math.pi)])


def capsule(n: int, rng: np.random.Generator, radius: float = 0.5, length: float = 1.0) -> Surface:
    """Capsule along x: a cylinder of `length` between two hemispheres (total length + 2 radius)."""
    side = 2 * math.pi * radius * length
    cap = 2 * math.pi * radius * radius
    k_side, k_a, k_b = split_counts(n, np.array([side, cap, cap]))
    c = cylinder(k_side, rng, radius, length, caps="")
    pts = [c.points[:, [2, 0, 1]] - [length / 2, 0, 0]]
    nrm = [c.normals[:, [2, 0, 1]]]
    uvs = [c.uv]
    for k, sign in ((k_a, 1.0), (k_b, -1.0)):
        if k:
            e = ellipsoid(k, rng, (radius, radius, radius), z_min=0.0)
            p = e.points[:, [2, 0, 1]] * [sign, 1, 1]
            pts.append(p + [sign * length / 2, 0, 0])
            nrm.append(e.normals[:, [2, 0, 1]] * [sign, 1, 1])
            uvs.append(e.uv)
    return Surface(np.concatenate(pts), np.concatenate(nrm), np.concatenate(uvs))


def pyramid(n: int, rng: np.random.Generator, base: float = 1.0, height: float = 1.0) -> Surface:
    """Square pyramid: base `base` x `base` centred in the z=0 plane (normal -z), apex at z=height."""
    half = base / 2
    slant = math.hypot(half, height)
    side = half * slant * 2                      # each triangle: base * slant / 2
    counts = split_counts(n, np.array([side] * 4 + [base * base]))
    pts, nrm, uvs = [], [], []
    for k, face in enumerate(counts[:4]):
        u = _stratified(face, rng)
        a, b = np.sqrt(u[:, 0]), u[:, 1]          # uniform on a triangle: apex -> base edge
        ang = k * math.pi / 2
        cx, cy = math.cos(ang), math.sin(ang)
        along = (b - 0.5) * base * a
        p = np.c_[half * a * cx - along * cy, half * a * cy + along * cx, height * (1 - a)]
        normal = _unit(np.array([cx * height, cy * height, half]))
        pts.append(p)
        nrm.append(np.tile(normal, (face, 1)))
        uvs.append(np.c_[b, 1 - a])
    u = _stratified(counts[4], rng)
    pts.append(np.c_[(u[:, 0] - 0.5) * base, (u[:, 1] - 0.5) * base, np.zeros(counts[4])])
    nrm.append(np.tile([0.0, 0, -1], (counts[4], 1)))
    uvs.append(u)
    return Surface(np.concatenate(pts), np.concatenate(nrm), np.concatenate(uvs))


def split_counts(n: int, weights: np.ndarray) -> list[int]:
    """Split n into integer counts proportional to weights (largest remainders)."""
    w = np.asarray(weights, dtype=np.float64)
    if w.sum() <= 0:
        return [0] * len(w)
    exact = n * w / w.sum()
    counts = np.floor(exact).astype(int)
    for i in np.argsort(-(exact - counts))[: n - counts.sum()]:
        counts[i] += 1
    return counts.tolist()


# -------------------------------------------------------------------- areas
def _ellipsoid_area(radii=(1.0, 1.0, 1.0), z_min: float = -1.0) -> float:
    a, b, c = radii
    p = 1.6075
    full = 4 * math.pi * (((a * b) ** p + (a * c) ** p + (b * c) ** p) / 3) ** (1 / p)
    return full * (1.0 - z_min) / 2.0


def _cylinder_area(radius=1.0, height=1.0, caps="tb", radius_top=None) -> float:
    r1 = radius if radius_top is None else radius_top
    a = math.pi * (radius + r1) * math.hypot(height, radius - r1)
    return a + (math.pi * r1 * r1 if "t" in caps else 0) + (math.pi * radius * radius if "b" in caps else 0)


def _box_area(size=(1.0, 1.0, 1.0), faces="xXyYzZ") -> float:
    s = np.asarray(size, dtype=np.float64)
    face = {"x": s[1] * s[2], "X": s[1] * s[2], "y": s[0] * s[2], "Y": s[0] * s[2], "z": s[0] * s[1], "Z": s[0] * s[1]}
    return float(sum(face[f] for f in faces))


SHAPES: dict[str, tuple[Callable[..., Surface], Callable[..., float]]] = {
    "ellipsoid": (ellipsoid, _ellipsoid_area),
    "box": (box, _box_area),
    "cylinder": (cylinder, _cylinder_area),
    "cone": (cone, lambda radius=1.0, height=1.0, base=True: _cylinder_area(radius, height, "b" if base else "", 0.0)),
    "disc": (disc, lambda radius=1.0: math.pi * radius * radius),
    "plane": (plane, lambda size=(1.0, 1.0): float(size[0] * size[1])),
    "torus": (torus, lambda major=1.0, minor=0.25: 4 * math.pi ** 2 * major * minor),
    "capsule": (capsule, lambda radius=0.5, length=1.0: 2 * math.pi * radius * length + 4 * math.pi * radius ** 2),
    "pyramid": (pyramid, lambda base=1.0, height=1.0: base * base + 2 * base * math.hypot(base / 2, height)),
}


def sample_shape(shape: str, n: int, rng: np.random.Generator, **params) -> Surface:
    """Sample `n` surface points of a named primitive."""
    if shape not in SHAPES:
        raise ValueError(f"Expected a primitive in {sorted(SHAPES)}, found {shape!r}")
    return SHAPES[shape][0](n, rng, **params)


def shape_area(shape: str, **params) -> float:
    """Surface area of a named primitive with these parameters."""
    if shape not in SHAPES:
        raise ValueError(f"Expected a primitive in {sorted(SHAPES)}, found {shape!r}")
    return float(SHAPES[shape][1](**params))
