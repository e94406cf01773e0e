"""Objects as lists of shaped, textured parts, and their conversion to surface Gaussians.

A `Part` is a primitive (see `primitives.py`) placed in the object's frame (x forward,
y left, z up, resting on z = 0) with a colour rule and an optional procedural texture.
`parts_to_gaussians` shares a Gaussian budget between parts by area, lays flat
Gaussians (discs) on the surfaces, and bakes a soft light into their colours.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence, Union

import numpy as np

from ..scene.rotations import matrix_to_quat
from .primitives import _split, sample_shape, shape_area

__all__ = ["Part", "Texture", "ColorRule", "parts_to_gaussians", "euler", "SurfaceCloud", "LIGHT_DIR",
           "TANGENTIAL_SCALE", "match_mean_color"]

TANGENTIAL_SCALE = 0.62   # in-surface scale of an object's Gaussians, as a fraction of their spacing

# A colour rule: "primary" (the object's colour), ("primary", k) (primary scaled by k and
# clipped), ("mix", rgb, w) (primary blended towards rgb by w), or a fixed RGB triple.
ColorRule = Union[str, tuple]

LIGHT_DIR = np.array([0.35, -0.45, 0.82]) / np.linalg.norm([0.35, -0.45, 0.82])
AMBIENT = 0.74
DIFFUSE = 0.34


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


def _normal_quats(normals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Quaternions whose local z is the normal, with a random twist about it."""
    n = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    helper = np.where(np.abs(n[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(helper, n)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(n, t1)
    twist = rng.uniform(0, 2 * math.pi, len(n))[:, None]
    a = np.cos(twist) * t1 + np.sin(twist) * t2
    b = np.cross(n, a)
    mats = np.stack([a, b, n], axis=-1)          # columns: local x, y, z in the object frame
    return matrix_to_quat(mats)


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
    counts = [max(8, c) for c in _split(budget, weights)]
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
        out["quats"].append(_normal_quats(nrm, rng))
        out["scales"].append(scales)
        out["opacities"].append(np.full(count, part.opacity))
        out["colors"].append(col)
        out["nodes"].append(np.full(count, node_names.index(part.node)))
    return SurfaceCloud(*(np.concatenate(out[k]) for k in ("means", "quats", "scales", "opacities", "colors",
                                                             "nodes")), node_names=node_names)


def match_mean_color(colors: np.ndarray, weights: np.ndarray, target: Sequence[float], iterations: int = 6,
                     tolerance: float = 1.0) -> np.ndarray:
    """Shift colours in CIE Lab so that their weighted mean is `target` (RGB), keeping their spread
    (shading, textures, darker parts); repeated because clipping to the RGB gamut eats part of
    each shift. Returns new colours [n, 3]."""
    import cv2

    from ..metrics import rgb_to_lab

    w = np.asarray(weights, dtype=np.float64)
    w = w / max(float(w.sum()), 1e-12)
    goal = rgb_to_lab(np.asarray(target, dtype=np.float64))
    c = np.asarray(colors, dtype=np.float64).copy()
    for _ in range(iterations):
        lab = rgb_to_lab(c)
        shift = goal - w @ lab
        if np.linalg.norm(shift) < tolerance:
            break
        moved = (lab + shift).astype(np.float32).reshape(-1, 1, 3)
        c = np.clip(cv2.cvtColor(moved, cv2.COLOR_Lab2RGB).reshape(-1, 3).astype(np.float64), 0.0, 1.0)
    return c
