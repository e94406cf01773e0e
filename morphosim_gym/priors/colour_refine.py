"""Instance masks corrected by colour: each object's own colours, learnt from its whole clip, against
the setting's colour row by row.

The motion and box tests that make the first masks (`masks.label_regions`, `masks.static_regions`)
go wrong in known ways: a moving camera's parallax hides slow objects, so an object is found
only inside its planned box, which the generated object need not fill (a cube set on a plate
stands above its planned box, and its top is taken for the plate); a box-shaped region at the
start of a clip takes grass with the sheep. What an object looks like changes little through a
clip, so:

1. per frame and row, the setting's colour: the median of the setting's pixels in that row (a
   setting changes colour with distance, row by row), and how far setting pixels stray from it;
   a pixel farther than that allows "stands out" from the setting;
2. per object, a few colour centres (k-means in CIE Lab) of the eroded cores of its first masks
   that stand out from the setting, from the frames where it touches no other object, each frame
   weighted the same;
3. near each object (its mask grown by a margin, a few rounds) each pixel goes to whichever is
   nearest in colour: the setting, or an object whose neighbourhood holds it. A setting pixel
   joins an object only if it stands out, is nearer the object's colours than those of the
   setting around the object (leaves strewn all over the ground) and, for a moving object under
   a still camera, was not seen unchanged by the background model (lane markings beside a white
   bus); one object's pixel goes to another only when the colours say so clearly (two white
   sheep keep their split); an object's pixel goes back to the setting when it does not stand
   out and is nearer the setting, unless the object encloses it (a bus's dark windows).

Specks are dropped; pixels no rule reaches keep their first label.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["colour_centres", "refine_by_colour", "setting_rows"]


def _lab(frame: np.ndarray) -> np.ndarray:
    """[H, W, 3] uint8 RGB -> float32 CIE Lab (L in 0..100)."""
    return cv2.cvtColor(np.ascontiguousarray(frame).astype(np.float32) / 255.0, cv2.COLOR_RGB2LAB)


def colour_centres(samples: np.ndarray, weights: np.ndarray, k: int = 3, seed: int = 0) -> np.ndarray:
    """[m, 3] weighted k-means centres of [n, 3] colour samples (deterministic: seeded draws,
    then Lloyd iterations); fewer centres when there are few samples."""
    n = len(samples)
    k = max(1, min(k, n // 8))
    rng = np.random.default_rng(seed)
    p = weights / weights.sum()
    centres = samples[rng.choice(n, size=k, replace=False, p=p)].astype(np.float64)
    for _ in range(12):
        d = ((samples[:, None, :] - centres[None]) ** 2).sum(-1)
        nearest = np.argmin(d, axis=1)
        for c in range(k):
            w = weights[nearest == c]
            if w.sum() > 0:
                centres[c] = (samples[nearest == c] * w[:, None]).sum(0) / w.sum()
    return centres.astype(np.float32)


def setting_rows(lab: np.ndarray, setting: np.ndarray, min_pixels: int = 4) -> tuple[np.ndarray, float] | None:
    """([H, 3] the setting's median colour per row, its spread: 1.4826 x the median distance of
    setting pixels to their row's colour), rows without enough setting taking the nearest row's;
    None when no row has enough setting."""
    h, w = setting.shape
    ref = np.full((h, 3), np.nan, np.float32)
    for r in range(h):
        if setting[r].sum() >= max(min_pixels, w // 8):
            ref[r] = np.median(lab[r][setting[r]], axis=0)
    rows = np.flatnonzero(np.isfinite(ref[:, 0]))
    if len(rows) == 0:
        return None
    for c in range(3):
        ref[:, c] = np.interp(np.arange(h), rows, ref[rows, c])
    dist = np.linalg.norm(lab - ref[:, None], axis=-1)
    return ref, float(np.median(dist[setting])) * 1.4826


def _object_models(labs: Sequence[np.ndarray], odd: Sequence[np.ndarray | None], ids: np.ndarray, setting_id: int,
                   objects: Sequence[int], k: int, samples_per_frame: int, seed: int) -> dict[int, np.ndarray]:
    """Colour centres of each object from the eroded cores of its masks, each frame weighted 1:
    from the frames where it touches no other object (its mask cannot hold the other's pixels
    there), if any, and from its pixels that stand out from the setting (`odd`: a box-shaped
    mask's grass is not the sheep's colour), unless fewer than a quarter of its pixels do (an
    object the setting's colour)."""
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (3, 3))
    near = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
    rng = np.random.default_rng(seed)
    models = {}
    for o in objects:
        alone = [i for i in range(len(labs)) if (ids[i] == o).any() and not np.any(
            cv2.dilate((ids[i] == o).astype(np.uint8), near).astype(bool) & (ids[i] > setting_id) & (ids[i] != o))]
        cores = {}
        for i in alone or range(len(labs)):
            m = ids[i] == o
            core = cv2.erode(m.astype(np.uint8), kernel).astype(bool)
            cores[i] = core if core.sum() >= 4 else m
        standing = [c & odd[i] for i, c in cores.items() if odd[i] is not None]
        if sum(int(c.sum()) for c in standing) >= 0.25 * sum(int(c.sum()) for c in cores.values()):
            cores = {i: c & odd[i] for i, c in cores.items() if odd[i] is not None}
        pts, wts = [], []
        for i, core in cores.items():
            px = labs[i][core]
            if len(px) == 0:
                continue
            if len(px) > samples_per_frame:
                px = px[rng.choice(len(px), samples_per_frame, replace=False)]
            pts.append(px)
            wts.append(np.full(len(px), 1.0 / len(px)))
        if pts and sum(len(p) for p in pts) >= 16:
            models[o] = colour_centres(np.concatenate(pts), np.concatenate(wts), k, seed)
    return models


def refine_by_colour(frames: np.ndarray, ids: np.ndarray, setting_id: int = 0, margin: float = 0.25,
                     min_margin: int = 2, centres: int = 3, odd_sigmas: float = 3.0, min_odd: float = 8.0,
                     samples_per_frame: int = 400, min_area: int = 4, switch: float = 0.5, passes: int = 3,
                     movers: Sequence[int] = (), still: np.ndarray | None = None, distinct: float = 20.0,
                     seed: int = 0) -> np.ndarray:
    """[T, H, W] ids with objects' masks corrected by colour (see the module docstring).

    Args:
        frames: [T, H, W, 3] uint8 RGB.
        ids: [T, H, W] int: `setting_id` the setting, larger ids objects, anything else unknown
            (left alone).
        margin: an object's neighbourhood is its mask grown by this fraction of its size
            (sqrt of its area), at least `min_margin` pixels; up to `passes` rounds a frame (a
            region grows by at most its margin a round).
        centres: colour centres per object.
        odd_sigmas, min_odd: a pixel stands out from the setting when its Lab distance to the
            row's setting colour exceeds max(`min_odd`, `odd_sigmas` x the setting's spread).
        switch, distinct: a pixel of one object goes to another only when its colour is nearer
            the other's by this factor, and only between objects whose colours can be told apart:
            some centre of one lies farther than `distinct` (Lab) from every centre of the other
            (two white sheep keep their split, however their speckles fall).
        movers, still: the ids of moving objects, and [T, H, W] bool the pixels a still camera
            saw unchanged through the clip (its background model's): no moving object takes
            those from the setting (a road's lane markings beside a white bus).
    """
    f = np.asarray(frames)
    out = np.asarray(ids).copy()
    if out.shape != f.shape[:3]:
        raise ValueError(f"Expected ids of shape {f.shape[:3]} (the frames'), found {out.shape}")
    objects = sorted(int(o) for o in np.unique(out) if o > setting_id)
    if not objects:
        return out
    labs = [_lab(fr) for fr in f]
    d_set, odd = [], []
    for i, lab in enumerate(labs):
        rows = setting_rows(lab, out[i] == setting_id)
        if rows is None:
            d_set.append(None)
            odd.append(None)
            continue
        ref, spread = rows
        d_set.append(np.linalg.norm(lab - ref[:, None], axis=-1))
        odd.append(d_set[-1] > max(min_odd, odd_sigmas * spread))
    models = _object_models(labs, odd, out, setting_id, objects, centres, samples_per_frame, seed)
    if not models:
        return out
    movers = set(int(m) for m in movers)
    alike = _alike(models, distinct)
    for i, lab in enumerate(labs):
        if d_set[i] is None:
            continue
        frame = _Frame(lab=lab, d_set=d_set[i], odd=odd[i], d_obj={o: _nearest(lab, c) for o, c in models.items()},
                       held=None if still is None else still[i], alike=alike)
        for _ in range(passes):
            new = _refine_frame(frame, out[i], setting_id, margin, min_margin, switch, movers, min_area)
            if np.array_equal(new, out[i]):
                break
            out[i] = new
    return out


@dataclass
class _Frame:
    """One frame's colour distances, computed once for all rounds."""

    lab: np.ndarray                 # [H, W, 3]
    d_set: np.ndarray               # [H, W] distance to the row's setting colour
    odd: np.ndarray                 # [H, W] bool: stands out from the setting
    d_obj: dict                     # object id -> [H, W] distance to its nearest colour centre
    held: np.ndarray | None         # [H, W] bool: seen unchanged by a still camera
    alike: dict                     # object id -> ids of the objects whose colours are too close to tell apart


def _alike(models: dict[int, np.ndarray], distinct: float) -> dict[int, set[int]]:
    """Per object, the objects whose colour centres all lie within `distinct` of the other's
    (symmetric Hausdorff distance between the centre sets)."""
    out: dict[int, set[int]] = {o: set() for o in models}
    for o, a in models.items():
        for j, b in models.items():
            if j <= o:
                continue
            d = np.sqrt(((a[:, None] - b[None]) ** 2).sum(-1))
            if max(d.min(1).max(), d.min(0).max()) < distinct:
                out[o].add(j)
                out[j].add(o)
    return out


def _nearest(lab: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """[...] Lab distance of each pixel [..., 3] to the nearest of `centres` [k, 3]."""
    return np.sqrt(((lab[..., None, :] - centres) ** 2).sum(-1)).min(-1)


def _refine_frame(fr: _Frame, ids: np.ndarray, setting_id: int, margin: float, min_margin: int, switch: float,
                  movers: set, min_area: int) -> np.ndarray:
    """One round of `refine_by_colour` on one frame."""
    setting = ids == setting_id
    objs = ids > setting_id
    best = np.where(setting, setting_id, -2)                       # -2: no rule decides the pixel
    best_d = np.where(setting, np.where(fr.odd, fr.d_set, 0.0), np.inf)
    own_d = np.full(ids.shape, np.inf)                             # an object pixel's distance to its own colours
    for o, d in fr.d_obj.items():
        m = ids == o
        own_d[m] = d[m]
    zone_any = np.zeros(ids.shape, bool)
    for o, d_o in fr.d_obj.items():
        m = ids == o
        area = int(m.sum())
        if area == 0:
            continue
        r = max(min_margin, int(round(margin * np.sqrt(area))))
        kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
        grown = cv2.dilate(m.astype(np.uint8), kernel).astype(bool)
        zone = grown & (setting | objs)
        # a setting pixel joins only if it stands out from the setting, is nearer the object's
        # colours than those of the setting around the object, and (a moving object, still
        # camera) was not seen unchanged; another object's pixel only when the colours say so
        # clearly; the object's own pixel stays unless it looks like the setting (below)
        closed = setting & ~fr.odd
        if fr.held is not None and o in movers:
            closed |= setting & fr.held
        ring = cv2.dilate(grown.astype(np.uint8), kernel).astype(bool) & ~grown & setting
        ring &= d_o > 2.0 * np.median(d_o[m])          # not the object's own colours left unlabelled
        if ring.sum() >= 16:
            local = colour_centres(fr.lab[ring], np.ones(int(ring.sum())), 3)
            near_setting = zone & setting
            closed[near_setting] |= _nearest(fr.lab[near_setting], local) <= d_o[near_setting]
        closed |= objs & (ids != o) & ((d_o >= switch * own_d) | np.isin(ids, sorted(fr.alike.get(o, ()))))
        d = np.where(zone & ~closed, d_o, np.inf)
        take = d < best_d
        best = np.where(take, o, best)
        best_d = np.where(take, d, best_d)
        zone_any |= zone
    # object pixels that look like the setting, and nearer it than any object's colours, go back to it
    back = objs & zone_any & ~fr.odd & (fr.d_set < best_d)
    best = np.where(back, setting_id, best)
    new = ids.copy()
    decided = zone_any & (best != -2)
    new[decided] = best[decided]
    return _keep_solid(_despeckle(new, ids, list(fr.d_obj), min_area), ids, list(fr.d_obj), setting_id)


def _despeckle(new: np.ndarray, old: np.ndarray, objects: list[int], min_area: int) -> np.ndarray:
    """Components of an object's new mask smaller than `min_area` go back to their old labels."""
    out = new.copy()
    for o in objects:
        n, lab, stats, _ = cv2.connectedComponentsWithStats((new == o).astype(np.uint8), connectivity=8)
        for c in np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] < min_area) + 1:
            comp = lab == c
            out[comp] = old[comp]
    return out


def _keep_solid(new: np.ndarray, old: np.ndarray, objects: list[int], setting_id: int) -> np.ndarray:
    """Pixels an object had that this round gave to the setting, where the object now encloses
    them, stay the object's (a bus's dark windows on a dark road)."""
    out = new.copy()
    for o in objects:
        m = (new == o).astype(np.uint8)
        if not m.any():
            continue
        flood = np.pad(m, 1).copy()
        cv2.floodFill(flood, None, (0, 0), 1)
        holes = (flood[1:-1, 1:-1] == 0) & (new == setting_id) & (old == o)
        out[holes] = o
    return out
