"""Complete what a monocular clip never shows, so novel views are plausible rather than empty.

Three documented priors (heuristics, not learned):
* ground: a plane is fitted (RANSAC) to the static Gaussians that face up; the empty plane
  around the observed ground is tiled with flat Gaussians in rings of growing size (fine next to
  what was seen, coarse far away), each coloured like the nearest observed cell (the ground
  continues beyond and behind what the camera saw); all cells grow when the rings would need
  more than `max_ground` discs, so the ground always reaches as far out; where the views show
  the ground end against empty space, it ends there on every side (`ground_reach`), and where
  a backdrop closes the view, the ground ends not far past it;
* backdrop: where most static Gaussians that face sideways lie on one vertical plane (hills,
  a wall: `find_backdrop`), it continues sideways beyond what was seen, up to the height seen
  (a novel view turned towards its end should not find the sky or the void there);
* symmetry: each object's visible side is mirrored across the vertical plane through its
  centre that faces the camera it was seen from, wherever that leaves empty space (objects
  are assumed left/right symmetric in depth: their far side looks like their near side).
Added Gaussians keep the instance id of what they complete and are skinned like it. Mirrored
Gaussians that an input view shows are dropped (`visible_weights`, measured with the renderer);
ground cells also fill gaps that the input views see, so the pipeline fits a few more
iterations after completion.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
import torch

from ..render import rasterize
from ..scene import GeneratedClip
from .model import DynamicGaussians, inverse_sigmoid, quat_to_rotmat

__all__ = ["Backdrop", "complete", "find_backdrop", "fit_backdrop_plane", "fit_ground_plane", "ground_reach",
           "seen_through", "visible_weights"]


def fit_ground_plane(points: np.ndarray, rng: np.random.Generator, iters: int = 200,
                     tolerance: float | None = None) -> tuple[np.ndarray, float, np.ndarray]:
    """RANSAC plane n . x = d (n pointing up) through `points` [n, 3]; returns (n, d, inlier mask)."""
    if len(points) < 3:
        raise ValueError(f"Expected at least 3 points to fit a plane, found {len(points)}")
    tol = _tolerance(points, tolerance)
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
        n, c = _least_squares_normal(points[inl])
        n = n if n[2] > 0 else -n
        d = float(n @ c)
        inl = np.abs(points @ n - d) < tol
    return n, d, inl


def _tolerance(points: np.ndarray, tolerance: float | None) -> float:
    """The inlier distance of a plane fit: `tolerance`, or 1% of the points' largest extent."""
    return tolerance if tolerance is not None else 0.01 * (float(np.ptp(points, axis=0).max()) or 1.0)


