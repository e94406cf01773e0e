"""The perturbation-axis edits on a `Scene4D`: size, swap, insertion, lighting, sky, texture, setting,
view, sensor and time offset.

Like `ops`, every function returns a new scene (`Scene4D.derive`), never mutates its input and
leaves what it does not target bit-identical:
    scale / texture:   only the selected Gaussians' rows (means+scales / colours)
    swap:              the target's rows are replaced (appended at the end, same object id and nodes)
    insert:            new rows appended, one new object; every existing row unchanged
    light:             colours (and background, sky) only; geometry, motion, cameras unchanged
    sky / setting:     sky and background (setting: also the background objects' colours)
    view:              cameras only
    sensor:            the scene's `sensor` effects only (rendering is unchanged; the env's
                       `SensorEffects` wrapper degrades the observations)
    delay:             only the scaffold nodes of the selected objects
Lighting is baked into the colours (`scene.lighting`), so a light edit is a colour transform:
brightness multiplies, temperature tints warm (+) or cool (-), direction re-shades the scene with a
ramp along the light's horizontal direction (the Gaussians carry no normals).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..errors import EditError
from ..scene import Gaussians, Motion, Scene4D, SceneObject
from ..scene.camera import Camera
from .ops import _moving_nodes, _with_node_poses, object_nodes
from .shapes import shape_gaussians

__all__ = ["scale_objects", "swap_objects", "insert_object", "light_brightness", "light_temperature",
           "light_direction", "set_sky", "texture", "set_setting", "change_view", "add_sensor", "delay",
           "sky_image", "SKY_COLORS", "SETTING_LOOKS"]

# sky name -> (zenith, horizon, ground-facing) colours of the procedural sky
SKY_COLORS: dict[str, tuple[tuple[float, float, float], ...]] = {
    "clear": ((0.25, 0.5, 0.92), (0.72, 0.84, 0.97), (0.5, 0.5, 0.5)),
    "sunset": ((0.25, 0.18, 0.45), (0.98, 0.55, 0.25), (0.35, 0.25, 0.22)),
    "overcast": ((0.62, 0.64, 0.67), (0.8, 0.8, 0.8), (0.45, 0.45, 0.45)),
    "night": ((0.02, 0.03, 0.09), (0.1, 0.12, 0.22), (0.05, 0.05, 0.06)),
    "dawn": ((0.45, 0.55, 0.8), (0.98, 0.8, 0.7), (0.45, 0.42, 0.4)),
}
# setting -> (ground colour, sky name)
SETTING_LOOKS: dict[str, tuple[tuple[float, float, float], str]] = {
    "snow": ((0.92, 0.94, 0.97), "overcast"), "grass": ((0.3, 0.55, 0.22), "clear"),
    "sand": ((0.86, 0.76, 0.52), "clear"), "road": ((0.3, 0.3, 0.32), "clear"),
    "water": ((0.12, 0.35, 0.6), "clear"), "table": ((0.55, 0.38, 0.22), "overcast"),
    "indoor": ((0.6, 0.55, 0.5), "overcast"), "ground": ((0.5, 0.45, 0.38), "clear"),
    "sky": ((0.72, 0.84, 0.97), "clear"),
}
INSERT_BUDGET = 600            # Gaussians of an inserted object


def _selected_ids(scene: Scene4D, selection: np.ndarray) -> list[int]:
    return sorted(set(np.unique(scene.gaussians.object_ids[selection]).tolist()) - {-1})


# ----------------------------------------------------------------- size
def scale_objects(scene: Scene4D, selection: np.ndarray, factor: float, label: str | None = None) -> Scene4D:
    """Resize the selected Gaussians by `factor` about their object's base point (the centre of its
    canonical footprint at its lowest point), so a resized object still stands where it stood."""
    if not (math.isfinite(factor) and factor > 0):
        raise ValueError(f"Expected a size factor > 0, found {factor}")
    g = scene.gaussians
    means, scales = g.means.copy(), g.scales.copy()
    for obj in _selected_ids(scene, selection):
        rows = selection & (g.object_ids == obj)
        pts = g.means[rows].astype(np.float64)
        base = np.array([*(0.5 * (pts[:, :2].min(0) + pts[:, :2].max(0))), pts[:, 2].min()])
        means[rows] = base + factor * (pts - base)
        scales[rows] = g.scales[rows] * factor
    return scene.derive(label, gaussians=g.replace(means=means, scales=scales))


# ----------------------------------------------------------------- new objects
def _append(scene: Scene4D, new: Gaussians, node: int, objects: tuple[SceneObject, ...], keep: np.ndarray,
            label: str | None) -> Scene4D:
    """Keep the rows `keep`, append `new` (bound rigidly to `node`, or unbound for -1)."""
    g, m = scene.gaussians, scene.motion
    kept = g.subset(keep)
    if g.features is not None and new.features is None:
        new = new.replace(features=np.zeros((len(new), g.feature_dim), dtype=g.features.dtype))
    merged = Gaussians.concat([kept, new])
    width = m.skin_nodes.shape[1]
    nodes = np.full((len(new), width), -1, dtype=np.int32)
    weights = np.zeros((len(new), width), dtype=np.float32)
    if node >= 0:
        nodes[:, 0], weights[:, 0] = node, 1.0
    motion = Motion(m.rotations, m.translations, np.concatenate([m.skin_nodes[keep], nodes]),
                    np.concatenate([m.skin_weights[keep], weights]), m.node_objects, m.shown)
    motion.rotations = m.rotations          # the stored bits (Motion re-normalises on construction)
    return scene.derive(label, gaussians=merged, motion=motion, objects=objects)


def swap_objects(scene: Scene4D, selection: np.ndarray, category: str, color: Sequence[float] | None = None,
                 label: str | None = None) -> Scene4D:
    """Replace each selected object by a `category` object as wide as it was, standing on the same
    base point, moving with the same scaffold node (its first), keeping its id; the object is
    renamed to `category`."""
    out = scene
    for obj in _selected_ids(scene, selection):
        g = out.gaussians
        rows = g.object_ids == obj
        pts = g.means[rows].astype(np.float64)
        width = float(max(np.ptp(pts[:, 0]), np.ptp(pts[:, 1]), 1e-3))
        base = np.array([*(0.5 * (pts[:, :2].min(0) + pts[:, :2].max(0))), pts[:, 2].min()])
        old = out.object(obj)
        rgb = tuple(color) if color is not None else old.color
        rng = np.random.default_rng([int(obj), len(category), 0x5A4B])
        new = shape_gaussians(category, width, rgb, max(int(rows.sum()), 200), rng, obj, g.feature_dim)
        new = new.replace(means=new.means + base)
        if g.features is not None:
            new = new.replace(features=np.repeat(g.features[rows].mean(0, keepdims=True), len(new), axis=0))
        nodes = object_nodes(out, [obj])
        objects = tuple(SceneObject(o.id, category, category, None if rgb is None else tuple(float(x) for x in rgb),
                                    o.dynamic, o.role) if o.id == obj else o for o in out.objects)
        out = _append(out, new, int(nodes[0]) if len(nodes) else -1, objects, ~rows, None)
    return scene.derive(label, gaussians=out.gaussians, motion=out.motion, objects=out.objects)


def _anchor_box(scene: Scene4D, ids: Sequence[int]) -> tuple[np.ndarray, float, float]:
    """(centre at t=0, width, floor z) of the anchors' Gaussians."""
    g = scene.at(0.0)
    pts = g.means[np.isin(g.object_ids, list(ids))].astype(np.float64)
    if len(pts) == 0:
        raise EditError(f"Cannot place a new object next to {ids}: they have no Gaussians")
    lo, hi = pts.min(0), pts.max(0)
    return 0.5 * (lo + hi), float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-3)), float(lo[2])


