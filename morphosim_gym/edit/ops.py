"""Edit operations on a `Scene4D`, given which Gaussians (or objects) they apply to.

Every function returns a new scene (via `Scene4D.derive`), never mutates its input, and
leaves what it does not target bit-identical: static edits touch only the selected
Gaussians' rows, dynamic edits only the scaffold nodes of the selected objects.

Colour functions (the paper's, with the parameters the parser gives):
    assign:          c' = rgb * s_j, s_j the Gaussian's shading relative to the selection's
                     mean brightness (kept in [0.6, 1.4]; `keep_shading=False` gives c' = rgb)
    additive:        c' = clip(c + delta)
    multiplicative:  c' = clip(c * factor_rgb)
Dynamic edits rewrite node poses: reverse plays the object's motion backwards, redirect turns
its displacement (and heading, for horizontal turns) towards a new direction, speed remaps
time by a factor (a faster object finishes early and waits; a slower one covers less), stop
freezes it at its first pose.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..errors import EditError
from ..scene import Motion, Scene4D
from ..scene.rotations import axis_angle_to_quat, matrix_to_quat, quat_to_matrix

__all__ = ["recolor", "remove", "extract", "reverse", "redirect", "change_speed", "stop", "object_nodes",
           "ensure_nodes", "main_direction"]


def _luminance(c: np.ndarray) -> np.ndarray:
    return c @ np.array([0.299, 0.587, 0.114])


def recolor(scene: Scene4D, selection: np.ndarray, mode: str, rgb: Sequence[float] | None = None,
            delta: Sequence[float] | None = None, factor_rgb: Sequence[float] | None = None,
            keep_shading: bool = True, label: str | None = None) -> Scene4D:
    """Change the colour of the selected Gaussians ([N] bool)."""
    sel = _check_selection(scene, selection)
    colors = scene.gaussians.colors.copy()
    c = colors[sel].astype(np.float64)
    if mode == "assign":
        if rgb is None:
            raise ValueError("Expected rgb for an 'assign' recolour, found none")
        target = np.asarray(rgb, dtype=np.float64)
        if keep_shading and len(c):
            lum = _luminance(c)
            # half the object's relative shading, averaging 1 so the object reads as the asked colour
            shade = 1.0 + 0.5 * (np.clip(lum / max(float(lum.mean()), 1e-6), 0.6, 1.4) - 1.0)
            shade /= shade.mean()
            new = target[None, :] * shade[:, None]
        else:
            new = np.broadcast_to(target, c.shape)
    elif mode == "additive":
        if delta is None:
            raise ValueError("Expected delta for an 'additive' recolour, found none")
        new = c + np.asarray(delta, dtype=np.float64)
    elif mode == "multiplicative":
        if factor_rgb is None:
            raise ValueError("Expected factor_rgb for a 'multiplicative' recolour, found none")
        new = c * np.asarray(factor_rgb, dtype=np.float64)
    else:
        raise ValueError(f"Expected mode 'assign', 'additive' or 'multiplicative', found {mode!r}")
    colors[sel] = np.clip(new, 0.0, 1.0)
    g = scene.gaussians.replace(colors=colors)
    objects = scene.objects
    if mode == "assign" and rgb is not None:
        touched = set(np.unique(scene.gaussians.object_ids[sel]).tolist())
        objects = tuple(o.__class__(o.id, o.name, o.category, tuple(float(x) for x in rgb), o.dynamic, o.role)
                        if o.id in touched and o.role != "background" else o for o in objects)
    return scene.derive(label, gaussians=g, objects=objects)


def _keep(scene: Scene4D, keep: np.ndarray, label: str | None) -> Scene4D:
    g = scene.gaussians.subset(keep)
    m = scene.motion
    motion = Motion(m.rotations, m.translations, m.skin_nodes[keep], m.skin_weights[keep], m.node_objects, m.shown)
    motion.rotations = m.rotations  # keep the stored bits (Motion re-normalises on construction)
    present = set(np.unique(g.object_ids).tolist())
    objects = tuple(o for o in scene.objects if o.id in present)
    return scene.derive(label, gaussians=g, motion=motion, objects=objects)


def remove(scene: Scene4D, selection: np.ndarray, label: str | None = None) -> Scene4D:
    """Delete the selected Gaussians (objects left with none disappear from `objects`)."""
    sel = _check_selection(scene, selection)
    return _keep(scene, ~sel, label)


def extract(scene: Scene4D, selection: np.ndarray, label: str | None = None) -> Scene4D:
    """Keep only the selected Gaussians (background removed)."""
    sel = _check_selection(scene, selection)
    return _keep(scene, sel, label)


# ----------------------------------------------------------------- motion
def object_nodes(scene: Scene4D, object_ids: Sequence[int]) -> np.ndarray:
    """Indices of the scaffold nodes that belong to these objects."""
    return np.flatnonzero(np.isin(scene.motion.node_objects, list(object_ids)))


def ensure_nodes(scene: Scene4D, object_ids: Sequence[int]) -> Scene4D:
    """Give every listed object without a scaffold node one rigid node (identity poses) and bind
    its Gaussians to it, so it can be moved. Returns the scene itself if nothing was missing."""
    m = scene.motion
    missing = [i for i in object_ids if not np.any(m.node_objects == i)]
    if not missing:
        return scene
    T = m.num_frames
    rot = np.concatenate([m.rotations, np.tile([1.0, 0, 0, 0], (T, len(missing), 1))], axis=1)
    trans = np.concatenate([m.translations, np.zeros((T, len(missing), 3))], axis=1)
    nodes, weights = m.skin_nodes.copy(), m.skin_weights.copy()
    ids = scene.gaussians.object_ids
    for k, obj in enumerate(missing):
        sel = ids == obj
        nodes[sel] = -1
        nodes[sel, 0] = m.num_nodes + k
        weights[sel] = 0.0
        weights[sel, 0] = 1.0
    shown = None if m.shown is None else np.concatenate([m.shown, np.ones((T, len(missing)), bool)], axis=1)
    motion = Motion(rot, trans, nodes, weights, np.concatenate([m.node_objects, missing]), shown)
    return scene.derive(None, motion=motion)


def _with_node_poses(scene: Scene4D, nodes: np.ndarray, rot: np.ndarray, trans: np.ndarray, object_ids, label,
                     dynamic: bool = True) -> Scene4D:
    m = scene.motion
    r, t = m.rotations.copy(), m.translations.copy()
    r[:, nodes] = rot
    t[:, nodes] = trans
    motion = Motion(r, t, m.skin_nodes, m.skin_weights, m.node_objects, m.shown)
    untouched = np.setdiff1d(np.arange(m.num_nodes), nodes)
    motion.rotations[:, untouched] = m.rotations[:, untouched]   # bit-exact for the rest
    objects = tuple(o.__class__(o.id, o.name, o.category, o.color, dynamic, o.role) if o.id in set(object_ids) else o
                    for o in scene.objects)
    return scene.derive(label, motion=motion, objects=objects)


def _moving_nodes(scene: Scene4D, object_ids: Sequence[int], what: str) -> np.ndarray:
    nodes = object_nodes(scene, object_ids)
    if len(nodes) == 0 or np.allclose(scene.motion.translations[:, nodes], scene.motion.translations[:1, nodes]) and \
            np.allclose(scene.motion.rotations[:, nodes], scene.motion.rotations[:1, nodes]):
        names = [o.name for o in scene.objects if o.id in set(object_ids)]
        raise EditError(f"Cannot {what} {names}: it does not move in this scene")
    return nodes


def reverse(scene: Scene4D, object_ids: Sequence[int], label: str | None = None) -> Scene4D:
    """Play the selected objects' motion backwards (the path traversed from its end to its start)."""
    nodes = _moving_nodes(scene, object_ids, "reverse")
    m = scene.motion
    return _with_node_poses(scene, nodes, m.rotations[::-1][:, nodes], m.translations[::-1][:, nodes], object_ids,
                            label)


