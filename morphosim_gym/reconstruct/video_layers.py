"""Moving things of a real video as per-frame layers that move between the fitted frames, a clean
background plate for a still camera, and whole-frame layers for a moving one.

The scaffold fit (`reconstruct`) moves each instance with a handful of rigid nodes; a video's
estimated masks make every moving region one instance (a crowd of walkers is one "person"), so
the fit cannot move walkers apart, and the estimated tracks often leave the instance static.
Between two fitted frames the movers then stay where they were (smeared), and held-out frames in
between score below simply showing the previous frame. `motion_layers` adds to a fitted scene:

* one layer per fitted frame k and connected moving region: the region's pixels lifted at the
  depth prior (a little nearer the camera) as pixel-sized Gaussians, bound to a node of their own;
* the node's poses on a timeline of half steps (motion frame 2k is fitted frame k): identity at
  2k, half the region's image motion towards frame k - 1 (masked template matching,
  `region_flows`) at 2k - 1, and not shown otherwise (`Motion.shown`). So a fitted frame
  shows its own layer, and the time half-way between two fitted frames shows the later one's
  layers moved half-way back (`LayerConfig.between`: or the earlier one's moved on, or both);
* for a still camera, a background plate: the per-pixel median of the frames over the pixels no
  moving region covers (a pixel covered in every frame takes its nearest neighbour's depth), in
  front of the fitted background (which keeps what the view never saw, from completion), with the
  fit's own mover Gaussians dropped and so are its static Gaussians that the input view sorts in
  front of the plate anywhere within their extent (floaters that only blur the plate's pixels);
  the layers then keep only their pixels that differ from the plate (the mover, not the background
  its mask also covers);
* for a moving camera (no plate: the view changes), frame layers: every pixel of each fitted frame
  k lifted at its depth prior (a little in front of the fit) on nodes of its own, shown at 2k and at
  the half step 2k + 1 after it, hidden otherwise. Rendered from the camera between frames k and
  k + 1, the layer is frame k turned by the camera's motion: the static scene where it was, where
  the scaffold fit of a real street draws it blurred. The fit's movers and its static Gaussians that
  a frame sorts in front of its layer are dropped, as for the plate (the fit keeps what no frame
  saw, for novel views); the movers' layers are left out (`LayerConfig.frame_movers`): the frame
  layers show the movers as the earlier frame had them;
* colours refined against the frames through the renderer (its blur undone, `refine_rounds`).

The result is a `Scene4D` with `2T - 1` motion frames at twice the clip's frame rate (times in
seconds are unchanged; the fitted nodes are resampled); its feature field and objects are the
fitted scene's (new Gaussians take their object's prototype latent, the one the semantic decoder
reads most clearly as its name, `object_features.object_prototypes`, so edits select them). Layers are pixel-thin cut-outs facing the input view: a novel view far from it sees them
edge-on.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..scene import Camera, GeneratedClip, Gaussians, Motion, Scene4D
from ..scene.camera_motion import slerp_cameras
from .object_features import object_prototypes

__all__ = ["LayerConfig", "LayerPriors", "coarse_guesses", "layer_priors", "motion_layers", "region_flows"]

BETWEEN = {"next": (-1,), "previous": (1,), "both": (-1, 1)}   # LayerConfig.between -> the half steps a layer shows at


@dataclass(frozen=True)
class LayerConfig:
    """Settings of `motion_layers`.

    Attributes:
        min_area: moving regions smaller than this many pixels are left out (mask noise).
        opacity: opacity of the layer and plate Gaussians.
        scale: Gaussian size as a fraction of the pixel footprint.
        plate: add the median background plate when the camera is still.
        plate_offset: the plate sits this fraction of its depth in front of the fitted background.
        layer_offset: the layers sit this fraction of their depth nearer the camera (in front of the
            plate, which their feet touch), at the same pixels.
        refine_rounds: colour refinement rounds against the frames (0: the pixels' colours as they are).
        search: how far a region's motion is searched for between fitted frames, as a fraction of the
            width, around its half-resolution match (`coarse_to_fine`) or around staying still.
        between: which fitted frame's layers a time half-way between two fitted frames shows,
            moved half-way: "next" (the later frame's, moved back), "previous" (the earlier
            frame's, moved on) or "both". Both neighbours' half-moved silhouettes overlap into a
            fatter one that covers the background around the mover: on vtest.avi's dev part
            held-out PSNR both 27.94, previous 28.13, next 28.42 dB (static pixels 34.3 / 35.4 /
            36.1 dB).
        frames: whole-frame layers (module docstring); None: for a moving camera (not a still one,
            which has the plate).
        frame_offset: the frame layers sit this fraction of their depth in front of the fitted scene.
        frame_movers: with frame layers, also add the movers' layers in front of them. Off by
            default: on bikes.mp4's dev part they lowered held-out PSNR (27.84 -> 27.29 dB; the
            estimated masks there take passing vans whole and miss the cyclist, and a region moved
            half-way by one flow ghosts), where the frame layers alone show the movers as the
            earlier frame had them.
        coarse_to_fine: also search around each region's motion matched at half resolution within
            twice the range (`coarse_guesses`), so fast movers are followed. Off by default: on the
            dev parts (96 px) it lowered held-out PSNR (bikes 24.64 -> 24.51, vtest 28.31 -> 27.66):
            the wider search finds more false matches of flat regions than fast movers.
        keep_still: a region moves only when its best match beats staying in place by this factor.
        keep_movers: keep the fit's own Gaussians of the movers behind the layers (None: only for a
            moving camera without frame layers, which has nothing else to show behind them).
        refine_step: fraction of the residual each round adds (below 1 damps overshoot at edges).
        plate_level: with a plate, a layer keeps only the pixels of its frame that differ from the
            plate by more than this (0-255, any channel): the mover itself, not the background its
            mask also covers (which the plate shows, and which would otherwise move along).
        drop_occluders: with a plate (frame layers), drop the fitted Gaussians of the static objects
            that the input view (a fitted frame's view) sorts in front of it (they can only cover
            its per-pixel colours there).
    """

    min_area: int = 4
    opacity: float = 0.98
    scale: float = 0.15
    plate: bool = True
    plate_offset: float = 0.05
    layer_offset: float = 0.1
    search: float = 0.125
    keep_still: float = 1.0
    refine_rounds: int = 3
    keep_movers: bool | None = None
    refine_step: float = 1.0
    plate_level: float = 12.0
    drop_occluders: bool = True
    coarse_to_fine: bool = False
    between: str = "next"
    frames: bool | None = None
    frame_offset: float = 0.05
    frame_movers: bool = False


@dataclass(frozen=True)
class LayerPriors:
    """What the layers are built from: per-frame masks of the moving objects and depths.

    Attributes:
        masks: [T, H, W] int, object id per pixel (< 0 none); the movers are `movers`.
        depth: [T, H, W] float camera depth of every pixel (0 unknown).
        movers: ids of the moving objects.
    """

    masks: np.ndarray
    depth: np.ndarray
    movers: tuple[int, ...]


def layer_priors(clip: GeneratedClip, scene: Scene4D) -> LayerPriors:
    """Masks and depths of a video clip from the same estimators the fit used (labels from its prompt)."""
    from ..priors import RGBPriorEstimators
    from .video_labels import video_estimators

    est: Any = video_estimators(clip) or RGBPriorEstimators()
    out = est.masks(clip.frames, None, [], cameras=clip.cameras)
    if out is None:
        t, h, w = clip.frames.shape[:3]
        return LayerPriors(np.full((t, h, w), -1, np.int32), np.zeros((t, h, w), np.float32), ())
    masks, _ = out
    depth = est.depth(clip.frames, list(clip.cameras), masks=masks)
    movers = tuple(o.id for o in scene.objects if o.role != "background")
    return LayerPriors(np.asarray(masks), np.asarray(depth, np.float32), movers)


def region_flows(frames: np.ndarray, a: int, b: int, labels: np.ndarray, count: int,
                 search: int | None = None, keep_still: float = 1.0, guess: np.ndarray | None = None) -> np.ndarray:
    """[count, 2] image motion (pixels, x y) from frame a to frame b of each labelled region 1..count:
    the shift within +- `search` px (default an eighth of the width, at least 6) of no motion or of
    the region's `guess` ([count, 2] px, optional) at which the region's own pixels match
    frame b best (masked template matching; dense optical flow leaves a region's flat interior at
    zero motion; `coarse_guesses` gives where to search). A region whose best shift
    matches no better than `keep_still` times its match in place is taken as still (an ambiguous
    match of a thin or flat region, such as a kerb that compression noise made "move")."""
    import cv2

    h, w = labels.shape
    r = int(search if search is not None else max(6, w // 8))
    centres = np.zeros((count, 2), int) if guess is None else np.round(np.asarray(guess, np.float64)).astype(int)
    if centres.shape != (count, 2):
        raise ValueError(f"Expected guess of shape ({count}, 2), found {centres.shape}")
    pad = r + int(np.abs(centres).max(initial=0))
    fa = np.ascontiguousarray(frames[a]).astype(np.float32)
    fb = cv2.copyMakeBorder(np.ascontiguousarray(frames[b]).astype(np.float32), pad, pad, pad, pad,
                            cv2.BORDER_REPLICATE)
    out = np.zeros((count, 2))
    for reg in range(1, count + 1):
        ys, xs = np.nonzero(labels == reg)
        if len(ys) == 0:
            continue
        y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
        patch = fa[y0:y1, x0:x1]
        mask = (labels[y0:y1, x0:x1] == reg).astype(np.float32)
        best, shift = np.inf, (0, 0)
        for gx, gy in {(0, 0), tuple(centres[reg - 1])}:     # around staying still and around the guess
            oy, ox = y0 + pad + gy - r, x0 + pad + gx - r       # window origin: shift (gx - r, gy - r)
            window = fb[oy:oy + (y1 - y0) + 2 * r, ox:ox + (x1 - x0) + 2 * r]
            cost = cv2.matchTemplate(window, patch, cv2.TM_SQDIFF, mask=np.repeat(mask[..., None], 3, axis=-1))
            dy, dx = np.unravel_index(int(np.argmin(cost)), cost.shape)
            if cost[dy, dx] < best:
                best, shift = float(cost[dy, dx]), (dx - r + gx, dy - r + gy)
        in_place = float((((fb[y0 + pad:y1 + pad, x0 + pad:x1 + pad] - patch) ** 2).sum(-1) * mask).sum())
        if best < keep_still * in_place:      # else no motion explains the region about as well
            out[reg - 1] = shift
    return out


def coarse_guesses(frames: np.ndarray, a: int, b: int, labels: np.ndarray, count: int,
                   search: int | None = None, keep_still: float = 1.0) -> np.ndarray:
    """[count, 2] motion (px, x y) of each labelled region 1..count from frame a to b, matched at half
    resolution within +- `search` half-resolution px (twice as far at full resolution): where
    `region_flows` then searches, so the range follows a fast mover's estimated motion instead of
    a fixed window around staying still. (Dense optical flow was tried and measured: it leaves a
    small flat region that jumps farther than its size at about zero motion.)"""
    import cv2

    h, w = labels.shape
    size = (max(1, w // 2), max(1, h // 2))
    small = np.stack([cv2.resize(np.ascontiguousarray(frames[i]), size, interpolation=cv2.INTER_AREA) for i in (a, b)])
    lab = cv2.resize(labels.astype(np.float32), size, interpolation=cv2.INTER_NEAREST).astype(np.int32)
    return 2.0 * region_flows(small, 0, 1, lab, count, search, keep_still)


def _lift(camera: Camera, rows: np.ndarray, cols: np.ndarray, depth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World points of pixels and their footprints (metres per pixel at their depth)."""
    uv = np.stack([cols + 0.5, rows + 0.5], axis=-1)
    return camera.unproject(uv, depth), depth / camera.fx