def insert_object(scene: Scene4D, anchor_ids: Sequence[int], category: str, color: Sequence[float] | None,
                  relation: str, label: str | None = None) -> Scene4D:
    """Add a static `category` object placed by `relation` to the anchors at t = 0 (see `InsertOp`);
    it gets the next free object id and is named `category`."""
    cam = scene.camera
    if anchor_ids:
        centre, width, floor = _anchor_box(scene, anchor_ids)
    else:
        centre, width, floor = scene.centre(), 0.4, float(np.min(scene.at(0.0).means[:, 2], initial=0.0))
    right = np.asarray(cam.camera_to_world[:3, 0], dtype=np.float64)
    right[2] = 0.0
    right /= max(np.linalg.norm(right), 1e-9)
    view = centre - cam.position
    view[2] = 0.0
    view /= max(np.linalg.norm(view), 1e-9)
    size, height = width, None
    if relation == "next_to":
        spot = centre + 1.2 * width * right
    elif relation == "behind":
        spot = centre + 1.5 * width * view
    elif relation == "in_front":
        spot = centre - 1.5 * width * view
    elif relation == "occluding":
        # on the line of sight from the generation camera to the anchor, 45% of the way to the camera (so
        # it looks ~1.8x as large as its width there), standing on the anchor's floor up past that line
        spot = centre + 0.45 * (cam.position - centre)
        size = 0.8 * width
        height = max(float(spot[2] - floor) + 0.6 * size, size)
    else:
        raise ValueError(f"Expected relation in ('next_to', 'occluding', 'behind', 'in_front'), found {relation!r}")
    new_id = max([o.id for o in scene.objects], default=-1) + 1
    rng = np.random.default_rng([new_id, len(category), 0x1A5E])
    new = shape_gaussians(category, size, color, INSERT_BUDGET, rng, new_id, scene.gaussians.feature_dim, height)
    new = new.replace(means=new.means + np.array([spot[0], spot[1], floor]))
    obj = SceneObject(new_id, category, category, None if color is None else tuple(float(x) for x in color))
    keep = np.ones(len(scene.gaussians), dtype=bool)
    return _append(scene, new, -1, scene.objects + (obj,), keep, label)


