"""Complete what a monocular clip never shows, so novel views are plausible rather than empty.

Two documented priors (heuristics, not learned):
* ground: a plane is fitted (RANSAC) to the static Gaussians that face up; grid cells of the
  plane around the observed ground that hold no Gaussian get one, coloured like the nearest
  observed cell (the ground continues beyond and behind what the camera saw);
* symmetry: each object's visible side is mirrored across the vertical plane through its
  centre that faces the camera it was seen from, wherever that leaves empty space (objects
  are assumed left/right symmetric in depth: their far side looks like their near side).
Added Gaussians keep the instance id of what they complete and are skinned like it.
"""

from __future__ import annotations

import cv2
import numpy as np
import torch

from ..scene import GeneratedClip
from .model import DynamicGaussians, inverse_sigmoid, quat_to_rotmat

__all__ = ["complete", "fit_ground_plane"]


def fit_ground_plane(points: np.ndarray, rng: np.random.Generator, iters: int = 200,
                     tolerance: float | None = None) -> tuple[np.ndarray, float, np.ndarray]:
    """RANSAC plane n . x = d (n pointing up) through `points` [n, 3]; returns (n, d, inlier mask)."""
    if len(points) < 3:
        raise ValueError(f"Expected at least 3 points to fit a plane, found {len(points)}")
    scale = float(np.ptp(points, axis=0).max()) or 1.0
    tol = tolerance if tolerance is not None else 0.01 * scale
    best = (np.array([0.0, 0.0, 1.0]), float(np.median(points[:, 2])), np.zeros(len(points), bool))
    for _ in range(iters):
        p = points[rng.choice(len(points), 3, replace=False)]
        n = np.cross(p[1] - p[0], p[2] - p[0])
        norm = np.linalg.norm(n)
        if norm < 1e-12:
            continue
        n = n / norm
        if n[2] < 0:
            n = -n
        if n[2] < 0.8:               # a ground, not a wall
            continue
        d = float(n @ p[0])
        inl = np.abs(points @ n - d) < tol
        if inl.sum() > best[2].sum():
            best = (n, d, inl)
    n, d, inl = best
    if inl.sum() >= 3:               # least-squares refinement on the inliers
        q = points[inl]
        c = q.mean(0)
        _, _, vt = np.linalg.svd(q - c)
        n = vt[-1] if vt[-1][2] > 0 else -vt[-1]
        d = float(n @ c)
        inl = np.abs(points @ n - d) < tol
    return n, d, inl


def _append(model: DynamicGaussians, means, quats, scales, opacities, colors, ids) -> None:
    f = torch.float32
    with torch.no_grad():
        model.means = torch.nn.Parameter(torch.cat([model.means.data, torch.as_tensor(means, dtype=f)]))
        model.quats = torch.nn.Parameter(torch.cat([model.quats.data, torch.as_tensor(quats, dtype=f)]))
        model.log_scales = torch.nn.Parameter(torch.cat([model.log_scales.data,
                                                         torch.log(torch.as_tensor(scales, dtype=f))]))
        model.opacity_logits = torch.nn.Parameter(torch.cat([model.opacity_logits.data,
                                                             torch.as_tensor(inverse_sigmoid(opacities), dtype=f)]))
        model.color_logits = torch.nn.Parameter(torch.cat([model.color_logits.data,
                                                           torch.as_tensor(inverse_sigmoid(colors, 1e-3), dtype=f)]))
        model.object_ids = torch.cat([model.object_ids, torch.as_tensor(ids, dtype=torch.int32)])
    model.rebind()