def _displacement(cams: tuple[Camera, ...], a: int, b: int, centre: np.ndarray, z: float, flow: np.ndarray) -> np.ndarray:
    """World displacement of a point seen at pixel `centre` in frame a, at `centre + flow` in frame b (same depth)."""
    pa = cams[a].unproject(centre, np.float64(z))
    pb = cams[b].unproject(centre + flow, np.float64(z))
    return pb - pa


def _differs_from_plate(frames: np.ndarray, plate: np.ndarray, level: float) -> np.ndarray:
    """[T, H, W] pixels whose colour differs from the plate image (in [0, 1]) by more than `level` (0-255)."""
    return np.abs(frames.astype(np.float64) - plate[None] * 255.0).max(axis=-1) > level


class _LayerSet:
    """Layers being built: each `add` is one node, its pixels of frame k lifted at their depths,
    its translation on the half-step timeline and the motion frames it is shown at."""

    KEYS = ("means", "colors", "footprint", "ids", "node", "pixel")

    def __init__(self) -> None:
        self.parts: dict[str, list[np.ndarray]] = {key: [] for key in self.KEYS}
        self.trans: list[np.ndarray] = []
        self.shown: list[np.ndarray] = []

    def add(self, clip: GeneratedClip, k: int, rows: np.ndarray, cols: np.ndarray, depth: np.ndarray,
            ids: np.ndarray, path: np.ndarray, seen: np.ndarray) -> None:
        pts, fp = _lift(clip.cameras[k], rows, cols, depth)
        for key, value in (("means", pts), ("colors", clip.frames[k, rows, cols].astype(np.float64) / 255.0),
                           ("footprint", fp), ("ids", ids), ("node", np.full(len(rows), len(self.trans))),
                           ("pixel", np.stack([np.full(len(rows), k), rows, cols], axis=1))):
            self.parts[key].append(value)
        self.trans.append(path)
        self.shown.append(seen)

    def result(self) -> dict[str, np.ndarray]:
        """The layers' arrays, "trans" [2T - 1, K, 3] and "shown" [2T - 1, K] ({} when none was added)."""
        if not self.trans:
            return {}
        out = {key: np.concatenate(v) for key, v in self.parts.items()}
        out["trans"], out["shown"] = np.stack(self.trans, axis=1), np.stack(self.shown, axis=1)
        return out