# ----------------------------------------------------------------- light
def _recolored(scene: Scene4D, colors: np.ndarray, gain_rgb: np.ndarray, label: str | None) -> Scene4D:
    bg = tuple(float(x) for x in np.clip(np.asarray(scene.background) * gain_rgb, 0.0, 1.0))
    sky = None if scene.sky is None else np.clip(scene.sky * gain_rgb.astype(np.float32), 0.0, 1.0)
    return scene.derive(label, gaussians=scene.gaussians.replace(colors=np.clip(colors, 0.0, 1.0)), background=bg,
                        sky=sky)


def light_brightness(scene: Scene4D, factor: float, label: str | None = None) -> Scene4D:
    """Multiply every colour (and the background and sky) by `factor`."""
    if not (math.isfinite(factor) and factor > 0):
        raise ValueError(f"Expected a brightness factor > 0, found {factor}")
    gain = np.full(3, factor)
    return _recolored(scene, scene.gaussians.colors * gain, gain, label)


def light_temperature(scene: Scene4D, amount: float, label: str | None = None) -> Scene4D:
    """Warm (amount > 0, more red, less blue) or cool (< 0) the light; amount in [-1, 1]."""
    if not (math.isfinite(amount) and -1.0 <= amount <= 1.0):
        raise ValueError(f"Expected a colour temperature amount in [-1, 1], found {amount}")
    gain = np.array([1.0 + 0.3 * amount, 1.0 + 0.05 * amount, 1.0 - 0.3 * amount])
    return _recolored(scene, scene.gaussians.colors * gain, gain, label)


def light_direction(scene: Scene4D, direction: Sequence[float], label: str | None = None) -> Scene4D:
    """Light from `direction` (world, towards the light): Gaussians on that side of the scene centre
    get up to 35% brighter, those on the far side up to 35% darker (a ramp over the scene's extent)."""
    d = np.asarray(direction, dtype=np.float64)
    d[2] = 0.0
    if np.linalg.norm(d) < 1e-9:
        raise EditError("Cannot light the scene from straight above or below: the light's direction is baked "
                        "from above already; say left, right, front or back")
    d /= np.linalg.norm(d)
    g = scene.gaussians
    rel = (g.means.astype(np.float64) - scene.centre()) @ d
    radius = max(float(np.percentile(np.abs(rel), 90)), 1e-6)
    gain = 1.0 + 0.35 * np.clip(rel / radius, -1.0, 1.0)
    colors = np.clip(g.colors * gain[:, None], 0.0, 1.0)
    return scene.derive(label, gaussians=g.replace(colors=colors.astype(g.colors.dtype)))