def _least_squares_normal(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit normal, centroid) of the least-squares plane (or line, in 2D) through `points`."""
    c = points.mean(0)
    _, _, vt = np.linalg.svd(points - c, full_matrices=False)
    return vt[-1], c


def fit_backdrop_plane(points: np.ndarray, rng: np.random.Generator, iters: int = 200,
                       tolerance: float | None = None) -> tuple[np.ndarray, float, np.ndarray]:
    """RANSAC vertical plane n . x = d (n horizontal) through `points` [n, 3]; returns (n, d, inlier mask)."""
    if len(points) < 2:
        raise ValueError(f"Expected at least 2 points to fit a vertical plane, found {len(points)}")
    tol = _tolerance(points, tolerance)
    xy = points[:, :2]
    best = (np.array([0.0, 1.0, 0.0]), float(np.median(points[:, 1])), np.zeros(len(points), bool))
    for _ in range(iters):
        a, b = xy[rng.choice(len(points), 2, replace=False)]
        t = b - a
        norm = np.linalg.norm(t)
        if norm < 1e-12:
            continue
        n2 = np.array([-t[1], t[0]]) / norm
        inl = np.abs(xy @ n2 - n2 @ a) < tol
        if inl.sum() > best[2].sum():
            best = (np.r_[n2, 0.0], float(n2 @ a), inl)
    n, d, inl = best
    if inl.sum() >= 2:               # least-squares refinement of the ground line on the inliers
        n2, c = _least_squares_normal(xy[inl])
        n, d = np.r_[n2, 0.0], float(n2 @ c)
        inl = np.abs(xy @ n2 - d) < tol
    return n, d, inl


def visible_weights(model: DynamicGaussians, clip: GeneratedClip, first: int, floor: float = 0.01,
                    frame_stride: int = 4) -> np.ndarray:
    """[N - first] how much each Gaussian from index `first` on shows in the input views (every
    `frame_stride`-th frame and the last): its blending weight summed over the pixels where those
    Gaussians together contribute more than `floor` of the colour (largest over the frames).

    Measured with the renderer itself: the new Gaussians carry a feature of 1 (the others 0),
    so a pixel's rendered feature is their joint weight there, and the gradient of
    sum(relu(feature - floor)) with respect to a Gaussian's feature is its weight over the
    pixels above the floor. Contributions below the floor (behind a nearly opaque surface)
    change the image by less than the floor and are ignored."""
    best = torch.zeros(model.num - first)
    frames = sorted(set(range(0, clip.num_frames, max(1, frame_stride))) | {clip.num_frames - 1})
    with torch.no_grad():
        scales, opacities, colors = model.scales(), model.opacities(), model.colors()
    for t in frames:
        cam = clip.cameras[t]
        probe = torch.zeros(model.num, 1)
        probe[first:] = 1.0
        probe.requires_grad_(True)
        with torch.no_grad():
            means, quats = model.warp(t)
        out = rasterize(means, quats, scales, opacities, colors,
                        torch.tensor(cam.world_to_camera[None], dtype=torch.float32),
                        torch.tensor(cam.K[None], dtype=torch.float32), cam.width, cam.height, features=probe,
                        nears=torch.tensor([cam.near], dtype=torch.float64))
        torch.relu(out["features"] - floor).sum().backward()
        best = torch.maximum(best, probe.grad[first:, 0].abs())
    return best.numpy()


def _drop_seen(model: DynamicGaussians, clip: GeneratedClip, first: int, threshold: float = 0.05,
               rounds: int = 3) -> int:
    """Remove the Gaussians from index `first` on that the input views show (`visible_weights`
    above `threshold` pixels), so that completion leaves the input views as fitted; repeated
    because removing one can uncover another. Returns how many are left."""
    for _ in range(rounds):
        if model.num == first:
            break
        seen = visible_weights(model, clip, first) > threshold
        if not seen.any():
            break
        keep = np.ones(model.num, bool)
        keep[first:] = ~seen
        _subset(model, keep)
    return model.num - first


def _near_cameras(model: DynamicGaussians, clip: GeneratedClip, first: int,
                  sigmas: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """For the Gaussians from index `first` on: (near [n], in_view [n]). `near`: the camera depth
    in some input frame is within `sigmas` times the largest scale of the camera plane (in front
    of it or behind: the affine footprint would be wrong); `in_view`: in one of those frames, the
    Gaussian (grown by the same reach) overlaps the view frustum."""
    cams = clip.cameras
    rot = np.stack([c.world_to_camera[:3, :3] for c in cams])                 # [T, 3, 3]
    off = np.stack([c.world_to_camera[:3, 3] for c in cams])                  # [T, 3]
    half = np.array([[0.5 * c.width / c.fx, 0.5 * c.height / c.fy] for c in cams])   # [T, 2] tan of half fov
    with torch.no_grad():
        reach = sigmas * model.scales()[first:].max(dim=1).values.numpy().astype(np.float64)
        points = model.means[first:]
        bound = model.bound[first:]
        if not bound.any():                       # static (ground discs): the same place in every frame
            pc = np.einsum("tij,nj->nti", rot, points.numpy().astype(np.float64)) + off[None]
        else:
            pc = np.empty((len(points), len(cams), 3))
            nodes, weights = model.skin_nodes[first:][bound], model.skin_weights[first:][bound]
            for t in range(len(cams)):
                world = points.clone()
                world[bound] = model.points_at(points[bound], nodes, weights, t)
                pc[:, t] = world.numpy().astype(np.float64) @ rot[t].T + off[t]
    r = reach[:, None]
    near = np.abs(pc[..., 2]) < r                                             # [n, T]
    lateral = np.abs(pc[..., :2]) - r[..., None] <= (pc[..., 2:3] + r[..., None]) * half[None]
    in_view = near & lateral.all(axis=-1)
    return near.any(axis=1), in_view.any(axis=1)


def _split_near(model: DynamicGaussians, clip: GeneratedClip, first: int, splits: int = 6) -> int:
    """Ground discs from index `first` on that come too close to an input camera (`_near_cameras`)
    inside its view are split into four discs of half the size, up to `splits` times; those still
    too close, and those near a camera but beside or behind its view (never seen there, and
    splitting them along the camera plane would multiply them for nothing), are dropped.
    Returns how many discs are left."""
    for round_ in range(splits + 1):
        near, in_view = _near_cameras(model, clip, first)
        if not near.any():
            break
        split = in_view if round_ < splits else np.zeros_like(in_view)    # the last round only drops
        idx = first + np.flatnonzero(split)
        keep = np.ones(model.num, bool)
        keep[first + np.flatnonzero(near)] = False
        with torch.no_grad():
            means = model.means[idx].numpy().astype(np.float64)
            quats = model.quats[idx].numpy()
            scales = model.scales()[idx].numpy()
            opac = model.opacities()[idx].numpy()
            colors = model.colors()[idx].numpy()
            axes = quat_to_rotmat(model.quats[idx]).numpy()        # columns: the disc's axes
        ids = model.object_ids[idx].numpy()
        _subset(model, keep)
        if not len(idx):
            continue
        quarter = scales[:, :1] / 0.8 / 4.0                         # a quarter of the cell side
        children = [means + (a * axes[:, :, 0] + b * axes[:, :, 1]) * quarter
                    for a, b in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
        _append(model, np.concatenate(children), np.tile(quats, (4, 1)), np.tile(scales * [0.5, 0.5, 0.5], (4, 1)),
                np.tile(opac, 4), np.tile(colors, (4, 1)), np.tile(ids, 4))
    return model.num - first


def _subset(model: DynamicGaussians, keep: np.ndarray) -> None:
    k = torch.as_tensor(keep)
    with torch.no_grad():
        for name in ("means", "quats", "log_scales", "opacity_logits", "color_logits"):
            setattr(model, name, torch.nn.Parameter(getattr(model, name).data[k]))
        model.object_ids = model.object_ids[k]
    model.rebind()


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


@dataclass(frozen=True)
class _Arrays:
    """A read-only numpy copy of a model's Gaussians (`_arrays`), which the priors measure."""

    means: np.ndarray       # [N, 3] float64
    quats: np.ndarray       # [N, 4] float64
    normals: np.ndarray     # [N, 3] each Gaussian's third (thinnest, for discs) axis
    ids: np.ndarray         # [N]
    colors: np.ndarray      # [N, 3]
    scales: np.ndarray      # [N, 3]
    opac: np.ndarray        # [N]