def _layers(clip: GeneratedClip, priors: LayerPriors, cfg: LayerConfig,
            plate: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """The movers' Gaussians of every frame and their nodes' translations on the half-step timeline
    (with a `plate` image, only the movers' pixels that differ from it)."""
    import cv2

    t = clip.num_frames
    cams = clip.cameras
    moving = np.isin(priors.masks, priors.movers) & (priors.depth > 0)
    if plate is not None:
        moving &= _differs_from_plate(clip.frames, plate, cfg.plate_level)
    built = _LayerSet()
    for k in range(t):
        count, labels, stats, _ = cv2.connectedComponentsWithStats(moving[k].astype(np.uint8), connectivity=8)
        keep = [r for r in range(1, count) if stats[r, cv2.CC_STAT_AREA] >= cfg.min_area]
        if not keep:
            continue
        reach = max(6, int(round(cfg.search * clip.width)))
        flows = {d: region_flows(clip.frames, k, k + d, labels, count - 1, reach, cfg.keep_still,
                                 coarse_guesses(clip.frames, k, k + d, labels, count - 1, reach, cfg.keep_still)
                                 if cfg.coarse_to_fine else None)
                 for d in BETWEEN[cfg.between] if 0 <= k + d < t}
        for r in keep:
            rows, cols = np.nonzero(labels == r)
            z = priors.depth[k, rows, cols].astype(np.float64) * (1.0 - cfg.layer_offset)
            path, seen = np.zeros((2 * t - 1, 3)), np.zeros(2 * t - 1, bool)
            seen[2 * k] = True
            centre = np.array([cols.mean() + 0.5, rows.mean() + 0.5])
            for d, fl in flows.items():
                path[2 * k + d] = 0.5 * _displacement(cams, k, k + d, centre, float(np.median(z)), fl[r - 1])
                seen[2 * k + d] = True
            built.add(clip, k, rows, cols, z, priors.masks[k, rows, cols], path, seen)
    return built.result()


def _frame_layers(clip: GeneratedClip, priors: LayerPriors, setting: int, cfg: LayerConfig) -> dict[str, np.ndarray]:
    """Every pixel of each fitted frame k at its depth prior (pixels of unknown depth take their
    nearest known pixel's), one node per frame and object, shown at motion frames 2k and 2k + 1;
    "depth" holds each frame's layer depth [T, H, W] (0 where the frame has no layer)."""
    t, h, w = priors.depth.shape
    built = _LayerSet()
    layer_depth = np.zeros((t, h, w))
    for k in range(t):
        depth = _fill_nearest(priors.depth[k], np.ones((h, w), bool))
        if not (depth > 0).all():
            continue                                     # no depth anywhere in this frame
        layer_depth[k] = depth * (1.0 - cfg.frame_offset)
        ids = np.where(priors.masks[k] >= 0, priors.masks[k], setting)
        seen = np.zeros(2 * t - 1, bool)
        seen[2 * k:2 * k + 2] = True                       # shown at its frame and the half step after
        for obj in np.unique(ids):
            rows, cols = np.nonzero(ids == obj)
            built.add(clip, k, rows, cols, layer_depth[k, rows, cols], np.full(len(rows), obj),
                      np.zeros((2 * t - 1, 3)), seen)
    out = built.result()
    if out:
        out["depth"] = layer_depth
    return out


def _merge_layers(first: dict[str, np.ndarray], second: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Two layer sets as one (the second's nodes numbered after the first's)."""
    if not first or not second:
        return first or second
    out = {k: np.concatenate([first[k], second[k] + (first["trans"].shape[1] if k == "node" else 0)])
           for k in _LayerSet.KEYS}
    for k in ("trans", "shown"):
        out[k] = np.concatenate([first[k], second[k]], axis=1)
    return out


def _plate(clip: GeneratedClip, priors: LayerPriors, setting: int, cfg: LayerConfig) -> dict[str, np.ndarray]:
    """Median background of a still camera over the pixels no mover covers, a little in front of the fit."""
    moving = np.isin(priors.masks, priors.movers)
    frames = np.where(moving[..., None], np.nan, clip.frames.astype(np.float64))
    with np.errstate(all="ignore"):
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            plate = np.nanmedian(frames, axis=0)
    plate = np.where(np.isnan(plate), np.median(clip.frames, axis=0), plate)
    depth = _fill_nearest(np.max(np.where(moving, 0.0, priors.depth), axis=0), np.max(priors.depth, axis=0) > 0)
    rows, cols = np.nonzero(depth > 0)
    z = depth[rows, cols].astype(np.float64) * (1.0 - cfg.plate_offset)
    pts, fp = _lift(clip.cameras[0], rows, cols, z)
    plate_depth = np.zeros(depth.shape)
    plate_depth[rows, cols] = z
    return {"means": pts, "colors": plate[rows, cols] / 255.0, "footprint": fp, "ids": np.full(len(rows), setting),
            "pixel": np.stack([np.zeros(len(rows), int), rows, cols], axis=1), "image": plate / 255.0,
            "depth": plate_depth}


def _fill_nearest(depth: np.ndarray, where: np.ndarray) -> np.ndarray:
    """`depth` [H, W] with its unknown (<= 0) pixels inside `where` given their nearest known pixel's depth
    (a pixel that a mover covers in every frame still gets a plate)."""
    import cv2

    known = depth > 0
    hole = where & ~known
    if not hole.any() or not known.any():
        return depth
    _, label = cv2.distanceTransformWithLabels((~known).astype(np.uint8), cv2.DIST_L2, 5,
                                               labelType=cv2.DIST_LABEL_PIXEL)
    source = np.flatnonzero(known.ravel())          # label j (1-based) is the j-th known pixel in scan order
    out = depth.ravel().copy()
    out[hole.ravel()] = out[source[label.ravel()[hole.ravel()] - 1]]
    return out.reshape(depth.shape)


def _in_front_of_plate(g: Gaussians, camera: Camera, plate_depth: np.ndarray, sigmas: float = 3.0) -> np.ndarray:
    """[N] Gaussians that the (still) input camera sorts in front of some plate pixel they cover: their
    centre is nearer than the farthest plate depth within `sigmas` of their projected size (the
    renderer sorts by centre depth, so a large Gaussian covers every farther plate pixel it reaches)."""
    import cv2

    uv, z = camera.project(np.asarray(g.means, np.float64))
    h, w = plate_depth.shape
    with np.errstate(invalid="ignore", divide="ignore"):
        inside = (z > 0) & (uv[:, 0] > -w) & (uv[:, 0] < 2 * w) & (uv[:, 1] > -h) & (uv[:, 1] < 2 * h)
        radius = sigmas * np.asarray(g.scales, np.float64).max(axis=1) * camera.fx / np.where(z > 0, z, 1.0)
    out = np.zeros(len(z), bool)
    idx = np.flatnonzero(inside)
    levels = [0] + [2 ** i for i in range(int(np.ceil(np.log2(max(h, w)))) + 1)]   # max-filter radii in px
    level = np.searchsorted(levels, np.minimum(radius[idx], levels[-1]))
    pad = levels[-1]
    padded = cv2.copyMakeBorder(plate_depth.astype(np.float32), pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0.0)
    cols = np.clip(uv[idx, 0], -pad, w + pad - 1).astype(int) + pad
    rows = np.clip(uv[idx, 1], -pad, h + pad - 1).astype(int) + pad
    for j, r in enumerate(levels):
        sel = level == j
        if not sel.any():
            continue
        far = padded if r == 0 else cv2.dilate(padded, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1,) * 2))
        out[idx[sel]] = z[idx[sel]] < far[rows[sel], cols[sel]]
    return out


def _gaussians(part: dict[str, np.ndarray], cfg: LayerConfig, features: np.ndarray | None) -> Gaussians:
    n = len(part["means"])
    s = np.repeat(part["footprint"][:, None] * cfg.scale, 3, axis=1)
    return Gaussians(means=part["means"].astype(np.float32), quats=np.tile([1.0, 0, 0, 0], (n, 1)).astype(np.float32),
                     scales=s.astype(np.float32), opacities=np.full(n, cfg.opacity, np.float32),
                     colors=np.clip(part["colors"], 0, 1).astype(np.float32), features=features,
                     object_ids=part["ids"].astype(np.int32))


def _concat(parts: list[Gaussians]) -> Gaussians:
    names = ("means", "quats", "scales", "opacities", "colors", "object_ids")
    cat = {n: np.concatenate([np.asarray(getattr(p, n)) for p in parts]) for n in names}
    feats = None
    if all(p.features is not None for p in parts):
        feats = np.concatenate([np.asarray(p.features) for p in parts]).astype(np.float32)
    return Gaussians(**cat, features=feats)


def _still(clip: GeneratedClip) -> bool:
    return len({c.world_to_camera.tobytes() for c in clip.cameras}) == 1


def _half_step_cameras(cams: tuple[Camera, ...]) -> tuple[Camera, ...]:
    if len({c.world_to_camera.tobytes() for c in cams}) == 1:
        return (cams[0],)
    times = list(range(len(cams)))
    return tuple(slerp_cameras(cams, times, 0.5 * j) for j in range(2 * len(cams) - 1))


def _half_step_motion(motion: Motion, keep: np.ndarray, frames: int) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                              np.ndarray, np.ndarray]:
    """The fitted motion of the kept Gaussians resampled at `frames` half steps: node rotations
    [F, K, 4], translations [F, K, 3], node objects [K], skin nodes and weights of the kept rows."""
    poses = [motion.node_poses(0.5 * j) for j in range(frames)]
    rot = np.stack([p[0] for p in poses]).reshape(frames, motion.num_nodes, 4)
    tr = np.stack([p[1] for p in poses]).reshape(frames, motion.num_nodes, 3)
    return rot, tr, motion.node_objects, motion.skin_nodes[keep], motion.skin_weights[keep]


def _assemble(scene: Scene4D, clip: GeneratedClip, parts: list[Gaussians], keep: np.ndarray,
              layers: dict[str, np.ndarray], movers: tuple[int, ...]) -> Scene4D:
    """The output scene: `parts` concatenated (the fitted Gaussians kept first, the layers' last),
    the kept ones moving as fitted and the layers on their own nodes, on the half-step timeline."""
    gaussians = _concat(parts)
    n = len(gaussians)
    if layers:
        rot, tr, node_objects, kept_nodes, kept_weights = _half_step_motion(scene.motion, keep, 2 * clip.num_frames - 1)
    else:                                   # no layers: the fitted timeline, motion and cameras as they are
        fitted = scene.motion
        rot, tr, node_objects, shown = fitted.rotations, fitted.translations, fitted.node_objects, fitted.shown
        kept_nodes, kept_weights = fitted.skin_nodes[keep], fitted.skin_weights[keep]
    slots = max(1, kept_nodes.shape[1])
    skin_nodes = np.full((n, slots), -1, np.int32)
    skin_weights = np.zeros((n, slots), np.float32)
    skin_nodes[:len(kept_nodes), :kept_nodes.shape[1]] = kept_nodes
    skin_weights[:len(kept_nodes), :kept_nodes.shape[1]] = kept_weights
    objects = scene.objects
    if layers:
        frames = rot.shape[0]
        m, k0 = len(layers["means"]), rot.shape[1]
        skin_nodes[n - m:, 0] = layers["node"] + k0
        skin_weights[n - m:, 0] = 1.0
        count = layers["trans"].shape[1]
        identity = np.zeros((frames, count, 4))
        identity[..., 0] = 1.0
        shown = np.concatenate([np.ones((frames, rot.shape[1]), bool), layers["shown"]], axis=1)
        rot, tr = np.concatenate([rot, identity], axis=1), np.concatenate([tr, layers["trans"]], axis=1)
        first = np.unique(layers["node"], return_index=True)[1]
        node_objects = np.concatenate([node_objects, layers["ids"][first]]).astype(np.int32)
        objects = tuple(replace(o, dynamic=o.dynamic or o.id in movers) for o in scene.objects)
    motion = Motion(rot, tr, skin_nodes, skin_weights, node_objects, shown)
    cameras = _half_step_cameras(clip.cameras) if layers else scene.cameras
    return Scene4D(gaussians, motion, objects, clip.fps * (2.0 if layers else 1.0), cameras,
                   decoders=scene.decoders, provenance=scene.provenance, background=scene.background, sky=scene.sky,
                   sensor=scene.sensor)


def _render(scene: Scene4D, camera: Camera, t: float) -> np.ndarray:
    from ..render import render

    return np.clip(np.asarray(render(scene, camera, t=t).rgb, np.float64), 0.0, 1.0)


def _refine_colours(scene: Scene4D, clip: GeneratedClip, spans: dict[str, slice], pixels: dict[str, np.ndarray],
                    targets: dict[str, np.ndarray], rounds: int, step_size: float = 1.0) -> Scene4D:
    """Undo the renderer's blur on the plate and layer colours: each round adds every Gaussian's
    pixel residual (its frame minus the render there) to its colour (Van Cittert iteration)."""
    fitted = np.unique(np.concatenate([px[:, 0] for px in pixels.values()] or [np.zeros(0, int)]))
    for _ in range(rounds):
        colors = np.array(scene.gaussians.colors, np.float64)
        for k in fitted:                                  # each fitted frame rendered once a round
            img = _render(scene, clip.cameras[int(k)], float(k) / clip.fps)
            for name, sl in spans.items():
                px = pixels[name]
                sel = np.flatnonzero(px[:, 0] == k)
                if not len(sel):
                    continue
                target = targets[name] if name == "plate" else clip.frames[int(k)] / 255.0
                rows, cols = px[sel, 1], px[sel, 2]
                step = target[rows, cols] - img[rows, cols]
                if name == "plate" and "plate_free" in targets:     # under frame 0's movers: left as is
                    step *= targets["plate_free"][rows, cols, None]
                colors[sl.start + sel] += step_size * step
        g = scene.gaussians.replace(colors=np.clip(colors, 0.0, 1.0).astype(np.float32))
        scene = Scene4D(g, scene.motion, scene.objects, scene.fps, scene.cameras, decoders=scene.decoders,
                        provenance=scene.provenance, background=scene.background, sky=scene.sky, sensor=scene.sensor)
    return scene


def _feature_table(scene: Scene4D, ids: np.ndarray) -> np.ndarray | None:
    """[max id + 1, D] latent for new Gaussians of each object id: the object's prototype
    (`object_prototypes`: the latent that decodes most clearly as its name; None without features)."""
    protos = object_prototypes(scene.gaussians, scene.objects, scene.decoders.get("semantic"),
                               instance=scene.decoders.get("instance"))
    if not protos:
        return None
    dim = len(next(iter(protos.values())))
    table = np.zeros((int(ids.max()) + 1, dim), np.float32)
    fallback = np.mean(list(protos.values()), axis=0)
    for i in ids:
        table[i] = protos.get(int(i), fallback)
    return table


def _append(parts: list[Gaussians], spans: dict[str, slice], pixels: dict[str, np.ndarray], name: str,
            part: dict[str, np.ndarray], cfg: LayerConfig, table: np.ndarray | None) -> None:
    """Add a plate or the layers to `parts`, noting where its Gaussians sit and which pixels they draw."""
    start = sum(len(p) for p in parts)
    parts.append(_gaussians(part, cfg, None if table is None else table[part["ids"]]))
    spans[name], pixels[name] = slice(start, start + len(part["means"])), part["pixel"]


def motion_layers(scene: Scene4D, clip: GeneratedClip, priors: LayerPriors | None = None,
                  config: LayerConfig | None = None) -> Scene4D:
    """`scene` (fitted to `clip`) with per-frame layers of its movers, moved between the fitted
    frames, for a still camera a median background plate in place of the fit's movers, for a moving
    one whole-frame layers (see the module docstring). A still scene without movers gets only the
    plate; a clip of one frame gets neither."""
    cfg = config or LayerConfig()
    if cfg.between not in BETWEEN:
        raise ValueError(f"Expected LayerConfig.between in {sorted(BETWEEN)}, found {cfg.between!r}")
    if scene.motion.num_frames not in (1, clip.num_frames):
        raise ValueError(f"Expected a scene fitted to the clip ({clip.num_frames} frames), found "
                         f"{scene.motion.num_frames} motion frames")
    pri = priors or layer_priors(clip, scene)
    g = scene.gaussians
    all_ids = np.array(sorted({o.id for o in scene.objects}), np.int64)
    table = _feature_table(scene, all_ids)
    still = _still(clip)
    spans: dict[str, slice] = {}
    pixels: dict[str, np.ndarray] = {}
    targets: dict[str, np.ndarray] = {}
    setting = [o.id for o in scene.objects if o.role == "background"]
    several = clip.num_frames > 1
    plate = _plate(clip, pri, setting[0], cfg) if cfg.plate and still and setting and several else None
    want_frames = cfg.frames if cfg.frames is not None else not still
    frames = _frame_layers(clip, pri, setting[0], cfg) if want_frames and setting and several else {}
    keep_movers = cfg.keep_movers if cfg.keep_movers is not None else not (still or frames)
    static = ~np.isin(np.asarray(g.object_ids), pri.movers)
    keep = np.ones(len(g), bool) if keep_movers else static.copy()
    if cfg.drop_occluders:                        # the movers kept by choice (keep_movers) stay
        views = [(clip.cameras[0], plate["depth"])] if plate is not None else []
        views += [(clip.cameras[k], d) for k, d in enumerate(frames.get("depth", ())) if d.any()]
        for camera, depth in views:
            keep &= ~(_in_front_of_plate(g, camera, depth) & static)
    parts = [g.subset(keep)]
    if plate is not None:
        _append(parts, spans, pixels, "plate", plate, cfg, table)
        targets["plate"] = plate["image"]
        targets["plate_free"] = (~np.isin(pri.masks[0], pri.movers)).astype(np.float64)
    movers = (_layers(clip, pri, cfg, None if plate is None else plate["image"])
              if pri.movers and several and (cfg.frame_movers or not frames) else {})
    for name, part, fallback in (("frames", frames, setting[:1]), ("layers", movers, pri.movers[:1])):
        if part:                                  # (in the order _merge_layers keeps)
            part["ids"] = np.where(np.isin(part["ids"], all_ids), part["ids"], fallback[0])
            _append(parts, spans, pixels, name, part, cfg, table)
    out = _assemble(scene, clip, parts, keep, _merge_layers(frames, movers), pri.movers)
    if not cfg.refine_rounds:
        return out
    return _refine_colours(out, clip, spans, pixels, targets, cfg.refine_rounds, cfg.refine_step)