# ----------------------------------------------------------------- sky, texture, setting
def sky_image(name: str, height: int = 32, width: int = 64) -> np.ndarray:
    """The procedural equirectangular sky `name` ([height, width, 3] in [0, 1]): zenith to horizon
    gradient above, a dim ground colour below."""
    if name not in SKY_COLORS:
        raise EditError(f"Expected a sky in {sorted(SKY_COLORS)}, found {name!r}")
    zenith, horizon, below = (np.asarray(c, dtype=np.float32) for c in SKY_COLORS[name])
    v = (np.arange(height, dtype=np.float32) + 0.5) / height            # 0 up, 1 down
    up = np.clip(1.0 - 2.0 * v, 0.0, 1.0)[:, None] ** 0.6
    rows = np.where((v < 0.5)[:, None], horizon + (zenith - horizon) * up, below)
    return np.repeat(rows[:, None, :], width, axis=1).astype(np.float32)


def set_sky(scene: Scene4D, name: str, label: str | None = None) -> Scene4D:
    """Show the sky `name` (`SKY_COLORS`) behind the scene; the background becomes its horizon colour."""
    img = sky_image(name)
    return scene.derive(label, sky=img, background=tuple(float(x) for x in SKY_COLORS[name][1]))


_PATTERN_CELLS = 4.0            # pattern cells across an object


def texture(scene: Scene4D, selection: np.ndarray, name: str, label: str | None = None) -> Scene4D:
    """Give the selected Gaussians a pattern (checkered, striped, dotted, noisy: dark cells at 55%)
    or a material (metallic: contrast x2 about the mean and a cool sheen; matte: shading flattened
    towards the mean colour; glossy: the brightest third brightened), per object, from canonical
    positions so the pattern moves with the object."""
    g = scene.gaussians
    colors = g.colors.astype(np.float64).copy()
    for obj in _selected_ids(scene, selection):
        rows = selection & (g.object_ids == obj)
        c = colors[rows]
        pts = g.means[rows].astype(np.float64)
        cell = max(float(np.ptp(pts, axis=0).max()) / _PATTERN_CELLS, 1e-6)
        q = np.floor((pts - pts.min(0)) / cell).astype(np.int64)
        if name == "checkered":
            gain = np.where(q.sum(1) % 2 == 0, 1.0, 0.55)[:, None]
        elif name == "striped":
            gain = np.where(q[:, 2] % 2 == 0, 1.0, 0.55)[:, None] if np.ptp(pts[:, 2]) > cell else \
                np.where(q[:, 0] % 2 == 0, 1.0, 0.55)[:, None]
        elif name == "dotted":
            frac = (pts - pts.min(0)) / cell - q - 0.5
            gain = np.where(np.linalg.norm(frac, axis=1) < 0.3, 0.55, 1.0)[:, None]
        elif name == "noisy":
            gain = np.random.default_rng([int(obj), 0x7E47]).uniform(0.55, 1.0, (len(c), 1))
        elif name == "metallic":
            mean = c.mean(0)
            c = mean + 2.0 * (c - mean) + np.array([0.04, 0.06, 0.1])
            gain = np.ones((len(c), 1))
        elif name == "matte":
            c = c.mean(0) + 0.3 * (c - c.mean(0))
            gain = np.ones((len(c), 1))
        elif name == "glossy":
            lum = c @ np.array([0.299, 0.587, 0.114])
            gain = np.where(lum >= np.quantile(lum, 2 / 3), 1.35, 1.0)[:, None]
        else:
            raise EditError(f"Expected a texture in (checkered, striped, dotted, noisy, metallic, matte, glossy), "
                            f"found {name!r}")
        colors[rows] = c * gain
    return scene.derive(label, gaussians=g.replace(colors=np.clip(colors, 0, 1).astype(g.colors.dtype)))


