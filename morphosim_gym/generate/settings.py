"""Settings (backgrounds): the ground, water, road, table top, snow, grass, sky... as Gaussians.

Every setting is a static set of Gaussians around the origin plus a background colour
for the pixels they leave uncovered. Objects rest on z = 0 (the ground, the road, the
table top, the sea floor) except floating ones, which sit at `water_level`. Density
falls off with distance from the centre so near ground is detailed and far ground stays
cheap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from typing import Sequence

from ..language.vocabulary import SETTING_LAYOUTS
from ..scene import Camera
from ..scene.lighting import AMBIENT, DIFFUSE, LIGHT_DIR
from ..scene.parts import SurfaceCloud
from ..scene.rotations import normal_quats

__all__ = ["Setting", "SETTING_NAMES", "build_setting", "setting_levels", "carve_under"]

SETTING_NAMES = ("ground", "grass", "road", "snow", "sand", "water", "underwater", "table", "indoor", "sky")


@dataclass
class Setting:
    """A built background.

    Attributes:
        name: which setting.
        cloud: its Gaussians in world coordinates (object-frame fields reused; `nodes` all 0).
        background: RGB shown where no Gaussian is drawn.
        water_level: z of the water surface (floating objects rest there), if any.
        swim_height: z at which swimming objects move, if any.
        air_height: z at which flying objects move.
        label: object name of the background in the scene ("ground", "water", "road"...).
    """

    name: str
    cloud: SurfaceCloud
    background: tuple[float, float, float]
    water_level: float | None = None
    swim_height: float | None = None
    air_height: float = 1.8
    label: str = "ground"


def _radial_patch(n: int, radius: float, rng: np.random.Generator, z: float = 0.0, power: float = 1.6,
                  inner: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Points on a disc (or the annulus beyond `inner`), denser towards the centre; returns
    (points, local spacing per point)."""
    u = rng.random(n)
    lo = (inner / radius) ** (2.0 / power) if inner > 0 else 0.0
    u = lo + (1 - lo) * u
    r = radius * u ** (power / 2.0)
    phi = rng.uniform(0, 2 * math.pi, n)
    pts = np.c_[r * np.cos(phi), r * np.sin(phi), np.full(n, z)]
    # density ~ r^(2/power - 2): spacing from the expected number of points per unit area
    area_density = n / (1 - lo) * (2.0 / power) * np.maximum(r / radius, 0.02) ** (2.0 / power - 2.0) / (math.pi * radius ** 2)
    spacing = 1.0 / np.sqrt(area_density)
    return pts, spacing