def _object_track(scene: Scene4D, object_ids: Sequence[int]) -> np.ndarray:
    """[T, 3] centroid of the selected objects' Gaussians at each frame.

    Exact for linear blend skinning without moving every Gaussian: the mean of
    sum_m w_jm (R_m x_j + t_m) over Gaussians j is sum_m (R_m a_m + b_m t_m) / n with
    a_m = sum_j w_jm x_j and b_m = sum_j w_jm (unbound Gaussians stay put)."""
    sel = np.isin(scene.gaussians.object_ids, list(object_ids))
    m = scene.motion
    x = scene.gaussians.means[sel].astype(np.float64)
    nodes, w = m.skin_nodes[sel], m.skin_weights[sel].astype(np.float64)
    bound = nodes >= 0
    w = np.where(bound, w, 0.0)
    a = np.zeros((m.num_nodes, 3))
    b = np.zeros(m.num_nodes)
    np.add.at(a, nodes[bound], (w[..., None] * x[:, None, :])[bound])
    np.add.at(b, nodes[bound], w[bound])
    still = x[~bound.any(axis=1)].sum(axis=0)
    R = quat_to_matrix(m.rotations)                                          # [T, K, 3, 3]
    moving = np.einsum("tkij,kj->ti", R, a) + np.einsum("k,tki->ti", b, m.translations)
    return (moving + still) / max(int(sel.sum()), 1)


def main_direction(scene: Scene4D, object_ids: Sequence[int]) -> np.ndarray | None:
    """Unit world direction from the selected objects' first position to their last one, or None when
    they do not move or do not travel one way (they end nearer their start than 80 % of their farthest
    excursion: a circle, a back-and-forth)."""
    track = _object_track(scene, object_ids)
    disp = track - track[0]
    far = float(np.linalg.norm(disp, axis=1).max())
    norm = float(np.linalg.norm(disp[-1]))
    return None if far < 1e-6 or norm < 0.8 * far else disp[-1] / norm


