"""Objects as lists of shaped, textured parts, and their conversion to surface Gaussians.

A `Part` is a primitive (see `primitives.py`) placed in the object's frame (x forward,
y left, z up, resting on z = 0) with a colour rule and an optional procedural texture.
`parts_to_gaussians` shares a Gaussian budget between parts by area, lays flat
Gaussians (discs) on the surfaces, and bakes a soft light into their colours. The generator's
object library and the rig's agent skins both build on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence, Union

import numpy as np

from .lighting import AMBIENT, DIFFUSE, LIGHT_DIR
from .primitives import sample_shape, shape_area, split_counts
from .rotations import normal_quats

__all__ = ["Part", "Texture", "ColorRule", "parts_to_gaussians", "euler", "resolve_color", "SurfaceCloud",
           "TANGENTIAL_SCALE"]

TANGENTIAL_SCALE = 0.62   # in-surface scale of an object's Gaussians, as a fraction of their spacing

# A colour rule: "primary" (the object's colour), ("primary", k) (primary scaled by k and
# clipped), ("mix", rgb, w) (primary blended towards rgb by w), or a fixed RGB triple.
ColorRule = Union[str, tuple]


@dataclass
class Texture:
    """A procedural texture: `kind` in {"noise", "stripes", "rings", "checker", "spots", "grid"}.

    Attributes:
        kind: the pattern.
        color: RGB (or a ColorRule) of the pattern's second colour.
        scale: pattern frequency (cycles per metre for spatial patterns, per unit uv otherwise).
        amount: strength for "noise" (relative brightness jitter) or coverage for "spots".
        axis: 0, 1, 2 for spatial stripes along x, y, z; "u" / "v" for stripes along uv.
        duty: fraction of each period in the second colour.
    """

    kind: str
    color: ColorRule = (0.1, 0.1, 0.1)
    scale: float = 4.0
    amount: float = 0.08
    axis: Union[int, str] = 0
    duty: float = 0.5


@dataclass
class Part:
    """One primitive of an object.

    Attributes:
        shape: primitive name ("ellipsoid", "box", "cylinder", "cone", "disc", "plane", "torus", "capsule").
        params: the primitive's size parameters (metres).
        position: [3] where the primitive's origin goes in the object frame.
        rotation: [3, 3] rotation of the primitive into the object frame (see `euler`).
        color: a ColorRule.
        textures: procedural textures applied in order.
        density: relative Gaussian density (1 = the object's average).
        node: name of the scaffold node this part moves with ("body" unless articulated).
        opacity: peak opacity of its Gaussians.
    """

    shape: str
    params: dict = field(default_factory=dict)
    position: Sequence[float] = (0.0, 0.0, 0.0)
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    color: ColorRule = "primary"
    textures: Sequence[Texture] = ()
    density: float = 1.0
    node: str = "body"
    opacity: float = 0.97

    def area(self) -> float:
        """Surface area of the placed primitive (rotation keeps area)."""
        return shape_area(self.shape, **self.params)


def euler(yaw: float = 0.0, pitch: float = 0.0, roll: float = 0.0) -> np.ndarray:
    """Rotation matrix from degrees: roll about x, then pitch about y, then yaw about z."""
    y, p, r = (math.radians(a) for a in (yaw, pitch, roll))
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    return rz @ ry @ rx


def resolve_color(rule: ColorRule, primary: np.ndarray) -> np.ndarray:
    """RGB of a colour rule for this primary colour."""
    if isinstance(rule, str):
        if rule != "primary":
            raise ValueError(f"Expected colour rule 'primary', found {rule!r}")
        return primary
    if len(rule) == 2 and rule[0] == "primary":
        return np.clip(primary * float(rule[1]), 0.0, 1.0)
    if len(rule) == 3 and rule[0] == "mix":
        w = float(rule[2])
        return (1 - w) * primary + w * np.asarray(rule[1], dtype=np.float64)
    return np.asarray(rule, dtype=np.float64)


@dataclass
class SurfaceCloud:
    """Flat Gaussians on an object's surfaces, in the object frame, before scaling to the world."""

    means: np.ndarray
    quats: np.ndarray
    scales: np.ndarray
    opacities: np.ndarray
    colors: np.ndarray
    nodes: np.ndarray        # [n] index into `node_names`
    node_names: list[str]

    def __len__(self) -> int:
        return len(self.means)

    def subset(self, keep: np.ndarray) -> "SurfaceCloud":
        """The Gaussians where `keep` [n] (bool) is set."""
        return SurfaceCloud(self.means[keep], self.quats[keep], self.scales[keep], self.opacities[keep],
                            self.colors[keep], self.nodes[keep], self.node_names)


def _pattern(tex: Texture, local: np.ndarray, uv: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(brightness multiplier [n], second-colour weight [n]) of a texture at points."""
    n = len(local)
    ones, zeros = np.ones(n), np.zeros(n)
    if tex.kind == "noise":
        k = tex.scale
        phase = rng.uniform(0, 2 * math.pi, 6)
        smooth = (np.sin(k * local[:, 0] + phase[0]) * np.sin(k * 1.3 * local[:, 1] + phase[1])
                  + np.sin(k * 0.7 * local[:, 2] + phase[2]) * np.sin(k * 1.7 * local[:, 0] + phase[3]))
        return 1.0 + tex.amount * (0.5 * smooth + 0.5 * rng.uniform(-1, 1, n)), zeros
    if tex.kind in ("stripes", "rings"):
        if isinstance(tex.axis, str):
            coord = uv[:, 0 if tex.axis == "u" else 1]
        else:
            coord = local[:, int(tex.axis)]
        if tex.kind == "rings":
            coord = np.linalg.norm(local[:, :2], axis=1)
        phase = (coord * tex.scale) % 1.0
        return ones, (phase < tex.duty).astype(np.float64)
    if tex.kind == "checker":
        cells = np.floor(uv * tex.scale).astype(int)
        return ones, ((cells[:, 0] + cells[:, 1]) % 2).astype(np.float64)
    if tex.kind == "grid":
        f = (uv * tex.scale) % 1.0
        inside = (f[:, 0] > tex.duty / 2) & (f[:, 0] < 1 - tex.duty / 2) & (f[:, 1] > tex.duty / 2) & (f[:, 1] < 1 - tex.duty / 2)
        return ones, inside.astype(np.float64)
    if tex.kind == "spots":
        centres = rng.uniform(local.min(0), local.max(0) + 1e-9, (max(3, int(tex.scale)), 3))
        d = np.min(np.linalg.norm(local[:, None, :] - centres[None], axis=-1), axis=1)
        radius = tex.amount * np.ptp(local, axis=0).max()
        return ones, (d < radius).astype(np.float64)
    raise ValueError(f"Expected a texture kind in noise/stripes/rings/checker/grid/spots, found {tex.kind!r}")


def parts_to_gaussians(parts: Sequence[Part], budget: int, primary: Sequence[float], rng: np.random.Generator,
                       shade: bool = True, thickness: float = 0.35) -> SurfaceCloud:
    """Sample about `budget` flat Gaussians over the parts' surfaces.

    Counts are shared by surface area times part density; each Gaussian's tangential
    scale follows the local spacing so the surface is closed, its normal scale is
    `thickness` times that. Colours: the part's colour rule, textures, then a soft
    Lambertian light (fixed sun `LIGHT_DIR`) baked in when `shade`.
    """
    if budget < len(parts):
        raise ValueError(f"Expected a Gaussian budget of at least one per part ({len(parts)}), found {budget}")
    primary = np.asarray(primary, dtype=np.float64)
    weights = np.array([max(p.area(), 1e-9) * p.density for p in parts])
    counts = [max(8, c) for c in split_counts(budget, weights)]
    node_names: list[str] = []
    out = {k: [] for k in ("means", "quats", "scales", "opacities", "colors", "nodes")}
    for part, count in zip(parts, counts):
        surf = sample_shape(part.shape, count, rng, **part.params)
        rot = np.asarray(part.rotation, dtype=np.float64)
        pts = surf.points @ rot.T + np.asarray(part.position, dtype=np.float64)
        nrm = surf.normals @ rot.T
        spacing = math.sqrt(part.area() / count)
        tangential = TANGENTIAL_SCALE * spacing
        base = resolve_color(part.color, primary)
        col = np.tile(base, (count, 1))
        bright = np.ones(count)
        for tex in part.textures:
            mult, w = _pattern(tex, surf.points, surf.uv, rng)
            second = resolve_color(tex.color, primary)
            col = col * (1 - w[:, None]) + second * w[:, None]
            bright = bright * mult
        if shade:
            lam = np.clip(nrm @ LIGHT_DIR, 0.0, 1.0)
            bright = bright * (AMBIENT + DIFFUSE * lam)
        col = np.clip(col * bright[:, None], 0.0, 1.0)
        jitter = rng.uniform(0.85, 1.15, (count, 2))
        scales = np.c_[tangential * jitter, np.full(count, tangential * thickness)]
        if part.node not in node_names:
            node_names.append(part.node)
        out["means"].append(pts)
        out["quats"].append(normal_quats(nrm, rng))
        out["scales"].append(scales)
        out["opacities"].append(np.full(count, part.opacity))
        out["colors"].append(col)
        out["nodes"].append(np.full(count, node_names.index(part.node)))
    return SurfaceCloud(*(np.concatenate(out[k]) for k in ("means", "quats", "scales", "opacities", "colors",
                                                             "nodes")), node_names=node_names)