def _complete_ground(model: DynamicGaussians, clip: GeneratedClip, dynamic: dict, rng: np.random.Generator,
                     max_new: int) -> int:
    with torch.no_grad():
        means = model.means.numpy().astype(np.float64)
        normals = quat_to_rotmat(model.quats).numpy()[:, :, 2]
        ids = model.object_ids.numpy()
        colors = model.colors().numpy()
        scales = model.scales().numpy()
        opac = model.opacities().numpy()
    static_ids = [i for i, d in dynamic.items() if not d]
    cand = np.isin(ids, static_ids) & (np.abs(normals[:, 2]) > 0.8) & (opac > 0.5)
    if cand.sum() < 50:
        return 0
    n, d, inl = fit_ground_plane(means[cand], rng)
    ground = np.flatnonzero(cand)[inl]
    if len(ground) < 50:
        return 0
    label = int(np.bincount(ids[ground]).argmax())
    # plane coordinates: two horizontal axes on the plane
    e1 = np.cross(n, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    uv = np.c_[means[ground] @ e1, means[ground] @ e2]
    cell = float(np.median(scales[ground, :2])) * 3.0
    lo, hi = uv.min(0), uv.max(0)
    extent = hi - lo
    lo, hi = lo - 1.5 * extent, hi + 1.5 * extent
    while True:                       # coarsen until every empty cell fits in the budget (no holes)
        size = np.ceil((hi - lo) / cell).astype(int)
        grid = np.full(tuple(size[::-1]), -1, np.int64)
        cells = np.floor((uv - lo) / cell).astype(int)
        grid[cells[:, 1], cells[:, 0]] = np.arange(len(ground))
        empty = (grid < 0).astype(np.uint8)
        if empty.sum() <= max_new:
            break
        cell *= 1.25
    if empty.sum() == 0:
        return 0
    _, labels = cv2.distanceTransformWithLabels(empty, cv2.DIST_L2, 5, labelType=cv2.DIST_LABEL_PIXEL)
    # map distance-transform labels (one per zero pixel) back to the observed Gaussian in that cell
    zero_rows, zero_cols = np.nonzero(empty == 0)
    label_to_gauss = np.full(labels.max() + 1, -1, np.int64)
    label_to_gauss[labels[zero_rows, zero_cols]] = grid[zero_rows, zero_cols]
    rows, cols = np.nonzero(empty)
    src = label_to_gauss[labels[rows, cols]]
    ok = src >= 0
    rows, cols, src = rows[ok], cols[ok], ground[src[ok]]
    pu = lo[0] + (cols + rng.random(len(cols))) * cell
    pv = lo[1] + (rows + rng.random(len(rows))) * cell
    pts = pu[:, None] * e1 + pv[:, None] * e2 + d * n
    k = len(pts)
    quats = np.tile(_quat_from_normal(n), (k, 1))
    sc = np.c_[np.full(k, cell * 0.8), np.full(k, cell * 0.8), np.full(k, cell * 0.15)]
    jitter = 1.0 + 0.04 * rng.standard_normal((k, 1))
    _append(model, pts, quats, sc, np.full(k, 0.95), np.clip(colors[src] * jitter, 0, 1), np.full(k, label))
    return k


def _quat_from_normal(n: np.ndarray) -> np.ndarray:
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(z, n)
    s = np.linalg.norm(axis)
    if s < 1e-9:
        return np.array([1.0, 0.0, 0.0, 0.0])
    angle = np.arctan2(s, z @ n)
    axis /= s
    return np.r_[np.cos(angle / 2), np.sin(angle / 2) * axis]


def _complete_symmetry(model: DynamicGaussians, clip: GeneratedClip, dynamic: dict, reference: dict | None,
                       background: set[int]) -> int:
    with torch.no_grad():
        means = model.means.numpy().astype(np.float64)
        quats = model.quats.numpy().astype(np.float64)
        ids = model.object_ids.numpy()
        colors = model.colors().numpy()
        scales = model.scales().numpy()
        opac = model.opacities().numpy()
    added = 0
    new = {k: [] for k in ("means", "quats", "scales", "opacities", "colors", "ids")}
    for inst in sorted(set(ids.tolist()) - background):
        sel = np.flatnonzero(ids == inst)
        if len(sel) < 20:
            continue
        frame = (reference or {}).get(inst, 0)
        cam = clip.cameras[frame]
        view = cam.forward.copy()
        view[2] = 0.0
        if np.linalg.norm(view) < 1e-6:
            continue
        view /= np.linalg.norm(view)
        p = means[sel]
        centre = p.mean(0)
        depth = (p - centre) @ view
        # mirror across the plane through the centre (shifted to the depth midpoint of what is seen)
        mid = 0.5 * (depth.min() + depth.max()) if np.ptp(depth) > 0 else 0.0
        plane = centre @ view + max(mid, float(np.median(depth)))
        mirrored = p - 2.0 * ((p @ view) - plane)[:, None] * view[None, :]
        # keep only mirrored points that land away from existing ones (an occupancy grid test)
        cell = float(np.median(scales[sel, :2])) * 2.0
        occupied = set(map(tuple, np.floor(p / cell).astype(int)))
        keys = np.floor(mirrored / cell).astype(int)
        free = np.array([tuple(k) not in occupied for k in keys])
        if not free.any():
            continue
        R = np.eye(3) - 2.0 * np.outer(view, view)
        from ..scene.rotations import matrix_to_quat, quat_to_matrix

        mats = quat_to_matrix(quats[sel][free])
        mq = matrix_to_quat(np.einsum("ij,njk->nik", R, mats) @ np.diag([1.0, 1.0, -1.0]))
        new["means"].append(mirrored[free])
        new["quats"].append(mq)
        new["scales"].append(scales[sel][free])
        new["opacities"].append(opac[sel][free])
        new["colors"].append(colors[sel][free])
        new["ids"].append(ids[sel][free])
        added += int(free.sum())
    if added:
        _append(model, *(np.concatenate(new[k]) for k in ("means", "quats", "scales", "opacities", "colors", "ids")))
    return added


def complete(model: DynamicGaussians, clip: GeneratedClip, dynamic: dict, seed: int = 0,
             reference: dict | None = None, max_ground: int = 12000) -> dict[str, int]:
    """Add ground and far-side Gaussians to a fitted model (in place); returns how many of each."""
    rng = np.random.default_rng([seed, 11])
    ground = _complete_ground(model, clip, dynamic, rng, max_ground)
    from ..language.vocabulary import word_to_setting

    background = {i for i, name in clip.labels.items() if word_to_setting(name.lower())}
    sym = _complete_symmetry(model, clip, dynamic, reference, background)
    return {"ground": ground, "symmetry": sym}