def set_setting(scene: Scene4D, name: str, label: str | None = None) -> Scene4D:
    """Move the scene to the setting `name` (`SETTING_LOOKS`): its background objects (ground,
    backdrop) take the setting's ground colour, keeping their shading, and the sky changes."""
    if name not in SETTING_LOOKS:
        raise EditError(f"Expected a setting in {sorted(SETTING_LOOKS)}, found {name!r}")
    ground, sky = SETTING_LOOKS[name]
    back = [o.id for o in scene.objects if o.role == "background"]
    if not back:
        raise EditError(f"Cannot move the scene to {name!r}: it has no ground or backdrop object "
                        f"(objects: {scene.object_names})")
    g = scene.gaussians
    rows = np.isin(g.object_ids, back)
    colors = g.colors.copy()
    c = g.colors[rows].astype(np.float64)
    lum = c @ np.array([0.299, 0.587, 0.114])
    shade = np.clip(lum / max(float(lum.mean()), 1e-6), 0.6, 1.4)
    colors[rows] = np.clip(np.asarray(ground)[None, :] * shade[:, None], 0.0, 1.0)
    return set_sky(scene.derive(None, gaussians=g.replace(colors=colors)), sky, label)


# ----------------------------------------------------------------- camera, sensor, time
def change_view(scene: Scene4D, fov_factor: float | None = None, height: float | None = None,
                label: str | None = None) -> Scene4D:
    """Every generation camera: field of view times `fov_factor` (clipped to [5, 150] degrees) and/or
    raised by `height` metres, still looking at the scene centre."""
    centre = scene.centre()
    cams = []
    for cam in scene.cameras:
        fov = cam.fov_y_deg if fov_factor is None else float(np.clip(cam.fov_y_deg * fov_factor, 5.0, 150.0))
        if height:
            eye = cam.position + np.array([0.0, 0.0, height])
            if np.linalg.norm(np.cross(centre - eye, [0.0, 0.0, 1.0])) < 1e-6:
                raise EditError("Cannot move the camera to straight above the point it looks at")
            cam = Camera.look_at(eye, centre, cam.width, cam.height, cam.fov_y_deg, near=cam.near)
        cams.append(_with_fov(cam, fov) if fov_factor is not None else cam)
    return scene.derive(label, cameras=tuple(cams))


def _with_fov(cam: Camera, fov_y_deg: float) -> Camera:
    fx, fy, cx, cy = Camera.intrinsics_from_fov(cam.width, cam.height, fov_y_deg)
    return Camera(cam.width, cam.height, fx, fy, cx, cy, np.array(cam.world_to_camera), cam.near)


def add_sensor(scene: Scene4D, name: str, amount: float, label: str | None = None) -> Scene4D:
    """Record a sensor effect (`name`, `amount`) on the scene (replacing an earlier one of that name)."""
    effects = tuple(e for e in scene.sensor if e[0] != name) + ((name, float(amount)),)
    return scene.derive(label, sensor=effects)


def delay(scene: Scene4D, object_ids: Sequence[int], seconds: float, label: str | None = None) -> Scene4D:
    """Start the selected objects' motion `seconds` later (< 0: earlier): frame i shows the pose of
    frame i - seconds * fps, held at the first and last frames."""
    if not math.isfinite(seconds):
        raise ValueError(f"Expected a finite time offset, found {seconds}")
    nodes = _moving_nodes(scene, object_ids, "shift the motion of")
    m = scene.motion
    T = m.num_frames
    rot = np.empty((T, len(nodes), 4))
    trans = np.empty((T, len(nodes), 3))
    for i in range(T):
        r, t = m.node_poses(float(np.clip(i - seconds * scene.fps, 0, T - 1)))
        rot[i], trans[i] = r[nodes], t[nodes]
    return _with_node_poses(scene, nodes, rot, trans, object_ids, label)