def _rotation_between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    u = u / np.linalg.norm(u)
    v = v / np.linalg.norm(v)
    axis = np.cross(u, v)
    s, c = np.linalg.norm(axis), float(u @ v)
    if s < 1e-9:
        if c > 0:
            return np.eye(3)
        perp = np.cross(u, [0.0, 0.0, 1.0]) if abs(u[2]) < 0.9 else np.cross(u, [1.0, 0.0, 0.0])
        return quat_to_matrix(axis_angle_to_quat(perp, math.pi))
    return quat_to_matrix(axis_angle_to_quat(axis, math.atan2(s, c)))


def redirect(scene: Scene4D, object_ids: Sequence[int], direction: Sequence[float], label: str | None = None,
             default_travel: float | None = None) -> Scene4D:
    """Send the selected objects along a new world direction: their path is turned about its
    midpoint from its old main direction to `direction` (so it stays where it was on screen); for
    a turn within the ground plane the objects turn to face it too. A still object starts moving
    from where it stands (straight, `default_travel` metres over the clip, default 1.5x its size)."""
    new = np.asarray(direction, dtype=np.float64)
    if new.shape != (3,) or np.linalg.norm(new) < 1e-9:
        raise ValueError(f"Expected a non-zero world direction, found {direction!r}")
    new = new / np.linalg.norm(new)
    scene = ensure_nodes(scene, object_ids)
    nodes = object_nodes(scene, object_ids)
    m = scene.motion
    track = _object_track(scene, object_ids)
    disp = track - track[0]
    T = m.num_frames
    if np.linalg.norm(disp, axis=1).max() < 1e-6:
        sel = np.isin(scene.gaussians.object_ids, list(object_ids))
        size = float(np.ptp(scene.gaussians.means[sel], axis=0).max())
        travel = default_travel if default_travel is not None else 1.5 * size
        disp = np.linspace(0.0, travel, T)[:, None] * new[None, :]
        old = new
        turn = np.eye(3)
        pivot = np.zeros(3)
    else:
        old = disp[np.argmax(np.linalg.norm(disp, axis=1))]
        turn = _rotation_between(old, new)
        pivot = 0.5 * (disp.min(axis=0) + disp.max(axis=0))          # the middle of the path
    horizontal = abs(new[2]) < 0.5 and abs(old[2] / max(np.linalg.norm(old), 1e-12)) < 0.5
    if horizontal:
        yaw = math.atan2(new[1], new[0]) - math.atan2(old[1], old[0])
        spin = quat_to_matrix(axis_angle_to_quat(np.array([0.0, 0.0, 1.0]), yaw))
    else:
        spin = np.eye(3)
    # world'(t) = spin (world(t) - c(t)) + c(0) + pivot + turn (d(t) - pivot), as a change of node poses
    rot = np.empty((T, len(nodes), 4))
    trans = np.empty((T, len(nodes), 3))
    for i in range(T):
        R = quat_to_matrix(m.rotations[i, nodes])                         # [k, 3, 3]
        new_R = np.einsum("ij,kjl->kil", spin, R)
        shift = track[0] + pivot + turn @ (disp[i] - pivot) - spin @ track[i]
        rot[i] = matrix_to_quat(new_R)
        trans[i] = m.translations[i, nodes] @ spin.T + shift
    return _with_node_poses(scene, nodes, rot, trans, object_ids, label)


def change_speed(scene: Scene4D, object_ids: Sequence[int], factor: float, label: str | None = None) -> Scene4D:
    """Play the selected objects' motion `factor` times faster (time t shows the pose of factor * t,
    held at the end)."""
    if not (math.isfinite(factor) and factor > 0):
        raise ValueError(f"Expected a speed factor > 0, found {factor}")
    nodes = _moving_nodes(scene, object_ids, "change the speed of")
    m = scene.motion
    T = m.num_frames
    rot = np.empty((T, len(nodes), 4))
    trans = np.empty((T, len(nodes), 3))
    for i in range(T):
        frame = min(i * factor, T - 1)
        r, t = m.node_poses(frame)
        rot[i], trans[i] = r[nodes], t[nodes]
    return _with_node_poses(scene, nodes, rot, trans, object_ids, label)


def stop(scene: Scene4D, object_ids: Sequence[int], label: str | None = None) -> Scene4D:
    """Freeze the selected objects at their pose of the first frame."""
    nodes = _moving_nodes(scene, object_ids, "stop")
    m = scene.motion
    T = m.num_frames
    return _with_node_poses(scene, nodes, np.repeat(m.rotations[:1, nodes], T, axis=0),
                            np.repeat(m.translations[:1, nodes], T, axis=0), object_ids, label, dynamic=False)


def _check_selection(scene: Scene4D, selection: np.ndarray) -> np.ndarray:
    sel = np.asarray(selection)
    if sel.dtype != bool or sel.shape != (len(scene.gaussians),):
        raise ValueError(f"Expected a boolean selection of shape ({len(scene.gaussians)},), found {sel.dtype} {sel.shape}")
    return sel

