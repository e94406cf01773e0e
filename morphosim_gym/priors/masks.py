"""Instance masks from the pixels: what moves (against a background model or the camera-induced
flow), cleaned into regions and labelled with the plan's moving objects.

- still camera: a per-pixel temporal median of the frames, taken over the frames where the pixel
  lies outside every planned box (so a slow, large object does not leak into its own background),
  and a pixel is foreground where it differs from that median by more than a colour threshold
  relative to the clip's noise (median absolute deviation);
- moving camera: DIS flow to the next frame against the flow the camera motion alone induces
  on the ground plane; a pixel is foreground where they disagree by more than `flow_pixels`;
- regions: morphological close and open, holes filled, connected components of a minimum area;
- labels: each component goes to the planned object whose box (grown by `box_margin`) covers
  most of it; a component no box covers is background. Without a plan, every component is one
  "object". The rest of the pixels below the horizon are the setting; above it, -1 (sky).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np

from ..scene.camera import Camera
from .depth import ground_plane_depth
from .protocol import BoxTrack, PlanTarget

__all__ = ["box_contrast", "box_masks", "label_regions", "motion_foreground", "plan_targets", "planned_boxes", "static_plan_labels",
           "static_regions", "still_camera"]


def still_camera(cameras: Sequence[Camera]) -> bool:
    """True when every frame's camera is the same pose and intrinsics."""
    a = cameras[0]
    return all(np.allclose(c.world_to_camera, a.world_to_camera, atol=1e-6) and np.allclose(c.K, a.K)
               for c in cameras[1:])


def plan_targets(info: dict[str, Any], num_frames: int, width: int, height: int) -> list[PlanTarget]:
    """The planned moving objects of a clip's info: procedural `trajectories` (pixel boxes) or
    diffusion `targets` (normalised boxes). Boxes of the wrong length are ignored."""
    out = []
    size = np.array([width, height, width, height], np.float64)
    for name, tr in (info.get("trajectories") or {}).items():
        b = np.asarray(tr.get("boxes", []), np.float64)
        if b.shape == (num_frames, 4) and np.all(np.isfinite(b)):
            out.append(PlanTarget(str(name), b / size))
    for tg in info.get("targets") or []:
        b = np.asarray(tg.get("boxes", []), np.float64)
        if b.shape == (num_frames, 4) and np.all(np.isfinite(b)):
            out.append(PlanTarget(str(tg.get("label") or " ".join(tg.get("words", []))), b))
    return out


def box_masks(targets: Sequence[BoxTrack], t: int, h: int, w: int, margin: float) -> list[np.ndarray]:
    """[H, W] bool per target: inside its frame-`t` box grown by `margin` of its size on each side."""
    out = []
    for tg in targets:
        x0, y0, x1, y1 = np.asarray(tg.boxes[t], np.float64)
        mx, my = margin * (x1 - x0), margin * (y1 - y0)
        m = np.zeros((h, w), bool)
        r0, r1 = int(np.floor((y0 - my) * h)), int(np.ceil((y1 + my) * h))
        c0, c1 = int(np.floor((x0 - mx) * w)), int(np.ceil((x1 + mx) * w))
        m[max(r0, 0):max(r1, 0), max(c0, 0):max(c1, 0)] = True
        out.append(m)
    return out


def planned_boxes(targets: Sequence[BoxTrack], t: int, h: int, w: int, margin: float) -> np.ndarray:
    """[t, H, W] bool: inside any planned box (grown by `margin`) in each of the first t frames."""
    return np.stack([np.any(box_masks(targets, i, h, w, margin), axis=0) if targets else np.zeros((h, w), bool)
                     for i in range(t)])


def _background_difference(frames: np.ndarray, boxes: np.ndarray | None) -> np.ndarray:
    """[T, H, W] colour distance of each frame to the temporal-median background."""
    f = frames.astype(np.float32)
    if boxes is not None and boxes.any():
        stack = np.where(boxes[..., None], np.nan, f)
        with warnings.catch_warnings():          # pixels inside a box in every frame: filled below
            warnings.simplefilter("ignore", RuntimeWarning)
            bg = np.nanmedian(stack, axis=0)
        bg = np.where(np.isnan(bg), np.median(f, axis=0), bg)
    else:
        bg = np.median(f, axis=0)
    return np.abs(f - bg[None]).max(axis=-1)


