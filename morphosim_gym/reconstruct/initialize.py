"""Initialise the 4D model from a clip: static background and dynamic instances, scaffold nodes.

* every instance of the masks is lifted with the depth prior; an instance whose lifted
  tracks move rigidly by more than `motion_threshold` (fraction of the scene depth), and
  whose tracks a static hypothesis misplaces by more than `static_pixels`, is dynamic, the
  others are static;
* pixels with a depth but no instance (translucent matter) are lifted into the static
  setting instance (`unlabelled_host`);
* static instances are fused from several frames into one point set (a voxel per pixel
  footprint), dynamic ones are brought back to their reference frame (where their mask
  is largest) with the per-frame rigid poses estimated from tracks (Kabsch, robust), or from
  the mask's own motion, turned by the spin its pixels show (`spin`: a rolling ball);
* each dynamic instance gets a scaffold of nodes (k-means over its canonical points),
  all starting with the instance's rigid motion; Gaussians are flat discs facing the
  camera they were seen from, one per pixel footprint, with the pixel's colour.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..priors import setting_label
from ..scene import GeneratedClip
from ..scene.rotations import normal_quats
from .lifting import (PointSet, backproject, instance_motion, instance_tracks, interior_mask, mask_motion,
                      reprojection_residual, static_residual, track_noise, voxel_downsample)
from .model import DynamicGaussians
from .pose_graph import graph_poses
from .spin import WORLD_UP, spin_angles, spin_poses

__all__ = ["InitConfig", "InitResult", "initialize", "unlabelled_host"]


@dataclass(frozen=True)
class InitConfig:
    """Initialisation settings.

    Attributes:
        frame_stride: lift every n-th frame (plus each dynamic instance's reference frame).
        motion_threshold: an instance is dynamic if it moves more than this fraction of the
            median scene depth over the clip ...
        static_pixels: ... and "it does not move" misplaces its tracks by more than this many
            pixels over most frames (`static_residual`, a robust percentile over all frames; with
            a moving camera, a depth prior a few percent off makes static things seem to move in
            3D, not in the image) ...
        noise_factor: ... and by more than this many times the tracks' own noise level
            (`track_noise`, from their jitter), so 1-2 px of track noise never makes a static
            road "dynamic" (a static object's residual is about 1.2-2 times the noise: the median
            of Rayleigh-distributed misplacements). An instance with too few tracks to decide
            (a small object whose tracks noise pushed off its mask) is judged by how far its
            lifted mask centroid moves against the static hypothesis instead (`mask_motion`).
        mask_pixels: an instance whose tracks do not show it moving is still dynamic when its
            mask centroid misplaces by more than this many pixels (and the tracks' limit) under
            "it does not move": a small object whose tracks the flow drags along with the
            background, or that noise pushed off its mask (static objects stay under ~3 px,
            mask errors of +-2 px move a centroid little).
        coverage_margin: a moving instance starts from its mask's translation instead of its
            tracks' rigid poses when that lands this much more of its reference points on its
            masks (`_coverage`, mean over the frames where the mask is seen).
        rotation_evidence: a moving instance keeps its tracks' rotations only when they explain
            the tracks in the image this many times better than moving its centre along the same
            path without turning (`lifting.reprojection_residual`); else it starts unturned. The
            rotations of a rigid fit to tracks lifted by depth (Kabsch) follow the depth prior:
            depth off by a smooth +-10% field turns a sliding car by 37 degrees (median over the
            frames), a bus by 43, while the image says they do not turn (a translation explains
            the tracks within 1.4x as well); a rolling ball's turn explains them 9-25x better.
        pose_graph: a moving instance's rotations from its tracks are averaged over the rigid
            motions between many pairs of frames (`pose_graph.graph_poses`), not taken from the
            reference frame's tracks alone (1 px of track noise turned the example ball's from the
            reference fit 8.6 degrees off its true turns, median over the frames; averaged 5.2).
        spin: a moving instance whose own pixels show it turning steadily about the line of
            sight (`spin.spin_angles`: a rolling ball, whose small textured disc the flow's
            tracks see mostly translating) takes that turn as its rotation, rolling about the
            horizontal part of the line of sight (`spin.spin_poses` with `WORLD_UP`), pivoting on its
            centre along the chosen path, when: ECC measured at least `spin_measured` of the frame
            pairs where its mask is seen, with a median correlation >= `spin_correlation`; the
            turns add up to >= `spin_degrees`; and they are consistent (|mean| over its standard
            error >= `spin_consistency`: a sheep's walking legs give turns of either sign); the
            rotation explains the pixels: the median over the pairs of ECC's residual (1 - its
            correlation) without rotation over that with it is >= `spin_gain` (a rolling ball:
            ~2.5; a sliding mug whose mask holds the table seen through its handle: ~0.2, its
            rotation only a worse fit found by the search); unless
            the poses already turn it by at least `spin_kept` of that (median over the frames
            turned by more than 10 degrees: exact tracks see the turn, about its true axis).
        points_per_node: scaffold density (one node per this many canonical points).
        max_nodes: at most this many nodes per dynamic instance.
        slots: nodes each Gaussian is skinned to.
        opacity: initial opacity.
        flatness: normal-axis scale as a fraction of the footprint.
    """

    frame_stride: int = 6
    motion_threshold: float = 0.01
    static_pixels: float = 2.0
    noise_factor: float = 3.0
    mask_pixels: float = 5.0
    coverage_margin: float = 0.1
    rotation_evidence: float = 2.0
    pose_graph: bool = True
    spin: bool = True
    spin_measured: float = 0.75
    spin_correlation: float = 0.95
    spin_degrees: float = 30.0
    spin_consistency: float = 10.0
    spin_kept: float = 0.5
    spin_gain: float = 1.5
    points_per_node: int = 600
    max_nodes: int = 6
    slots: int = 4
    opacity: float = 0.9
    flatness: float = 0.25


@dataclass
class InitResult:
    """The initial model and what initialisation learnt about the clip."""

    model: DynamicGaussians
    dynamic: dict[int, bool]
    reference: dict[int, int]
    instance_poses: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)


def _kmeans(points: np.ndarray, k: int, rng: np.random.Generator, iters: int = 20) -> np.ndarray:
    if k <= 1 or len(points) <= k:
        return points.mean(axis=0, keepdims=True) if k <= 1 else points[:k].copy()
    centres = points[rng.choice(len(points), size=k, replace=False)]
    for _ in range(iters):
        d = ((points[:, None] - centres[None]) ** 2).sum(-1)
        lab = d.argmin(1)
        for j in range(k):
            sel = lab == j
            if sel.any():
                centres[j] = points[sel].mean(0)
    return centres


def _covered(clip: GeneratedClip, frame: int, points: np.ndarray, tolerance: float = 0.05) -> np.ndarray:
    """[H, W] pixels of a frame onto which some of `points` project at the depth prior's depth
    (within `tolerance` of it): already explained by those points."""
    H, W = clip.height, clip.width
    out = np.zeros((H, W), bool)
    if len(points) == 0:
        return out
    uv, z = clip.cameras[frame].project(points)
    with np.errstate(invalid="ignore"):
        c, r = np.floor(uv[:, 0]), np.floor(uv[:, 1])
        ok = (z > clip.cameras[frame].near) & (c >= 0) & (c < W) & (r >= 0) & (r < H)
    c, r, z = c[ok].astype(int), r[ok].astype(int), z[ok]
    prior = clip.depth[frame, r, c]
    hit = np.abs(prior - z) <= tolerance * prior
    out[r[hit], c[hit]] = True
    return out


def _is_setting(label: str) -> bool:
    """True for the label of a setting ("road", "table", "grass"...): the ground never moves,
    whatever estimated tracks on it seem to say (drift, a moving camera's parallax)."""
    from ..language.vocabulary import noun_to_category, word_to_setting

    text = label.lower()
    return bool(word_to_setting(text)) and not noun_to_category(text)


def unlabelled_host(clip: GeneratedClip, static_ids: list[int]) -> int | None:
    """The static instance that pixels with a depth but no instance are lifted into (the
    setting, e.g. particles in the water), or None to leave them out: the static instance named
    by a setting word, else the static instance with the largest mask."""
    if not static_ids or not np.any((clip.masks < 0) & (clip.depth > 0)):
        return None
    from ..language.vocabulary import word_to_setting

    for i in static_ids:
        if word_to_setting(clip.labels.get(i, "").lower()):
            return i
    return max(static_ids, key=lambda i: int((clip.masks == i).sum()))


def _mask_residual(clip: GeneratedClip, instance: int, reference: int, trans: np.ndarray, seen: np.ndarray,
                   scales: np.ndarray = np.linspace(0.85, 1.15, 31)) -> float:
    """Pixels by which "this instance does not move" misplaces its mask centroid (75th
    percentile over the frames where the mask is seen), minimised over the depth at which the
    reference centroid is lifted (times `scales`: a centroid lifted a few percent off its depth, a
    mask grown over the ground behind it, seems to slide as the camera moves, as in
    `lifting.static_residual`); 0 with fewer than 2 such frames."""
    if seen.sum() < 2:
        return 0.0
    cen = backproject(clip, reference, select=clip.masks[reference] == instance).points
    if not len(cen):
        return 0.0
    c = cen.mean(0)
    eye = clip.cameras[reference].position
    frames = np.flatnonzero(seen)
    moved = [clip.cameras[t].project((c + trans[t])[None])[0][0] for t in frames]
    best = np.inf
    for s in scales:
        still = eye + s * (c - eye)
        err = [float(np.linalg.norm(m - clip.cameras[t].project(still[None])[0][0])) for t, m in zip(frames, moved)]
        best = min(best, float(np.percentile(err, 75.0)))
    return best


def _coverage(clip: GeneratedClip, instance: int, points: np.ndarray, rots: np.ndarray, trans: np.ndarray,
              seen: np.ndarray) -> float:
    """Mean share, over the frames where the instance's mask is `seen`, of its reference points
    [n, 3] that the poses (rotations [T, 3, 3], translations [T, 3]) land inside its mask."""
    shares = []
    for t in np.flatnonzero(seen):
        if not len(points):
            break
        uv, z = clip.cameras[t].project(points @ rots[t].T + trans[t])
        c, r = np.floor(uv[:, 0]).astype(int), np.floor(uv[:, 1]).astype(int)
        ok = (z > 0) & (c >= 0) & (c < clip.width) & (r >= 0) & (r < clip.height)
        hit = np.zeros(len(points), bool)
        hit[ok] = clip.masks[t][r[ok], c[ok]] == instance
        shares.append(hit.mean())
    return float(np.mean(shares)) if shares else 0.0


def _spun(clip: GeneratedClip, inst: int, ref: int, cfg: InitConfig, centre: np.ndarray,
          poses: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The poses with the instance's spin about the line of sight as their rotation (its centre
    kept on the poses' path), when its pixels show a steady turn (`InitConfig.spin`); else as given."""
    if not cfg.spin or clip.num_frames < 3:
        return poses
    angles, ok, corr, still = spin_angles(clip, inst)
    present = (clip.masks == inst).reshape(clip.num_frames, -1).any(1)
    pairs = int((present[:-1] & present[1:]).sum())
    if ok.sum() < max(2, cfg.spin_measured * pairs) or np.median(corr[ok]) < cfg.spin_correlation:
        return poses
    if np.median((1.0 - still[ok]) / np.maximum(1.0 - corr[ok], 1e-9)) < cfg.spin_gain:
        return poses
    a = angles[ok]
    spread = a.std() / np.sqrt(len(a))
    if abs(a.sum()) < np.radians(cfg.spin_degrees) or abs(a.mean()) < cfg.spin_consistency * spread:
        return poses
    rots, trans = poses
    path = np.einsum("tij,j->ti", rots, centre) + trans - centre      # where the centre goes
    spun = spin_poses(clip, ref, centre, path, angles, up=WORLD_UP)
    turn, own = _turn_angles(spun[0]), _turn_angles(rots)
    far = turn > np.radians(10.0)
    if far.any() and np.median(own[far] / turn[far]) >= cfg.spin_kept:
        return poses            # the tracks saw the turn: their rotations keep its true axis
    return spun


def _evident_turn(clip: GeneratedClip, inst: int, ref: int, cfg: InitConfig, centre: np.ndarray,
                  poses: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The tracks' rigid poses, or the same path of the centre without turning when the turn
    does not explain the tracks `InitConfig.rotation_evidence` times better in the image."""
    rots, trans = poses
    path = np.einsum("tij,j->ti", rots, centre) + trans - centre      # where the centre goes
    eye = np.tile(np.eye(3), (clip.num_frames, 1, 1))
    turned = reprojection_residual(clip, inst, ref, rots, trans)
    unturned = reprojection_residual(clip, inst, ref, eye, path)
    # (a residual under 0.05 px, exact tracks, counts as 0.05: no ratio of two rounding errors)
    if not (np.isfinite(turned) and np.isfinite(unturned)) or unturned >= cfg.rotation_evidence * max(turned, 0.05):
        return poses                     # nothing to judge by, or the turn is evident
    return eye, path


def _turn_angles(rots: np.ndarray) -> np.ndarray:
    """[T] angle (radians) of each rotation [T, 3, 3]."""
    return np.arccos(np.clip((np.trace(rots, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0))


def _decide_motion(clip: GeneratedClip, inst: int, ref: int, cfg: InitConfig, scene_depth: float,
                   ) -> tuple[bool, tuple[np.ndarray, np.ndarray]]:
    """Whether an instance is dynamic, and its per-frame rigid poses (rotations [T, 3, 3],
    translations [T, 3]) relative to its reference frame (`_moving`, then `_spun`)."""
    dynamic, poses = _moving(clip, inst, ref, cfg, scene_depth)
    if not dynamic:
        return dynamic, poses
    pts = backproject(clip, ref, select=clip.masks[ref] == inst)
    return True, _spun(clip, inst, ref, cfg, pts.points.mean(0) if len(pts) else np.zeros(3), poses)


def _moving(clip: GeneratedClip, inst: int, ref: int, cfg: InitConfig, scene_depth: float,
            ) -> tuple[bool, tuple[np.ndarray, np.ndarray]]:
    """Whether an instance is dynamic, and its per-frame rigid poses (rotations [T, 3, 3],
    translations [T, 3]) relative to its reference frame (see `InitConfig`)."""
    label = clip.labels.get(inst, "")
    if _is_setting(label) or (clip.info.get("setting") and label == setting_label(clip)):
        return False, (np.tile(np.eye(3), (clip.num_frames, 1, 1)), np.zeros((clip.num_frames, 3)))
    rots, trans, good = instance_motion(clip, inst, ref)
    sel = clip.masks[ref] == inst
    pts = backproject(clip, ref, select=sel)
    centre = pts.points.mean(0) if len(pts) else np.zeros(3)
    own = instance_tracks(clip, inst) if clip.tracks is not None else np.zeros(0, int)
    limit = max(cfg.static_pixels, cfg.noise_factor * track_noise(clip, own)) if clip.tracks is not None \
        else cfg.static_pixels
    if good.sum() >= 2:
        travel = np.linalg.norm(np.einsum("tij,j->ti", rots, centre) + trans - centre, axis=1).max()
        if travel > cfg.motion_threshold * scene_depth and static_residual(clip, inst, ref) > limit:
            # the tracks' rigid poses, unless the mask's own translation lands the object on its
            # masks clearly better (tracks lifted onto a flat depth, or dragged by the flow, give a
            # rolling ball a wrong rotation and a fish a lagging path)
            mtrans, seen = mask_motion(clip, inst, ref)
            eye = np.tile(np.eye(3), (clip.num_frames, 1, 1))
            if cfg.pose_graph:
                rots, trans = graph_poses(clip, inst, ref, rots, trans, centre)
            rots, trans = _evident_turn(clip, inst, ref, cfg, centre, (rots, trans))
            if _coverage(clip, inst, pts.points, eye, mtrans, seen) > \
                    _coverage(clip, inst, pts.points, rots, trans, seen) + cfg.coverage_margin:
                return True, (eye, mtrans)
            return True, (rots, trans)
    # the tracks do not show it moving (too few of them, or dragged along with the background
    # by the flow): the mask's own motion decides (translation only)
    mtrans, seen = mask_motion(clip, inst, ref)
    travel = float(np.linalg.norm(mtrans, axis=1).max())
    moving = travel > cfg.motion_threshold * scene_depth and \
        _mask_residual(clip, inst, ref, mtrans, seen) > max(cfg.mask_pixels, limit)
    if not moving:
        return False, (rots, trans)
    return True, (np.tile(np.eye(3), (clip.num_frames, 1, 1)), mtrans)

def initialize(clip: GeneratedClip, config: InitConfig | None = None, seed: int = 0) -> InitResult:
    """Build the initial `DynamicGaussians` of a clip (never reads `clip.ground_truth`)."""
    cfg = config or InitConfig()
    if clip.depth is None or clip.masks is None:
        missing = [n for n in ("depth", "masks") if getattr(clip, n) is None]
        raise ValueError(f"Expected a clip with depth and instance-mask priors for reconstruction, missing {missing}")
    rng = np.random.default_rng(seed)
    T = clip.num_frames
    ids = sorted(int(i) for i in np.unique(clip.masks) if i >= 0)
    valid_depth = clip.depth[clip.depth > 0]
    if valid_depth.size == 0:
        raise ValueError("Expected some pixels with a positive depth prior, found none")
    scene_depth = float(np.median(valid_depth))
    frames = sorted(set(range(0, T, max(1, cfg.frame_stride))) | {T - 1})

    dynamic, reference, poses = {}, {}, {}
    for inst in ids:
        area = (clip.masks == inst).reshape(T, -1).sum(1)
        ref = int(np.argmax(area))
        dynamic[inst], poses[inst] = _decide_motion(clip, inst, ref, cfg, scene_depth)
        reference[inst] = ref

    static_sets, dyn_sets = [], {}
    host = unlabelled_host(clip, [i for i in ids if not dynamic[i]])
    static_ids = [i for i in ids if not dynamic[i]]
    for t in frames:
        select = interior_mask(clip.masks[t], clip.depth[t])
        if static_sets:
            # a moving camera sees the same static surfaces again from elsewhere: lift only the
            # pixels that the points lifted so far do not already cover in this frame
            select &= ~_covered(clip, t, PointSet.concat(static_sets).points)
        ps = backproject(clip, t, select=select)
        if host is not None:
            ps.ids = np.where(ps.ids < 0, host, ps.ids)
        static_sets.append(ps.subset(np.isin(ps.ids, static_ids)))
    for inst in ids:
        if not dynamic[inst]:
            continue
        rots, trans = poses[inst]
        parts = []
        for t in sorted(set(frames) | {reference[inst]}):
            ps = backproject(clip, t)
            ps = ps.subset(ps.ids == inst)
            if not len(ps):
                continue
            # frame t world -> reference frame (canonical): x_ref = R^T (x - t)
            ps.points = (ps.points - trans[t]) @ rots[t]
            ps.normals = ps.normals @ rots[t]
            parts.append(ps)
        dyn_sets[inst] = PointSet.concat(parts)

    static = PointSet.concat(static_sets)
    if len(static):
        static = voxel_downsample(static, float(np.median(static.footprint)) * 1.0)
    all_sets = [static]
    node_centres, node_objects, node_rot, node_trans = [], [], [], []
    for inst, ps in dyn_sets.items():
        if not len(ps):
            continue
        ps = voxel_downsample(ps, float(np.median(ps.footprint)) * 1.0)
        all_sets.append(ps)
        k = int(np.clip(round(len(ps) / cfg.points_per_node), 1, cfg.max_nodes))
        centres = _kmeans(ps.points.copy(), k, rng)
        rots, trans = poses[inst]
        for c in centres:
            node_centres.append(c)
            node_objects.append(inst)
            node_rot.append(rots)
            node_trans.append(trans)
    pts = PointSet.concat(all_sets)
    if len(pts) == 0:
        raise ValueError("Expected pixels to lift into Gaussians, found none (empty masks or depth)")
    fp = np.maximum(pts.footprint, 1e-5)
    scales = np.c_[fp, fp, fp * cfg.flatness] * 0.9
    quats = normal_quats(pts.normals, rng)
    K = len(node_centres)
    rot_arr = np.stack(node_rot, axis=1) if K else np.zeros((T, 0, 3, 3))
    trans_arr = np.stack(node_trans, axis=1) if K else np.zeros((T, 0, 3))
    model = DynamicGaussians(pts.points, quats, scales, np.full(len(pts), cfg.opacity), np.clip(pts.colors, 0.0, 1.0),
                             pts.ids, np.asarray(node_centres).reshape(-1, 3), np.asarray(node_objects, dtype=int),
                             rot_arr, trans_arr, slots=cfg.slots)
    return InitResult(model, dynamic, reference, poses)