def _arrays(model: DynamicGaussians) -> _Arrays:
    with torch.no_grad():
        return _Arrays(model.means.numpy().astype(np.float64), model.quats.numpy().astype(np.float64),
                       quat_to_rotmat(model.quats).numpy()[:, :, 2], model.object_ids.numpy(),
                       model.colors().numpy(), model.scales().numpy(), model.opacities().numpy())


@dataclass(frozen=True)
class Backdrop:
    """A vertical plane normal . x = offset behind the objects (hills, a wall): `normal` is
    horizontal and points towards the objects, `inliers` index the model's Gaussians on it and
    `distance` is the objects' (median) centre's distance to it."""

    normal: np.ndarray
    offset: float
    inliers: np.ndarray
    distance: float


def find_backdrop(model: DynamicGaussians, dynamic: dict, background: set[int], rng: np.random.Generator,
                  min_inliers: int = 200, min_share: float = 0.6) -> Backdrop | None:
    """The backdrop of a fitted model, if it has one: a vertical plane (`fit_backdrop_plane`) through
    at least `min_inliers` of the setting's (`background` ids) static, opaque Gaussians that face
    sideways, and at least `min_share` of them (sideways Gaussians scattered over rocks or
    dunes fit no plane). Objects, even static ones (seaweed, a house), are never a backdrop."""
    a = _arrays(model)
    means, normals, ids, opac = a.means, a.normals, a.ids, a.opac
    setting = [i for i, d in dynamic.items() if not d and i in background]
    objects = ~np.isin(ids, list(background)) & (opac > 0.5)
    cand = np.flatnonzero(np.isin(ids, setting) & (np.abs(normals[:, 2]) < 0.3) & (opac > 0.5))
    if len(cand) < min_inliers or not objects.any():
        return None
    n, d, inl = fit_backdrop_plane(means[cand], rng)
    if inl.sum() < max(min_inliers, min_share * len(cand)):
        return None
    centre = np.median(means[objects], axis=0)
    if n @ centre < d:
        n, d = -n, -d
    return Backdrop(n, d, cand[inl], float(n @ centre - d))