def _view_patch(cameras: Sequence[Camera], n: int, radius: float, rng: np.random.Generator,
                z: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Points on the plane z = `z` seen by the cameras, spread evenly in image space (so the ground
    is as detailed as the pixels that see it); returns (points, spacing = footprint of a cell)."""
    keys = [cameras[i] for i in sorted({0, len(cameras) // 3, 2 * len(cameras) // 3, len(cameras) - 1})]
    keys = [c for i, c in enumerate(keys) if all(not np.array_equal(c.world_to_camera, k.world_to_camera)
                                                    for k in keys[:i])]
    per = max(1, n // len(keys))
    pts_all, sp_all = [], []
    for cam in keys:
        # count the pixels that see the plane to size the cells
        probe = np.stack(np.meshgrid(np.arange(0, cam.width, 4) + 0.5, np.arange(0, cam.height, 4) + 0.5), -1).reshape(-1, 2)
        frac = max(float(np.mean(_hits(cam, probe, z, radius)[1])), 1e-3)
        cell = math.sqrt(cam.width * cam.height * frac / per)
        cols, rows = int(math.ceil(cam.width / cell)), int(math.ceil(cam.height / cell))
        g = np.stack(np.meshgrid(np.arange(cols), np.arange(rows)), -1).reshape(-1, 2).astype(np.float64)
        uv = (g + rng.random(g.shape)) * cell
        pts, ok, depth = _hits(cam, uv, z, radius)
        pts_all.append(pts[ok])
        sp_all.append(cell * depth[ok] / cam.fx)
    return np.concatenate(pts_all), np.concatenate(sp_all)


def _hits(cam: Camera, uv: np.ndarray, z: float, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the pixels' rays meet the plane z (points, hit mask within `radius`, camera depth)."""
    d_cam = np.c_[(uv[:, 0] - cam.cx) / cam.fx, (uv[:, 1] - cam.cy) / cam.fy, np.ones(len(uv))]
    c2w = cam.camera_to_world
    d = d_cam @ c2w[:3, :3].T
    o = c2w[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (z - o[2]) / d[:, 2]
    pts = o + s[:, None] * d
    ok = (s > 0) & np.isfinite(s) & (np.linalg.norm(pts[:, :2], axis=1) < radius)
    return pts, ok, np.where(ok, s, 0.0)


def _flat(pts: np.ndarray, spacing: np.ndarray, colors: np.ndarray, rng: np.random.Generator,
          normal=(0.0, 0.0, 1.0), opacity: float = 0.98, shade: bool = True, thickness: float = 0.3) -> SurfaceCloud:
    n = len(pts)
    nrm = np.tile(np.asarray(normal, dtype=np.float64), (n, 1))
    if shade:
        colors = colors * (AMBIENT + DIFFUSE * max(float(np.dot(normal, LIGHT_DIR)), 0.0))
    tang = 0.85 * spacing
    scales = np.c_[tang * rng.uniform(0.85, 1.15, n), tang * rng.uniform(0.85, 1.15, n), tang * thickness]
    return SurfaceCloud(pts, normal_quats(nrm, rng), scales, np.full(n, opacity), np.clip(colors, 0, 1),
                        np.zeros(n, dtype=np.int64), ["setting"])


def _noise(pts: np.ndarray, rng: np.random.Generator, scale: float, amount: float) -> np.ndarray:
    ph = rng.uniform(0, 2 * math.pi, 4)
    smooth = np.sin(scale * pts[:, 0] + ph[0]) * np.sin(scale * 1.37 * pts[:, 1] + ph[1])
    smooth += 0.5 * np.sin(scale * 2.9 * pts[:, 0] + ph[2]) * np.sin(scale * 3.3 * pts[:, 1] + ph[3])
    return 1.0 + amount * (0.6 * smooth / 1.5 + 0.4 * rng.uniform(-1, 1, len(pts)))


def _merge(clouds: list[SurfaceCloud]) -> SurfaceCloud:
    return SurfaceCloud(*(np.concatenate([getattr(c, k) for c in clouds]) for k in
                          ("means", "quats", "scales", "opacities", "colors", "nodes")), node_names=["setting"])


def _ground(rng, n, radius, base, noise_scale, noise_amount, patches=None, cameras=None, z=0.0,
            far_share=0.3) -> SurfaceCloud:
    """A textured plane: most Gaussians where the cameras look (even in image space), the rest in a
    coarser disc around it (so orbiting or novel views still find ground)."""
    if cameras:
        near_pts, near_sp = _view_patch(cameras, int(n * (1 - far_share)), radius, rng, z)
        far_pts, far_sp = _radial_patch(max(1, int(n * far_share)), radius, rng, z=z)
        pts, spacing = np.concatenate([near_pts, far_pts]), np.concatenate([near_sp, far_sp])
    else:
        pts, spacing = _radial_patch(n, radius, rng, z=z)
    col = np.tile(np.asarray(base, dtype=np.float64), (len(pts), 1)) * _noise(pts, rng, noise_scale, noise_amount)[:, None]
    if patches is not None:
        w = (_noise(pts, rng, noise_scale * 0.3, 1.0) > 1.15)[:, None]
        col = np.where(w, np.asarray(patches), col)
    return _flat(pts, spacing, col, rng)


def _backdrop(rng, n, distance, width, height, base, z0=0.0, noise=0.08, hills=True) -> SurfaceCloud:
    """A far vertical band (hills, a wall) at y = distance facing the camera."""
    u = rng.random((n, 2))
    x = (u[:, 0] - 0.5) * width
    top = height * (0.55 + 0.45 * np.sin(x / width * 7.0 + 1.0) * np.sin(x / width * 3.1)) if hills else np.full(n, height)
    z = z0 + u[:, 1] * top
    pts = np.c_[x, np.full(n, distance), z]
    spacing = np.full(n, math.sqrt(width * height / n))
    col = np.tile(np.asarray(base, dtype=np.float64), (n, 1)) * _noise(pts[:, [0, 2]], rng, 1.5, noise)[:, None]
    return _flat(pts, spacing, col, rng, normal=(0.0, -1.0, 0.0), shade=False)


def setting_levels(name: str) -> dict[str, float | None]:
    """Heights a setting fixes before it is built: water_level, swim_height, air_height."""
    if name not in SETTING_NAMES:
        raise ValueError(f"Expected a setting in {SETTING_NAMES}, found {name!r}")
    return {"water_level": 0.0 if name == "water" else None, "swim_height": 0.9 if name == "underwater" else None,
            "air_height": 2.0 if name == "sky" else 1.8}


def _colored(cloud: SurfaceCloud, colors: np.ndarray) -> SurfaceCloud:
    cloud.colors = np.clip(colors, 0.0, 1.0)
    return cloud


def build_setting(name: str, radius: float, rng: np.random.Generator, budget: int = 9000,
                  cameras: Sequence[Camera] | None = None) -> Setting:
    """Build a setting covering a disc of `radius` metres around the origin, detailed where the
    `cameras` (the generation camera path) look."""
    if name not in SETTING_NAMES:
        raise ValueError(f"Expected a setting in {SETTING_NAMES}, found {name!r}")
    sky = (0.62, 0.77, 0.93)
    far = radius * 0.95
    cams = list(cameras) if cameras else None
    if name == "ground":
        cloud = _ground(rng, budget, radius, (0.58, 0.55, 0.5), 2.0, 0.12, cameras=cams)
        return Setting(name, cloud, sky, label=SETTING_LAYOUTS[name].label)
    if name == "grass":
        g = _ground(rng, int(budget * 0.88), radius, (0.3, 0.55, 0.2), 2.5, 0.25, patches=(0.36, 0.5, 0.18),
                    cameras=cams)
        hills = _backdrop(rng, int(budget * 0.12), far * 0.8, radius * 2.0, radius * 0.12, (0.25, 0.45, 0.22))
        return Setting(name, _merge([g, hills]), sky, label=SETTING_LAYOUTS[name].label)
    if name == "snow":
        g = _ground(rng, int(budget * 0.88), radius, (0.93, 0.95, 0.98), 1.5, 0.06, cameras=cams)
        hills = _backdrop(rng, int(budget * 0.12), far * 0.8, radius * 2.0, radius * 0.2, (0.85, 0.88, 0.95))
        return Setting(name, _merge([g, hills]), (0.7, 0.8, 0.92), label=SETTING_LAYOUTS[name].label)
    if name == "sand":
        g = _ground(rng, budget, radius, (0.86, 0.76, 0.55), 3.0, 0.12, cameras=cams)
        return Setting(name, g, (0.68, 0.82, 0.95), label=SETTING_LAYOUTS[name].label)
    if name == "road":
        g = _ground(rng, int(budget * 0.9), radius, (0.34, 0.52, 0.24), 2.0, 0.2, cameras=cams)
        road_w = max(3.5, radius * 0.12)
        x, y = g.means[:, 0], g.means[:, 1]
        asphalt = np.abs(y) < road_w / 2
        col = g.colors.copy()
        tone = _noise(g.means, rng, 6.0, 0.15)[:, None]
        col[asphalt] = (np.array([0.22, 0.22, 0.23]) * tone[asphalt]) * (AMBIENT + DIFFUSE * LIGHT_DIR[2])
        dash = asphalt & (np.abs(y) < road_w * 0.03) & ((x % 3.0) < 1.6)
        edge = asphalt & (np.abs(np.abs(y) - road_w * 0.45) < road_w * 0.025)
        col[dash | edge] = [0.9, 0.9, 0.86]
        hills = _backdrop(rng, int(budget * 0.1), far * 0.8, radius * 2.0, radius * 0.1, (0.3, 0.45, 0.28))
        return Setting(name, _merge([_colored(g, col), hills]), sky, label=SETTING_LAYOUTS[name].label)
    if name == "water":
        g = _ground(rng, budget, radius, (1.0, 1.0, 1.0), 4.0, 0.0, cameras=cams)
        p = g.means
        waves = 0.5 + 0.5 * np.sin(p[:, 0] * 3.0 + np.sin(p[:, 1] * 1.7) * 2.0)
        col = np.c_[0.12 + 0.1 * waves, 0.35 + 0.12 * waves, 0.55 + 0.12 * waves] * _noise(p, rng, 4.0, 0.08)[:, None]
        g.opacities[:] = 0.96
        return Setting(name, _colored(g, col), sky, water_level=setting_levels(name)["water_level"], label=SETTING_LAYOUTS[name].label)
    if name == "underwater":
        floor = _ground(rng, int(budget * 0.8), radius, (0.78, 0.72, 0.55), 3.0, 0.15, cameras=cams)
        floor.colors = np.clip(floor.colors * [0.75, 0.95, 1.0], 0, 1)       # water tint
        n_p = int(budget * 0.2)
        p = np.c_[rng.uniform(-radius * 0.5, radius * 0.5, n_p), rng.uniform(-radius * 0.3, radius * 0.7, n_p),
                  rng.uniform(0.1, 3.0, n_p)]
        particles = _flat(p, np.full(n_p, 0.02), np.tile([0.75, 0.9, 0.92], (n_p, 1)), rng, opacity=0.35, shade=False)
        return Setting(name, _merge([floor, particles]), (0.12, 0.45, 0.55),
                       swim_height=setting_levels(name)["swim_height"], label=SETTING_LAYOUTS[name].label)
    if name == "table":
        top = _ground(rng, int(budget * 0.8), radius * 0.6, (0.6, 0.42, 0.26), 1.0, 0.05, cameras=cams)
        grain = 0.88 + 0.12 * np.sin(top.means[:, 0] * 25.0 + np.sin(top.means[:, 1] * 3.0) * 2.0)
        top.colors = np.clip(top.colors * grain[:, None], 0, 1)
        wall = _backdrop(rng, int(budget * 0.2), radius * 0.55, radius * 2.0, radius * 0.6, (0.85, 0.82, 0.76),
                         z0=-radius * 0.2, hills=False, noise=0.03)
        return Setting(name, _merge([top, wall]), (0.8, 0.78, 0.74), label=SETTING_LAYOUTS[name].label)
    if name == "indoor":
        floor = _ground(rng, int(budget * 0.75), radius * 0.7, (0.62, 0.45, 0.3), 1.0, 0.06, cameras=cams)
        planks = 0.85 + 0.15 * ((floor.means[:, 0] * 4.0) % 1.0 > 0.05)
        floor.colors = np.clip(floor.colors * planks[:, None], 0, 1)
        wall = _backdrop(rng, int(budget * 0.25), radius * 0.6, radius * 2.0, radius * 0.5, (0.9, 0.88, 0.82),
                         hills=False, noise=0.03)
        return Setting(name, _merge([floor, wall]), (0.85, 0.84, 0.8), label=SETTING_LAYOUTS[name].label)
    # sky: only clouds far away; objects fly
    n = budget
    clumps = rng.integers(0, 12, n)
    centres = np.c_[rng.uniform(-radius, radius, 12), rng.uniform(radius * 0.6, radius, 12), rng.uniform(0, radius * 0.3, 12)]
    c = centres[clumps] + rng.normal(size=(n, 3)) * [radius * 0.08, radius * 0.03, radius * 0.02]
    clouds = _flat(c, np.full(n, radius * 0.03), np.tile([0.97, 0.97, 0.99], (n, 1)), rng, normal=(0.0, -1.0, 0.0),
                   opacity=0.55, shade=False)
    return Setting(name, clouds, (0.45, 0.65, 0.92), air_height=setting_levels(name)["air_height"],
                   label=SETTING_LAYOUTS["sky"].label)


def carve_under(cloud: SurfaceCloud, base: np.ndarray, spacing: float) -> SurfaceCloud:
    """The setting with a resting object's footprint carved out.

    `base` [m, 3] are the object's lowest surface points in world coordinates, about `spacing`
    metres apart; only setting Gaussians at that height are touched. The renderer orders Gaussians by the depth of their centres, so a large flat
    setting Gaussian whose disc reaches under the object, with its centre in front of the
    object's own Gaussians, draws the ground through the object (a table showing through a
    plate at a low view). Setting Gaussians the base covers entirely are dropped; those whose
    disc (two standard deviations) reaches under it are replaced by small ones of the same
    colour on a grid `1.5 spacing` apart, less those under the base.
    """
    if len(base) == 0 or spacing <= 0:
        return cloud
    cell = 2.0 * spacing
    lo = base[:, :2].min(axis=0) - 2 * cell
    ij = np.floor((base[:, :2] - lo) / cell).astype(np.int64)
    shape = np.asarray(ij.max(axis=0) + 3)
    occupied = np.zeros(tuple(shape), bool)
    occupied[ij[:, 0], ij[:, 1]] = True
    # close one-cell gaps of the sampling; `inner`: cells whose four neighbours are occupied too
    # (a rim cell is partly outside the base)
    closed = occupied.copy()
    closed[1:-1, 1:-1] |= (occupied[:-2, 1:-1] & occupied[2:, 1:-1]) | (occupied[1:-1, :-2] & occupied[1:-1, 2:])
    inner = np.zeros_like(closed)
    inner[1:-1, 1:-1] = (closed[1:-1, 1:-1] & closed[:-2, 1:-1] & closed[2:, 1:-1]
                         & closed[1:-1, :-2] & closed[1:-1, 2:])

    def lookup(grid: np.ndarray, xy: np.ndarray) -> np.ndarray:
        k = np.floor((xy - lo) / cell).astype(np.int64)
        inside = np.all((k >= 0) & (k < shape), axis=1)
        out = np.zeros(len(xy), bool)
        out[inside] = grid[k[inside, 0], k[inside, 1]]
        return out

    # setting Gaussians at the height of the base (an object hovering above the ground hides nothing)
    z = cloud.means[:, 2]
    low = np.flatnonzero((z <= base[:, 2].max()) & (z >= base[:, 2].min() - 2.0 * spacing))
    reach = 2.0 * cloud.scales[low, :2].max(axis=1)
    angles = np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
    directions = np.r_[np.zeros((1, 2)), np.c_[np.cos(angles), np.sin(angles)]]
    covered = np.ones(len(low), bool)
    touches = np.zeros(len(low), bool)
    for d in directions:
        xy = cloud.means[low, :2] + reach[:, None] * d
        covered &= lookup(inner, xy)
        touches |= lookup(closed, xy)
    drop = np.zeros(len(cloud.means), bool)
    drop[low[touches]] = True
    # the small Gaussians that replace the parents reaching under the base: one grid `step` apart
    # shared by all parents, each point coloured by the parents' weights there
    step = 1.5 * spacing
    keys, parent, weight = [], [], []
    for j in low[touches & ~covered]:
        sigma = float(cloud.scales[j, :2].max())
        half = 1.5 * sigma
        k0 = np.floor((cloud.means[j, :2] - half - lo) / step).astype(np.int64)
        k1 = np.floor((cloud.means[j, :2] + half - lo) / step).astype(np.int64)
        g = np.stack(np.meshgrid(np.arange(k0[0], k1[0] + 1), np.arange(k0[1], k1[1] + 1), indexing="ij"),
                     -1).reshape(-1, 2)
        d2 = (((g + 0.5) * step + lo - cloud.means[j, :2]) ** 2).sum(axis=1)
        near = d2 <= half * half
        keys.append(g[near])
        parent.append(np.full(int(near.sum()), j))
        weight.append(np.exp(-0.5 * d2[near] / (sigma * sigma)))
    keep = ~drop
    if not keys:
        return cloud.subset(keep)
    keys, parent, weight = np.concatenate(keys), np.concatenate(parent), np.concatenate(weight)
    uniq, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.ravel()
    total = np.bincount(inv, weights=weight, minlength=len(uniq))

    def blend(values: np.ndarray) -> np.ndarray:
        return np.stack([np.bincount(inv, weights=weight * values[parent, c], minlength=len(uniq))
                         for c in range(values.shape[1])], axis=1) / total[:, None]

    xy = (uniq + 0.5) * step + lo
    under = lookup(inner, xy)
    # the strongest parent gives a point its orientation
    order = np.lexsort((-weight, inv))
    first = order[np.r_[0, np.flatnonzero(np.diff(inv[order])) + 1]]
    strongest = parent[first]
    tang = 0.85 * step
    ratio = cloud.scales[:, 2] / np.maximum(cloud.scales[:, :2].max(axis=1), 1e-12)
    n = len(uniq)
    children = SurfaceCloud(np.c_[xy, blend(cloud.means[:, 2:3])[:, 0]], cloud.quats[strongest],
                            np.c_[np.full((n, 2), tang), tang * blend(ratio[:, None])], blend(cloud.opacities[:, None])[:, 0],
                            blend(cloud.colors), cloud.nodes[strongest], cloud.node_names)
    return _merge([cloud.subset(keep), children.subset(~under)])
