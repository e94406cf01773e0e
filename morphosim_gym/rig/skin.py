"""An agent's MuJoCo geoms as Gaussians, so that cameras render the agent with the scene.

`AgentSkin` samples flat surface Gaussians over each visual geom of a model once (in the
geom's own frame, at the model's nominal size, with the scene's part sampler), then
poses them every step from MuJoCo's `geom_xpos` / `geom_xmat` and shades them with the
scene's fixed sun (`scene.lighting`) so they match the scene's baked lighting.

Supported geom types: sphere, capsule, ellipsoid, cylinder, box. Planes, meshes and
height fields are skipped (a rig's MJCF uses primitives only).
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np

from ..scene.gaussians import Gaussians
from ..scene.lighting import AMBIENT, DIFFUSE, LIGHT_DIR
from ..scene.parts import Part, parts_to_gaussians
from ..scene.rotations import quat_to_matrix

__all__ = ["AgentSkin", "geom_part"]

# mjtGeom values (stable across MuJoCo versions)
_PLANE, _HFIELD, _SPHERE, _CAPSULE, _ELLIPSOID, _CYLINDER, _BOX = 0, 1, 2, 3, 4, 5, 6

# Rotation taking the capsule sampler's x axis (its long axis) to MuJoCo's local z.
_X_TO_Z = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


def geom_part(geom_type: int, size: np.ndarray) -> Part | None:
    """The `Part` (in the geom's own frame, centred on it) of a MuJoCo primitive geom, or None
    for types that are not drawn (plane, height field, mesh, SDF)."""
    s = np.asarray(size, dtype=np.float64)
    if geom_type == _SPHERE:
        return Part("ellipsoid", dict(radii=(s[0], s[0], s[0])))
    if geom_type == _ELLIPSOID:
        return Part("ellipsoid", dict(radii=tuple(s[:3])))
    if geom_type == _CAPSULE:
        return Part("capsule", dict(radius=s[0], length=2 * s[1]), rotation=_X_TO_Z)
    if geom_type == _CYLINDER:
        return Part("cylinder", dict(radius=s[0], height=2 * s[1]), position=(0.0, 0.0, -s[1]))
    if geom_type == _BOX:
        return Part("box", dict(size=tuple(2 * s[:3])))
    return None


class AgentSkin:
    """Surface Gaussians of a model's visual geoms, posed per step.

    Args:
        model: a compiled `mujoco.MjModel`.
        object_id: the instance id the agent's Gaussians render with.
        budget: about how many Gaussians in all (shared by surface area).
        seed: sampling seed (the skin is the same for the same model and seed).
        groups: geom groups to draw (MJCF `group`); default group 1 (our rigs' visual geoms).
        geoms: optional subset of geom names to draw (default: all drawable geoms of `groups`).
        geom_size: [G, 3] geom sizes at scale 1 (default the model's current `geom_size`); pass the
            nominal sizes when the model has been scaled since, as `gaussians(scale=...)` scales again.

    Examples:
        >>> skin = AgentSkin(model, object_id=100)              # doctest: +SKIP
        >>> g = skin.gaussians(data, scale=0.4)                 # doctest: +SKIP
        >>> g.means.shape                                       # doctest: +SKIP
        (1500, 3)
    """

    def __init__(self, model: Any, object_id: int = 100, budget: int = 1500, seed: int = 0,
                 groups: tuple[int, ...] = (1,), geoms: tuple[str, ...] | None = None,
                 geom_size: np.ndarray | None = None) -> None:
        rng = np.random.default_rng(seed)
        sizes = np.asarray(model.geom_size if geom_size is None else geom_size, dtype=np.float64)
        chosen = []
        for i in range(model.ngeom):
            if int(model.geom_group[i]) not in groups:
                continue
            if geoms is not None and model.geom(i).name not in geoms:
                continue
            part = geom_part(int(model.geom_type[i]), sizes[i])
            if part is None or float(model.geom_rgba[i, 3]) <= 0.0:
                continue
            chosen.append((i, part))
        if not chosen:
            raise ValueError("Expected at least one drawable geom (sphere, capsule, ellipsoid, cylinder, box) "
                             f"in groups {groups}, found none")
        areas = np.array([max(p.area(), 1e-9) for _, p in chosen])
        counts = np.maximum(24, np.round(budget * areas / areas.sum())).astype(int)
        means, quats, scales, opac, colors, index = [], [], [], [], [], []
        for (gid, part), n in zip(chosen, counts):
            rgb = np.asarray(model.geom_rgba[gid, :3], dtype=np.float64)
            cloud = parts_to_gaussians([part], int(n), rgb, rng, shade=False)
            means.append(cloud.means)
            quats.append(cloud.quats)
            scales.append(cloud.scales)
            opac.append(np.full(len(cloud.means), 0.98))
            colors.append(cloud.colors)
            index.append(np.full(len(cloud.means), gid))
        self.object_id = int(object_id)
        self.geom_ids = np.array([g for g, _ in chosen], dtype=np.int64)
        self._geom_of = np.concatenate(index)
        self._means = np.concatenate(means).astype(np.float64)
        self._quats = np.concatenate(quats).astype(np.float64)
        self._scales = np.concatenate(scales).astype(np.float32)
        self._opacities = np.concatenate(opac).astype(np.float32)
        self._albedo = np.concatenate(colors).astype(np.float64)
        self._normals = quat_to_matrix(self._quats)[:, :, 2]       # a surface Gaussian's local z is its normal
        self._ids = np.full(len(self._means), self.object_id, dtype=np.int32)

    def __len__(self) -> int:
        return len(self._means)

    def gaussians(self, data: Any, scale: float = 1.0) -> Gaussians:
        """World Gaussians of the agent in its current pose (after `mj_kinematics`).

        Args:
            data: the `mujoco.MjData` holding `geom_xpos` [G, 3] and `geom_xmat` [G, 9].
            scale: the uniform scale the rig's model was scaled by (sizes and offsets).

        Returns:
            Gaussians with means [M, 3], quats [M, 4], scales [M, 3], opacities [M], colors [M, 3]
            and object_ids [M] (all `object_id`).
        """
        rot = np.ascontiguousarray(data.geom_xmat, dtype=np.float64).reshape(-1, 3, 3)
        pos = np.ascontiguousarray(data.geom_xpos, dtype=np.float64)
        m = len(self._means)
        means = np.empty((m, 3), np.float32)
        quats = np.empty((m, 4), np.float32)
        colors = np.empty((m, 3), np.float32)
        _pose_kernel(self._geom_of, self._means, self._quats, self._normals, self._albedo, rot, pos, float(scale),
                     LIGHT_DIR, AMBIENT, DIFFUSE, means, quats, colors)
        return Gaussians._trusted(means=means, quats=quats, scales=self._scales * np.float32(scale),
                                  opacities=self._opacities, colors=colors, features=None, object_ids=self._ids)


@numba.njit(cache=True, nogil=True)
def _pose_kernel(geom_of, local_means, local_quats, local_normals, albedo, rot, pos, scale, light, ambient, diffuse,
                 out_means, out_quats, out_colors):  # pragma: no cover - compiled
    """World means, quats and lit colours of skin Gaussians from their geoms' poses."""
    g_count = rot.shape[0]
    gq = np.zeros((g_count, 4))
    for g in range(g_count):                      # rotation matrix -> quaternion (w, x, y, z), per geom
        r = rot[g]
        tr = r[0, 0] + r[1, 1] + r[2, 2]
        if tr > 0.0:
            s = np.sqrt(tr + 1.0) * 2.0
            gq[g, 0] = 0.25 * s
            gq[g, 1] = (r[2, 1] - r[1, 2]) / s
            gq[g, 2] = (r[0, 2] - r[2, 0]) / s
            gq[g, 3] = (r[1, 0] - r[0, 1]) / s
        elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
            s = np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2]) * 2.0
            gq[g, 0] = (r[2, 1] - r[1, 2]) / s
            gq[g, 1] = 0.25 * s
            gq[g, 2] = (r[0, 1] + r[1, 0]) / s
            gq[g, 3] = (r[0, 2] + r[2, 0]) / s
        elif r[1, 1] > r[2, 2]:
            s = np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2]) * 2.0
            gq[g, 0] = (r[0, 2] - r[2, 0]) / s
            gq[g, 1] = (r[0, 1] + r[1, 0]) / s
            gq[g, 2] = 0.25 * s
            gq[g, 3] = (r[1, 2] + r[2, 1]) / s
        else:
            s = np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1]) * 2.0
            gq[g, 0] = (r[1, 0] - r[0, 1]) / s
            gq[g, 1] = (r[0, 2] + r[2, 0]) / s
            gq[g, 2] = (r[1, 2] + r[2, 1]) / s
            gq[g, 3] = 0.25 * s
    for i in range(local_means.shape[0]):
        g = geom_of[i]
        r = rot[g]
        x = local_means[i, 0] * scale
        y = local_means[i, 1] * scale
        z = local_means[i, 2] * scale
        for k in range(3):
            out_means[i, k] = r[k, 0] * x + r[k, 1] * y + r[k, 2] * z + pos[g, k]
        aw, ax, ay, az = gq[g, 0], gq[g, 1], gq[g, 2], gq[g, 3]
        bw, bx, by, bz = local_quats[i, 0], local_quats[i, 1], local_quats[i, 2], local_quats[i, 3]
        out_quats[i, 0] = aw * bw - ax * bx - ay * by - az * bz
        out_quats[i, 1] = aw * bx + ax * bw + ay * bz - az * by
        out_quats[i, 2] = aw * by - ax * bz + ay * bw + az * bx
        out_quats[i, 3] = aw * bz + ax * by - ay * bx + az * bw
        lam = 0.0
        for k in range(3):
            lam += (r[k, 0] * local_normals[i, 0] + r[k, 1] * local_normals[i, 1] + r[k, 2] * local_normals[i, 2]) \
                * light[k]
        shade = ambient + diffuse * min(max(lam, 0.0), 1.0)
        for k in range(3):
            out_colors[i, k] = min(max(albedo[i, k] * shade, 0.0), 1.0)
