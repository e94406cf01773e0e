"""`RGBPriorEstimators`: the offline default (CPU, no weights) for clips that come without priors."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from ..scene.camera import Camera
from .depth import contact_depth, ground_plane_depth, wall_depth
from .colour_refine import refine_by_colour
from .masks import box_masks, label_regions, motion_foreground, planned_boxes, static_regions, still_camera
from .overlaps import split_by_motion
from .protocol import BoxTrack
from .rims import trim_rims
from .shapes import split_by_shape
from .siblings import base_name, depths_from_siblings
from .sizes import ObjectSize, pixel_rows, size_depth
from .skyline import horizon_rows, sky_region, sky_seam
from .tracks import flow_tracks

__all__ = ["SETTING_ID", "RGBPriorEstimators", "object_depths"]

SETTING_ID = 0      # the setting (ground, road, water...) in estimated masks; objects are 1..
BEYOND_ID = -1      # neither the setting nor an object: the sky (no ground there, or none at all)


@dataclass(frozen=True)
class RGBPriorEstimators:
    """Priors from the frames and cameras alone.

    - masks: moving regions (`masks.motion_foreground`) labelled with the plan's moving objects
      (`masks.label_regions`); the other pixels are the setting (id 0, label `setting_label`),
      except the sky (-1). With `backdrop` there is no sky; without it, the sky is what
      `skyline.sky_region` reads from each frame's colours (`skyline`: a setting's ground
      that ends short of the horizon, hills that rise above it), or above the ground plane's
      horizon where colour cannot tell or `skyline` is False. Attention maps are not used. The still
      objects the plan names (`static_labels`: `masks.static_plan_labels`) are the regions of the
      setting that stand out from it in colour (`masks.static_regions`); other still things
      join the setting. With a plan (`targets`), each object's mask is then corrected by its own
      colours over the clip (`colour_refine.refine_by_colour`; `colour_refine=False` skips it).
      Without one (a video: every moving region is one "object", a crowd of many colours) it is
      not: on the two real videos of `benchmarks/video.py` it cost 0.3-0.6 dB on held-out frames.
      Where two moving objects' boxes overlap, `label_regions` gave the pixels to the nearest box;
      each now goes to the object whose box motion it follows (`overlaps.split_by_motion`; after
      the colour correction: before it, two 96-px sheep came out worse, IoU 0.68 -> 0.43;
      `motion_split=False` skips it).
      Last, with a plan, each moving object's outline against the setting, and against the sky
      (also where no setting is seen: a bird up in the sky), is trimmed to the pixels it covers
      at least half of (`rims.trim_rims`; `rims=False` skips it): masks from motion take every
      pixel the object touches, a rim of setting 1 px wide.
      Then numbered instances of one planned object ("duck 1", "duck 2"), which move in step and
      look alike, so that neither motion nor colour tells them apart, share out their pixels by
      the one shape they share in their boxes (`shapes.split_by_shape`; `sibling_shapes=False`
      skips it): three ducks in a row, estimated masks' IoU 0.17 / 0.58 / 0.29 -> 0.76 / 0.80 /
      0.74; it costs siblings of two different looks (two cows 0.88 / 0.91 -> 0.77 / 0.87).
    - depth: the ground plane z = `ground_height` for the setting (the setting above the horizon:
      a backdrop as far as the farthest ground seen; the sky: 0); each object region gets the
      ground depth where its lowest pixels meet the ground (objects stand on the ground), or,
      given its real size (`sizes`, by label: `sizes.planned_sizes`), the depth at which
      something that tall covers its rows when it swims or flies or touches no ground; a
      planned object off the ground (a bouncing ball in the air) is found by measuring it
      against itself on the ground, its contact depth times its pixel height, and put at the
      depth its rows give there (`object_depths`); the median ground depth when neither is known. A flat
      object (a plate, a book: its size under a fifth as tall as long) takes the ground's own
      depth, or with `flat_tops` the plane its height above the ground. With `walls` (and
      `backdrop`), the setting above the row where a frame's colour changes from floor to wall
      (`skyline.sky_seam`) is a vertical wall standing on the floor there (`depth.wall_depth`),
      instead of a backdrop as far as the farthest ground.
    - tracks: chained DIS optical flow with a forward-backward check (`tracks.flow_tracks`).

    Attributes:
        ground_height: world z of the ground plane (metres).
        max_depth: ground farther than this is unknown (0).
        far_heights: with a value, the ground is seen as far as this many times the camera's
            height above it (camera depth) instead of `max_depth`: farther rows are the
            setting's backdrop, as far as the farthest ground left, where the masks say setting
            (`depth`), and the sky where they do not. A fixed cap does not follow the scene's
            scale: 50 m is 6 heights of the bus's camera (8.1 m up; its far road, up to hedges
            74 m away, became a wall at 48.6 m) and 227 of a table-top camera's. None: `max_depth`.
        track_spacing: pixel spacing of the tracked point grid.
        fb_threshold: forward-backward check tolerance in pixels.
        box_margin: planned boxes grow by this fraction of their size before labelling.
        setting_label: label of id 0.
        contact_percentile: an object's ground contact is this percentile of the ground depths
            under its lowest pixels (`contact_depth`: its nearest feet, not the ground under its
            belly; sheep 64 px: depth error 24% at the median, 11% at 10).
        lifted_ratio: an object whose ground contact is this many times farther than its size
            prior says is taken to be off the ground there (a bouncing ball in the air: the
            ground seen just under it lies behind it); its depth comes from its size
            (`object_depths`).
        own_lift_ratio: first, a planned ground object is measured against itself: where its
            contact depth times its mask's pixel height is this many times its value on the
            ground (5th percentile over the clip), it is off the ground, at that value over its
            rows (`object_depths`; the football 128 px: contact up to 1.38 m where it flies at
            0.74-0.79 m, a product 26.6-50.9 where the ground truth's stays 26.7-27.6); the size
            test above then only fills the frames without a contact. None: off (the size test
            alone).
        sibling_scale: numbered instances of one planned ground object ("sheep 1", "sheep 2")
            share its size: where more than half of one's contact is hidden by other objects,
            its depth is a sibling's whose contact shows, times that sibling's pixel width over
            its own (`siblings.depths_from_siblings`; the example's rear sheep: 5.9 m where it
            walks at 4.45 m).
        backdrop: pixels above the horizon are part of the setting, at the depth of the farthest
            ground seen (a backdrop: a generated frame draws something there); False leaves them
            unknown (depth 0, mask -1).
        ground: the frames show a ground plane at `ground_height`; False (a scene up in the sky,
            whose frames show no ground near enough to tell from the sky): every pixel outside
            the objects is left unknown (depth 0, mask -1), and objects take their size depth.
        colour_refine: correct a planned clip's object masks by colour (see masks above).
        skyline: without `backdrop`, tell the sky from the setting by colour (see masks above).
        rims: trim a planned clip's moving objects' outlines (see masks above).
        motion_split: share out overlapping moving objects by their motion (see masks above).
        sibling_shapes: share out numbered siblings by their shared shape (see masks above).
        walls: with `backdrop`, a wall where the setting's colour changes above the floor (see
            depth above); `prepare.default_estimators` turns it on in settings closed by walls.
            The mug clip's wall, 1.23-1.33 m away, is at 1.26-1.36 m with it, 22 m without. A
            fit to a near wall needs its Gaussians kept near their first size and the wall
            continued in the colours the views show (`reconstruct.pipeline` does both when
            `info["prior_walls"]` says so): without, floor-coloured streaks along the wall's
            foot, hidden in the input view, crossed it in turned views (mug novel views -0.6
            to -5.1 dB).
        flat_tops: a flat object's pixels at its top rather than on the ground. Off by
            default: the plate's depth error fell from 4.5% to 1% and its fitted IoU rose
            (cube clip 0.71 -> 0.74; held-out 0.61 -> 0.62 and 0.72 -> 0.73), but novel views
            moved by -6.1 to +1.0 dB on the held-out plates (`reconstruct_flat_heldout_prompts.txt`,
            first run, 2026-12-06), through where the completion found the far backdrop.
    """

    ground_height: float = 0.0
    max_depth: float = 50.0
    far_heights: float | None = None
    track_spacing: int = 4
    fb_threshold: float = 1.0
    box_margin: float = 0.25
    setting_label: str = "ground"
    backdrop: bool = True
    lifted_ratio: float = 1.35
    own_lift_ratio: float | None = 1.15
    sibling_scale: bool = True
    contact_percentile: float = 10.0
    ground: bool = True
    colour_refine: bool = True
    skyline: bool = True
    walls: bool = False
    flat_tops: bool = False
    rims: bool = True
    motion_split: bool = True
    sibling_shapes: bool = True

    def __post_init__(self) -> None:
        if self.far_heights is not None and not (np.isfinite(self.far_heights) and self.far_heights > 0):
            raise ValueError(f"Expected far_heights > 0 or None, found {self.far_heights!r}")
        if self.own_lift_ratio is not None and not (np.isfinite(self.own_lift_ratio) and self.own_lift_ratio > 1):
            raise ValueError(f"Expected own_lift_ratio > 1 or None, found {self.own_lift_ratio!r}")

    @property
    def stands_walls(self) -> bool:
        """Whether `depth` stands walls where the setting's colour changes above the floor
        (`walls` on a seen ground closed by a backdrop)."""
        return self.ground and self.backdrop and self.walls

    def _ground(self, camera: Camera) -> np.ndarray:
        """[H, W] camera depth of the ground plane as far as it is taken to be seen (`max_depth`,
        `far_heights`), 0 beyond."""
        reach = self.max_depth
        if self.far_heights is not None:
            reach = self.far_heights * max(float(camera.position[2]) - self.ground_height, 0.0)
        return ground_plane_depth(camera, self.ground_height, reach)

    def _cameras(self, camera: Camera | Sequence[Camera], t: int) -> list[Camera]:
        cams = [camera] * t if isinstance(camera, Camera) else list(camera)
        if len(cams) != t:
            raise ValueError(f"Expected one camera or {t} cameras, found {len(cams)}")
        return cams

    def depth(self, frames: np.ndarray, camera: Camera | Sequence[Camera],
              masks: np.ndarray | None = None, labels: Mapping[int, str] | None = None,
              sizes: Mapping[str, ObjectSize] | None = None) -> np.ndarray:
        t = len(frames)
        cams = self._cameras(camera, t)
        grounds = [self._ground(c) for c in cams]
        out = np.stack(grounds)
        far = float(out.max()) if np.any(out > 0) else self.max_depth     # a backdrop: the farthest ground seen
        if not self.ground:
            out = np.zeros_like(out)
        elif self.backdrop:
            out = np.where(out > 0, out, far).astype(np.float32)          # everything above the horizon
        if masks is None:
            return out
        if self.stands_walls:
            # where the setting changes colour above the floor, a wall stands on it
            for i, (c, g) in enumerate(zip(cams, grounds)):
                seam = sky_seam(np.asarray(frames[i]), masks[i] > SETTING_ID, horizon_rows(g > 0))
                if seam is not None:
                    wall = wall_depth(c, seam, g)
                    at = (wall > 0) & (masks[i] == SETTING_ID)
                    out[i][at] = wall[at]
        if self.ground and not self.backdrop:
            # the setting above the horizon (hills) is a backdrop; the sky (-1) is nothing at all
            out = np.where((masks == SETTING_ID) & (out <= 0), far, out)
            out = np.where(masks < 0, 0.0, out).astype(np.float32)
        valid = out[out > 0]
        fallback = float(np.median(valid)) if valid.size else 1.0
        ground = out.copy()
        depths: dict[int, np.ndarray] = {}
        groups: dict[str, list[int]] = {}
        for inst in np.unique(masks):
            if inst <= SETTING_ID:
                continue
            base = base_name((labels or {}).get(int(inst), ""))
            size = (sizes or {}).get(base)
            if size is not None and size.height < 0.2 * size.longest:
                if not self.flat_tops:
                    continue            # flat on the ground (a plate): the ground's own depth
                # its top: the plane its height above the ground
                for i, c in enumerate(cams):
                    m = masks[i] == inst
                    top = ground_plane_depth(c, self.ground_height + size.height, self.max_depth)[m]
                    out[i][m] = np.where(top > 0, top, out[i][m])
                continue
            depths[int(inst)] = object_depths(masks, int(inst), ground, cams, size, self.lifted_ratio,
                                              self.contact_percentile, own_lift_ratio=self.own_lift_ratio)
            if size is not None and size.mobility not in ("swim", "air"):
                groups.setdefault(base, []).append(int(inst))
        if self.sibling_scale:
            depths = depths_from_siblings(masks, depths, list(groups.values()))
        for inst, z in depths.items():
            z = np.where(np.isfinite(z), z, fallback)
            for i in range(t):
                out[i][masks[i] == inst] = z[i]
        return out.astype(np.float32)

    def masks(self, frames: np.ndarray, attention: np.ndarray | None, targets: Sequence[BoxTrack],
              cameras: Sequence[Camera] | None = None, static_labels: Sequence[str] = (),
              ) -> tuple[np.ndarray, dict[int, str]]:
        f = np.asarray(frames)
        t, h, w = f.shape[:3]
        fg = motion_foreground(f, cameras, targets, self.ground_height, self.box_margin)
        ids, labels = label_regions(fg, targets, self.box_margin, frames=f)
        ids = ids.copy()
        if not self.ground:
            not_sky = np.zeros((t, h, w), bool)
        elif cameras is not None and not self.backdrop:
            not_sky = np.stack([self._not_sky(f[i], ids[i] > 0, c)
                                for i, c in enumerate(self._cameras(cameras, t))])
        else:
            not_sky = np.ones((t, h, w), bool)
        setting = (ids == 0) & not_sky
        if static_labels:
            # the still objects the plan names: what stands out from the setting in colour (one
            # label: every such region; several: the largest regions, one label each)
            first = len(targets) + 1
            for i in range(t):
                # not inside a moving object's planned box: what the motion test missed of it
                boxed = np.any(box_masks(targets, i, h, w, 0.0), axis=0) if targets else np.zeros((h, w), bool)
                odd = static_regions(f[i], setting[i]) & ~boxed
                n, lab, stats, _ = cv2.connectedComponentsWithStats(odd.astype(np.uint8), connectivity=8)
                order = np.argsort(-stats[1:, cv2.CC_STAT_AREA]) + 1
                for k, c in enumerate(order):
                    idx = min(k, len(static_labels) - 1) if len(static_labels) == 1 else k
                    if idx >= len(static_labels):
                        break
                    ids[i][lab == c] = first + idx
                    setting[i][lab == c] = False
            labels = {**labels, **{first + k: str(n) for k, n in enumerate(static_labels)}}
        ids[ids == 0] = BEYOND_ID
        ids[setting] = SETTING_ID
        if self.colour_refine and targets and setting.any():
            still = None
            if cameras is None or still_camera(cameras):
                # unchanged against a background model that saw the pixel free of every planned
                # box in enough frames (a slow mug's own pixels are in its box in all of them)
                boxed = planned_boxes(targets, t, h, w, self.box_margin)     # the background model's boxes
                still = ~fg & ((~boxed).sum(axis=0) >= max(1, 0.2 * t))[None]
            ids = refine_by_colour(f, ids, SETTING_ID, movers=range(1, len(targets) + 1), still=still)
        if self.motion_split and len(targets) > 1:
            ids = split_by_motion(f, ids, targets, self.box_margin)
        if self.rims and targets:
            ids = np.stack([trim_rims(f[i], ids[i], range(1, len(targets) + 1), SETTING_ID, backdrops=(BEYOND_ID,))
                            for i in range(t)])
        if self.sibling_shapes and len(targets) > 1:
            ids = split_by_shape(ids, targets)
        if setting.any():
            labels = {SETTING_ID: self.setting_label, **labels}
        present = set(np.unique(ids).tolist())
        return ids, {k: v for k, v in labels.items() if k in present}

    def _not_sky(self, frame: np.ndarray, objects: np.ndarray, camera: Camera) -> np.ndarray:
        """[H, W] bool: where one frame shows something (the setting or an object), not the sky."""
        below = self._ground(camera) > 0
        sky = sky_region(frame, objects, horizon_rows(below)) if self.skyline else None
        return below if sky is None else ~sky

    def tracks(self, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return flow_tracks(frames, self.track_spacing, self.fb_threshold)


def _lifted_by_own_scale(contact: np.ndarray, rows: np.ndarray, ratio: float, percentile: float = 5.0,
                         min_frames: int = 3) -> tuple[np.ndarray, bool]:
    """[T] contact depths with the frames where contact x rows exceeds `ratio` times its
    `percentile` over the clip (the object on the ground) replaced by that value over the rows,
    and True; as given and False when under `min_frames` frames have both."""
    scale = contact * rows
    ok = np.isfinite(scale)
    if ok.sum() < min_frames:
        return contact, False
    grounded = float(np.percentile(scale[ok], percentile))
    lifted = ok & (scale > ratio * grounded)
    return np.where(lifted, grounded / np.where(ok, rows, 1.0), contact), True


def _median_filter(z: np.ndarray, radius: int = 2) -> np.ndarray:
    """Running median over the finite entries of a [T] series (NaN stays where no entry is near)."""
    out = np.full_like(z, np.nan)
    for i in range(len(z)):
        w = z[max(0, i - radius):i + radius + 1]
        w = w[np.isfinite(w)]
        if w.size:
            out[i] = np.median(w)
    return out


def _fill_gaps(z: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """[T] series with its NaN entries interpolated linearly in time between the finite ones
    (held at the ends); `fallback` where no entry is finite."""
    ok = np.isfinite(z)
    if not ok.any():
        return fallback
    t = np.arange(len(z))
    return np.interp(t, t[ok], z[ok])


def object_depths(masks: np.ndarray, inst: int, ground: np.ndarray, cameras: Sequence[Camera],
                  size: ObjectSize | None = None, lifted_ratio: float = 1.35,
                  contact_percentile: float = 10.0, lift_rows: int = 8,
                  own_lift_ratio: float | None = None) -> np.ndarray:
    """[T] camera depth of one object per frame (NaN where neither cue says anything): its ground
    contact (`contact_depth`) and, with its real `size`, the depth at which that height covers
    its mask's rows (`size_depth`, a running median over 5 frames against mask noise). Swimmers
    and flyers take the size depth; others the contact, unless they touch no ground or the contact is
    `lifted_ratio` times farther than the size says (off the ground there: the ground seen just
    under a thing in the air lies behind it; only for a mask of at least `lift_rows` rows, where
    a pixel of mask error moves the size depth by little). A swimmer's or flyer's frames without a
    size depth take it interpolated from its other frames (`_fill_gaps`), not the contact.

    With `own_lift_ratio` (and a `size`: a planned object), the object is first measured
    against itself: its contact depth times its mask's pixel height (`pixel_rows`) stays the same
    while it stands on the ground, wherever it goes; in a frame where that product is
    `own_lift_ratio` times its value on the ground (the 5th percentile over the frames: a
    bouncing ball touches the ground in a tenth of them), the contact lies behind it (the ball in
    the air), and its depth is that value over its rows there. The category's size then only
    fills frames without a contact (it is a type's size, not this object's: a real-asset car
    about a third taller than the category's took its size depth, 25% too near, in 40 of 49
    frames)."""
    t = len(masks)
    contact = np.full(t, np.nan)
    by_size = np.full(t, np.nan)
    rows = np.full(t, np.nan)       # pixel height where the whole object is seen
    tall = np.zeros(t, bool)        # enough rows that the size depth can overrule a contact
    for i in range(t):
        sel = masks[i] == inst
        if not sel.any():
            continue
        others = (masks[i] > SETTING_ID) & ~sel          # an object in front hides the contact
        contact[i] = contact_depth(sel, ground[i], np.nan, blocked=others,
                                   percentile=contact_percentile)
        if size is not None:
            z = size_depth(sel, cameras[i], size, blocked=others)
            by_size[i] = np.nan if z is None else z
            n = pixel_rows(sel, lift_rows, blocked=others)
            rows[i] = np.nan if n is None else n
            tall[i] = np.count_nonzero(sel.any(axis=1)) >= lift_rows
    if size is None:
        return contact
    judged = False              # whether the object's own scale said where it is off the ground
    if own_lift_ratio is not None:
        contact, judged = _lifted_by_own_scale(contact, rows, own_lift_ratio)
    by_size = _median_filter(by_size)
    if size.mobility in ("swim", "air"):
        # no ground under a swimmer or a flyer: where its size says nothing (another object
        # beside it), its depth goes on smoothly from the frames where it does
        return np.where(np.isfinite(by_size), by_size, _fill_gaps(by_size, contact))
    off = ~judged & tall & (contact > lifted_ratio * by_size)
    lifted = np.isfinite(by_size) & (~np.isfinite(contact) | off)
    return np.where(lifted, by_size, contact)