def _complete_backdrop(model: DynamicGaussians, clip: GeneratedClip, backdrop: Backdrop, rng: np.random.Generator,
                       max_new: int, spread: float = 0.75, window: float = 0.1, seen_colours: bool = False) -> int:
    """Continue the backdrop sideways, along its plane, by `spread` of its seen width on either
    side, and fill the holes in what was seen (behind the objects). Within the seen width the
    top follows the highest point seen within `window` of the seen width; beyond it, the median
    of those tops (a wall keeps its edge, hills their typical height rather than the last
    peak). The bottom is the lowest point seen. Each disc takes the colour of the nearest seen
    backdrop Gaussian (with `seen_colours`, the nearest one the input views show, the frontmost
    where several share a cell: a fit leaves hidden ones of any colour behind a near wall's
    front layer); the cells grow where more than `max_new` would be needed. Discs that an input
    view sees through (`seen_through`) are left out. Returns how many discs were added."""
    a = _arrays(model)
    means, ids, colors, scales, opac = a.means, a.ids, a.colors, a.scales, a.opac
    n, on = backdrop.normal, backdrop.inliers
    e1 = np.cross(n, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.array([0.0, 0.0, 1.0])
    uv = np.c_[means[on] @ e1, means[on] @ e2]
    lo, hi = uv.min(0), uv.max(0)
    lo[0], hi[0] = lo[0] - spread * (hi[0] - lo[0]), hi[0] + spread * (hi[0] - lo[0])
    facing = np.abs(a.normals @ n) > 0.7
    # what covers the backdrop: Gaussians on it that face the same way (not the ground's discs
    # meeting it, whose footprint would cover the backdrop's plane above and below them)
    near = np.flatnonzero((np.abs(means @ n - backdrop.offset) < 3.0 * float(np.median(scales[on].max(1))))
                          & facing & (opac > 0.1))
    ouv = np.c_[means[near] @ e1, means[near] @ e2]
    cell = max(float(np.median(scales[on, :2])) * 3.0, float((hi - lo).max()) / 2048.0)
    for _ in range(12):
        size = np.maximum(np.ceil((hi - lo) / cell).astype(int), 1)
        # a Gaussian covers the backdrop over its narrower in-plane side: a long thin streak
        # (a wrongly stretched Gaussian) does not hide the empty wall around it
        empty = ~_occupancy(ouv, scales[near, :2].min(1), lo, size, cell)
        rows, cols = np.nonzero(empty)
        pu, pv = lo[0] + (cols + 0.5) * cell, lo[1] + (rows + 0.5) * cell
        # the top: per column of cells, the highest point seen within `window` of it (the views
        # show the outermost columns only in part)
        col = np.clip(np.floor((uv[:, 0] - lo[0]) / cell).astype(int), 0, size[0] - 1)
        tops = np.full(size[0], -np.inf)
        np.maximum.at(tops, col, uv[:, 1])
        m = max(1, int(np.ceil(window * np.ptp(uv[:, 0]) / cell)))
        tops = np.where(np.isfinite(tops), sliding_window_view(np.pad(tops, m, constant_values=-np.inf),
                                                                2 * m + 1).max(axis=1), -np.inf)
        seen_cols = np.flatnonzero(np.isfinite(tops))
        top = np.interp(cols, seen_cols, tops[seen_cols])
        beyond = (cols < seen_cols[0]) | (cols > seen_cols[-1])
        top[beyond] = np.median(tops[seen_cols])
        keep = pv <= top
        if keep.sum() <= max_new:
            break
        cell *= 1.5
    rows, cols, pu, pv = rows[keep], cols[keep], pu[keep], pv[keep]
    if len(pu) > max_new:                                    # keep those nearest the seen backdrop
        order = np.argsort(np.abs(pu - np.clip(pu, uv[:, 0].min(), uv[:, 0].max())), kind="stable")[:max_new]
        rows, cols, pu, pv = rows[order], cols[order], pu[order], pv[order]
    seen = on
    if seen_colours:                # the backdrop Gaussians the input views show, the front one of a cell
        seen = on[visible_weights(model, clip, 0)[on] >= 0.5]
        seen = seen if len(seen) else on
        seen = seen[np.argsort(means[seen] @ n, kind="stable")]        # the last in a cell is its source
    suv = np.c_[means[seen] @ e1, means[seen] @ e2]
    src = seen[_nearest_source(suv, lo, size, cell)[rows, cols]]
    jitter = 0.3 * (rng.random((len(pu), 2)) - 0.5) * cell
    pts = (pu + jitter[:, 0])[:, None] * e1 + (pv + jitter[:, 1])[:, None] * e2 + backdrop.offset * n
    hidden = ~seen_through(pts, clip)              # an input view sees past it: no backdrop there
    pts, src = pts[hidden], src[hidden]
    if not len(pts):
        return 0
    label = int(np.bincount(ids[on]).argmax())
    _append_discs(model, pts, n, np.full(len(pts), cell), colors[src], label, rng)
    return len(pts)


def seen_through(points: np.ndarray, clip: GeneratedClip, margin: float = 0.15, frame_stride: int = 4) -> np.ndarray:
    """[n] whether an input view sees through each of `points` [n, 3]: in some frame (every
    `frame_stride`-th) it lies in view, in front of the camera, on a pixel whose depth prior
    shows nothing or lies more than `margin` (relative) beyond it. False everywhere without depth."""
    through = np.zeros(len(points), bool)
    if clip.depth is None or not len(points):
        return through
    for f in range(0, clip.num_frames, max(1, frame_stride)):
        cam = clip.cameras[f]
        uv, z = cam.project(points)
        col, row = np.floor(uv[:, 0]), np.floor(uv[:, 1])
        inside = (z > cam.near) & (col >= 0) & (col < cam.width) & (row >= 0) & (row < cam.height)
        idx = np.flatnonzero(inside)
        seen = clip.depth[f][row[idx].astype(int), col[idx].astype(int)]
        through[idx] |= (seen <= 0) | (seen > z[idx] * (1.0 + margin))
    return through


def _complete_ground(model: DynamicGaussians, clip: GeneratedClip, dynamic: dict, rng: np.random.Generator,
                     max_new: int, background: set[int], backdrop: Backdrop | None = None, levels: int = 7,
                     spread: float = 3.0, backdrop_slack: float = 1.5) -> int:
    """Tile the ground plane around what was seen (module docstring); returns how many discs were
    added. With a backdrop, the ground reaches at most `backdrop_slack` times the backdrop's
    distance from the objects (or as far as it was seen)."""
    a = _arrays(model)
    means, normals, ids, colors, scales, opac = a.means, a.normals, a.ids, a.colors, a.scales, a.opac
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
    objects = ~np.isin(ids, list(background)) & (opac > 0.5)
    centre = np.median(np.c_[means[objects] @ e1, means[objects] @ e2], axis=0) if objects.any() else uv.mean(0)
    seen = float(np.linalg.norm(uv - centre, axis=1).max())
    reach = ground_reach(clip, n, d, e1, e2, centre, seen=seen)
    if backdrop is not None:        # the backdrop bounds the world: the ground ends not far past it
        reach = min(reach, max(seen, backdrop_slack * backdrop.distance))
    lo, hi = uv.min(0), uv.max(0)
    extent = hi - lo
    lo, hi = lo - spread * extent, hi + spread * extent
    static = np.flatnonzero(np.isin(ids, static_ids) & (opac > 0.1))
    ouv = np.c_[means[static] @ e1, means[static] @ e2]
    # the finest cell follows the observed ground's Gaussians; where the rings would need more
    # than `max_new` discs (a densified fit has small ones, and the sparse far ground leaves
    # many gaps) the cells grow, so that the outer rings still reach `spread` extents out
    cell = max(float(np.median(scales[ground, :2])) * 3.0, float((hi - lo).max()) / 2048.0)
    for _ in range(8):
        pts, src, side = _ring_cells(uv, ouv, scales[static, :2].max(1), lo, hi, cell, levels, rng)
        inside = np.linalg.norm(pts - centre, axis=1) <= reach
        pts, src, side = pts[inside], src[inside], side[inside]
        if len(pts) <= max_new:
            break
        cell *= 1.5
    pts = pts[:, :1] * e1 + pts[:, 1:] * e2 + d * n
    src = ground[src]
    if len(pts) > max_new:                                   # keep the inner rings, drop the farthest
        order = np.argsort(side, kind="stable")[:max_new]
        pts, src, side = pts[order], src[order], side[order]
    k = len(pts)
    if k:
        _append_discs(model, pts, n, side, colors[src], label, rng)
    return k


def _append_discs(model: DynamicGaussians, pts: np.ndarray, normal: np.ndarray, side: np.ndarray,
                  colors: np.ndarray, label: int, rng: np.random.Generator) -> None:
    """Append flat opaque discs at `pts` [k, 3] facing `normal`, `side` [k] wide, with slightly
    jittered `colors` [k, 3] and instance `label`."""
    k = len(pts)
    quats = np.tile(_quat_from_normal(normal), (k, 1))
    sc = np.c_[side * 0.8, side * 0.8, side * 0.15]
    jitter = 1.0 + 0.04 * rng.standard_normal((k, 1))
    _append(model, pts, quats, sc, np.full(k, 0.95), np.clip(colors * jitter, 0, 1), np.full(k, label))


def ground_reach(clip: GeneratedClip, n: np.ndarray, d: float, e1: np.ndarray, e2: np.ndarray, centre: np.ndarray,
                 seen: float, slack: float = 1.5, frame_stride: int = 8, min_share: float = 0.005,
                 quantile: float = 0.5) -> float:
    """How far from `centre` (plane coordinates on axes e1, e2) the ground n . x = d may reach,
    given that the input views show it up to `seen` from there.

    Free-space evidence: an input pixel that shows nothing (no depth) although its ray meets the
    plane in front of the camera proves the ground absent at that meeting point; the nearest such
    point (a low `quantile`, in percent, against stray pixels) bounds the ground. When that bound
    lies within `slack` times `seen`, the views show where the ground ends (a floor disc against
    empty water, a table edge): it ends at `seen`, on every side. Otherwise the free space lies far
    beyond (rays grazing the horizon past hills or a wall) and only bounds it there; with no such
    pixels (at least `min_share` of those sampled) nothing bounds it (inf)."""
    if clip.depth is None:
        return float("inf")
    hits, sampled = [], 0
    for f in range(0, clip.num_frames, max(1, frame_stride)):
        cam = clip.cameras[f]
        empty = clip.depth[f] <= 0
        sampled += empty.size
        if not empty.any():
            continue
        origin = cam.position
        ray = cam.unproject(cam.pixel_centres()[empty], np.ones(int(empty.sum()))) - origin
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (d - origin @ n) / (ray @ n)
        ok = np.isfinite(t) & (t > 0)
        if ok.any():
            p = origin + t[ok, None] * ray[ok]
            hits.append(np.c_[p @ e1, p @ e2])
    if not hits or sum(len(h) for h in hits) < min_share * sampled:
        return float("inf")
    free = float(np.percentile(np.linalg.norm(np.concatenate(hits) - centre, axis=1), quantile))
    return seen if free <= slack * seen else free


def _occupancy(ouv: np.ndarray, oscale: np.ndarray, lo: np.ndarray, size: np.ndarray, cell: float) -> np.ndarray:
    """[rows, cols] cells of the plane grid (`size` cells from `lo`) that observed Gaussians at
    plane coordinates `ouv` [m, 2] cover over their footprint (largest scale `oscale` [m])."""
    occupied = np.zeros(tuple(size[::-1]), bool)
    ocells = np.floor((ouv - lo) / cell).astype(int)
    inside = np.all((ocells >= 0) & (ocells < size), axis=1)
    ocells, oscale = ocells[inside], oscale[inside]
    reach = np.minimum(np.floor(oscale / cell).astype(int), 16)
    for r in np.unique(reach):
        sel = reach == r
        for dy in range(-r, r + 1):
            for dx in range(-r, r + 1):
                occupied[np.clip(ocells[sel, 1] + dy, 0, size[1] - 1), np.clip(ocells[sel, 0] + dx, 0, size[0] - 1)] = True
    return occupied


def _nearest_source(uv: np.ndarray, lo: np.ndarray, size: np.ndarray, cell: float) -> np.ndarray:
    """[rows, cols] index into `uv` [n, 2] of the source Gaussian nearest each cell of the plane
    grid (whose colour a new disc there takes)."""
    grid = np.full(tuple(size[::-1]), -1, np.int64)
    cells = np.clip(np.floor((uv - lo) / cell).astype(int), 0, size - 1)
    grid[cells[:, 1], cells[:, 0]] = np.arange(len(uv))
    no_source = (grid < 0).astype(np.uint8)
    _, labels = cv2.distanceTransformWithLabels(no_source, cv2.DIST_L2, 5, labelType=cv2.DIST_LABEL_PIXEL)
    zero_rows, zero_cols = np.nonzero(no_source == 0)
    label_to_source = np.full(labels.max() + 1, -1, np.int64)
    label_to_source[labels[zero_rows, zero_cols]] = grid[zero_rows, zero_cols]
    return label_to_source[labels]


def _ring_cells(uv: np.ndarray, ouv: np.ndarray, oscale: np.ndarray, lo: np.ndarray, hi: np.ndarray, cell: float,
                levels: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Plane coordinates [k, 2], source ground index [k] and side [k] of the discs that tile the
    empty plane in `[lo, hi]` around the observed ground `uv` in rings of growing cells (`cell`
    wide next to what was seen); `ouv`/`oscale`: every observed static Gaussian, which covers
    the ground under it over its footprint."""
    size = np.ceil((hi - lo) / cell).astype(int)
    empty = (~_occupancy(ouv, oscale, lo, size, cell)).astype(np.uint8)
    if empty.sum() == 0:
        return np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0)
    dist = cv2.distanceTransform(empty, cv2.DIST_L2, 5)
    nearest = _nearest_source(uv, lo, size, cell)
    # level L (cells 2^L fine cells wide) fills the empty cells whose distance to the observed
    # ground (in fine cells) is in [2^(L+1) - 2, 2^(L+2) - 2)
    pts_all, src_all, size_all = [], [], []
    for level in range(levels):
        step = 2 ** level
        lo_d = 2 ** (level + 1) - 2
        hi_d = np.inf if level == levels - 1 else 2 ** (level + 2) - 2
        rows, cols = np.mgrid[0:(size[1] + step - 1) // step, 0:(size[0] + step - 1) // step]
        cr = np.minimum(rows * step + step // 2, size[1] - 1).ravel()
        cc = np.minimum(cols * step + step // 2, size[0] - 1).ravel()
        d_c = dist[cr, cc]
        take = (empty[cr, cc] > 0) & (d_c >= lo_d) & (d_c < hi_d)
        src = nearest[cr[take], cc[take]]
        ok = src >= 0
        r, c = rows.ravel()[take][ok], cols.ravel()[take][ok]
        side = cell * step
        pu = lo[0] + (c + 0.5 + 0.3 * (rng.random(len(c)) - 0.5)) * side
        pv = lo[1] + (r + 0.5 + 0.3 * (rng.random(len(r)) - 0.5)) * side
        pts_all.append(np.c_[pu, pv])
        src_all.append(src[ok])
        size_all.append(np.full(len(c), side))
    return np.concatenate(pts_all), np.concatenate(src_all), np.concatenate(size_all)


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
    a = _arrays(model)
    means, quats, ids, colors, scales, opac = a.means, a.quats, a.ids, a.colors, a.scales, a.opac
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
             reference: dict | None = None, max_ground: int = 12000, max_backdrop: int = 4000,
             seen_colours: bool = False) -> dict[str, int]:
    """Add ground, backdrop and far-side Gaussians to a fitted model (in place); returns how many
    of each. `max_ground` and `max_backdrop` bound the discs of the ground's rings and of the
    backdrop (splitting those too close to a camera can add a few); `seen_colours`: the backdrop's
    new discs take the colours of the backdrop Gaussians the input views show (`_complete_backdrop`).

    Ground cells also fill the gaps that the input views see between observed Gaussians (far
    ground seen at a grazing angle is sparse in 3D), so a short fit should follow to blend them
    in; far-side Gaussians that an input view shows (a wrong silhouette) are dropped."""
    from ..language.vocabulary import word_to_setting

    rng = np.random.default_rng([seed, 11])
    background = {i for i, name in clip.labels.items() if word_to_setting(name.lower())}
    backdrop = find_backdrop(model, dynamic, background, np.random.default_rng([seed, 12]))
    first = model.num
    _complete_ground(model, clip, dynamic, rng, max_ground, background, backdrop)
    ground = _split_near(model, clip, first)
    wall = 0
    if backdrop is not None:
        first = model.num
        _complete_backdrop(model, clip, backdrop, rng, max_backdrop, seen_colours=seen_colours)
        wall = _split_near(model, clip, first)
    first = model.num
    _complete_symmetry(model, clip, dynamic, reference, background)
    sym = _drop_seen(model, clip, first)
    return {"ground": ground, "backdrop": wall, "symmetry": sym}