def _flow_residual(frames: np.ndarray, cameras: Sequence[Camera], ground_height: float) -> np.ndarray:
    """[T, H, W] distance between the optical flow to a neighbouring frame and the flow the camera
    motion induces on the ground plane (0 where the ground is not seen)."""
    t, h, w = frames.shape[:3]
    gray = [cv2.cvtColor(np.ascontiguousarray(fr), cv2.COLOR_RGB2GRAY) for fr in frames]
    dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    out = np.zeros((t, h, w), np.float32)
    for k in range(t):
        n = k + 1 if k + 1 < t else k - 1
        flow = dis.calc(gray[k], gray[n], None)
        depth = ground_plane_depth(cameras[k], ground_height)
        uv = cameras[k].pixel_centres().reshape(-1, 2)
        world = cameras[k].unproject(uv, depth.reshape(-1).astype(np.float64))
        proj, _ = cameras[n].project(world)
        induced = (proj - uv).reshape(h, w, 2)
        res = np.linalg.norm(flow - induced, axis=-1)
        out[k] = np.where(depth > 0, res, 0.0)
    return out


def _clean(fg: np.ndarray, min_area: int) -> np.ndarray:
    """Close, open and hole-fill a [H, W] bool mask; drop components under `min_area` pixels."""
    k = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    m = cv2.morphologyEx(fg.astype(np.uint8), cv2.MORPH_CLOSE, k, iterations=2)
    m = cv2.morphologyEx(m, cv2.MORPH_OPEN, k)
    flood = np.pad(m, 1).copy()
    cv2.floodFill(flood, None, (0, 0), 1)
    m = m | (1 - flood[1:-1, 1:-1])        # pixels the outside cannot reach are holes
    n, lab, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    keep = np.zeros(n, bool)
    keep[1:] = stats[1:, cv2.CC_STAT_AREA] >= min_area
    return keep[lab]


def motion_foreground(frames: np.ndarray, cameras: Sequence[Camera] | None = None,
                      targets: Sequence[BoxTrack] = (), ground_height: float = 0.0, box_margin: float = 0.25,
                      colour_sigmas: float = 4.0, min_colour: float = 10.0, flow_pixels: float = 1.0,
                      min_area_frac: float = 0.002) -> np.ndarray:
    """[T, H, W] bool: the pixels of things that move on their own (see the module docstring).
    All False for a single frame (nothing can be seen to move)."""
    f = np.asarray(frames)
    t, h, w = f.shape[:3]
    if t < 2:
        return np.zeros((t, h, w), bool)
    if cameras is None or still_camera(cameras):
        boxes = planned_boxes(targets, t, h, w, box_margin)
        diff = _background_difference(f, boxes)
        noise = float(np.median(np.abs(diff - np.median(diff)))) * 1.4826
        fg = diff > max(min_colour, colour_sigmas * noise)
    else:
        fg = _flow_residual(f, cameras, ground_height) > flow_pixels
    min_area = max(4, int(min_area_frac * h * w))
    return np.stack([_clean(fg[i], min_area) for i in range(t)])


def label_regions(foreground: np.ndarray, targets: Sequence[BoxTrack], box_margin: float = 0.25,
                  min_cover: float = 0.3, frames: np.ndarray | None = None,
                  min_fill: float = 0.3) -> tuple[np.ndarray, dict[int, str]]:
    """Foreground [T, H, W] -> ([T, H, W] int32 ids 1.. of the planned objects (0 elsewhere), labels).
    A connected region is shared out among the targets whose grown boxes cover at least
    `min_cover` of it (`_split_region`: by box, the nearest in front where boxes overlap); a target whose region fills less than `min_fill` of
    its box in a frame is completed by `box_contrast` on `frames` (when given). Without targets
    every region is id 1 "object"."""
    t, h, w = foreground.shape
    ids = np.zeros((t, h, w), np.int32)
    if not targets:
        ids[foreground] = 1
        return ids, ({1: "object"} if foreground.any() else {})
    labels = {k + 1: tg.label for k, tg in enumerate(targets)}
    bottoms = np.array([np.asarray(tg.boxes, np.float64)[:, 3] for tg in targets])     # [K, T]
    for i in range(t):
        n, lab = cv2.connectedComponents(foreground[i].astype(np.uint8), connectivity=8)
        boxes = box_masks(targets, i, h, w, box_margin)
        tight = box_masks(targets, i, h, w, 0.0)
        for c in range(1, n):
            comp = lab == c
            cover = np.array([float((comp & b).sum()) / float(comp.sum()) for b in boxes])
            owners = np.flatnonzero(cover >= min_cover)
            if len(owners):
                ids[i] = _split_region(comp, owners, boxes, tight, bottoms[:, i], ids[i])
        if frames is None:
            continue
        for k, b in enumerate(tight):
            if (ids[i] == k + 1).sum() < min_fill * b.sum():
                extra = _clean(box_contrast(frames[i], b), 2) & (ids[i] == 0)
                ids[i][extra] = k + 1
    return ids, labels


def _split_region(comp: np.ndarray, owners: np.ndarray, grown: Sequence[np.ndarray], tight: Sequence[np.ndarray],
                  bottoms: np.ndarray, ids: np.ndarray) -> np.ndarray:
    """[H, W] ids with a connected moving region shared out among the targets `owners` whose boxes
    cover it: each pixel goes to a target whose tight box holds it (else whose grown box does),
    and where several do, to the nearest (objects stand on the ground: the lowest box bottom is
    in front). Pixels already labelled stay as they are."""
    out = ids.copy()
    # rank: 2 inside the tight box, 1 inside the grown one; the box bottom breaks ties (front wins)
    score = np.stack([2.0 * tight[k] + 1.0 * grown[k] + 1e-3 * bottoms[k] * (tight[k] | grown[k])
                      for k in owners])
    best = owners[np.argmax(score, axis=0)]
    take = comp & (score.max(axis=0) > 0) & (out == 0)
    out[take] = best[take] + 1
    return out


def box_contrast(frame: np.ndarray, box: np.ndarray, ring: int = 3, min_colour: float = 25.0) -> np.ndarray:
    """[H, W] bool: pixels inside a box [H, W] whose colour differs from the median colour of a
    `ring`-pixel band around the box by more than `min_colour` (the object against its
    surroundings; completes an object the motion test missed, e.g. under a moving camera)."""
    k = np.ones((2 * ring + 1, 2 * ring + 1), np.uint8)
    band = cv2.dilate(box.astype(np.uint8), k).astype(bool) & ~box
    if not band.any() or not box.any():
        return np.zeros(box.shape, bool)
    f = frame.astype(np.float32)
    ref = np.median(f[band], axis=0)
    return box & (np.abs(f - ref).max(axis=-1) > min_colour)


SETTING_DRESSING: dict[str, tuple[str, ...]] = {"underwater": ("seaweed",)}
"""Setting -> the still objects the procedural generator always dresses it with (its rule: the
sea floor comes with seaweed), looked for like planned still objects."""


def static_plan_labels(info: dict[str, Any]) -> list[str]:
    """Names of the objects a clip's plan says stay still: planned objects no motion moves
    (and without a trajectory), plus the setting's dressing (`SETTING_DRESSING`)."""
    plan = info.get("plan") or {}
    moving = {str(m.get("target")) for m in plan.get("motions") or [] if m.get("path") != "stop"}
    moving |= set((info.get("trajectories") or {}).keys())
    out = [str(o.get("name")) for o in plan.get("objects") or [] if str(o.get("name")) not in moving]
    for extra in SETTING_DRESSING.get(str(info.get("setting") or ""), ()):
        if extra not in out and extra not in moving:
            out.append(extra)
    return out


def static_regions(frame: np.ndarray, setting: np.ndarray, min_colour: float = 45.0, colour_sigmas: float = 4.0,
                   min_area_frac: float = 0.004) -> np.ndarray:
    """[H, W] bool: pixels of the setting region `setting` [H, W] of one frame [H, W, 3] that stand
    out from it in colour: farther than max(`min_colour`, `colour_sigmas` x the setting's spread)
    from the median colour of the setting's pixels in the same row (a setting's colour changes
    with distance, row by row, far more than along a row), cleaned into regions of at least
    `min_area_frac` of the image. What a still object (a plate on the table, seaweed on the sea
    floor) looks like against the setting it stands on."""
    h, w = setting.shape
    f = frame.astype(np.float32)
    ref = np.full((h, 3), np.nan, np.float32)
    for r in range(h):
        if setting[r].sum() >= max(4, w // 8):
            ref[r] = np.median(f[r][setting[r]], axis=0)
    rows = np.flatnonzero(np.isfinite(ref[:, 0]))
    if len(rows) == 0:
        return np.zeros((h, w), bool)
    for c in range(3):                      # rows with too little setting: the nearest row's colour
        ref[:, c] = np.interp(np.arange(h), rows, ref[rows, c])
    dist = np.abs(f - ref[:, None]).max(axis=-1)
    spread = float(np.median(np.abs(dist[setting] - np.median(dist[setting])))) * 1.4826
    odd = setting & (dist > max(min_colour, colour_sigmas * spread))
    return _clean(odd, max(4, int(min_area_frac * h * w)))
