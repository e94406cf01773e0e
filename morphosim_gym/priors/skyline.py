"""Where the setting ends and the sky begins, read from the pixels (one frame at a time).

The ground plane's horizon says where the ground could be seen, not where it is: a generated
setting's ground ends short of the horizon and its sky panorama (trees, a room, clouds) shows
below it, and hills or a wall that belong to the setting rise above it. `sky_region` draws one
boundary row per column (a seam): above it the sky, below it the setting. Each side is a colour
model (a histogram over CIE Lab bins, smoothed by one bin, of the frame blurred a little against
texture), seeded from where each side surely is (the sky: the image's top rows where they lie
above the horizon; the setting: the nearest rows of ground), fitted again from the seam's two
sides a few times. The seam minimises the two models' negative log-likelihoods summed over each
column's two parts plus `smooth` per row that it steps between neighbouring columns (dynamic
programming). Objects' pixels count for neither side. Where the top rows show no sky (the
camera looks down at the ground) or the two fitted models barely differ (Bhattacharyya
distance under `min_separation`: an overcast sky over snow), colour cannot tell and
`sky_region` says so (None): the caller keeps the horizon.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..metrics.image import rgb_to_lab

__all__ = ["horizon_rows", "sky_region", "sky_seam"]

def horizon_rows(below: np.ndarray) -> np.ndarray:
    """[W] int: per column, the number of rows above the first one where `below` [H, W] (the
    ground plane is seen) holds; H where it never does."""
    h = below.shape[0]
    any_ = below.any(axis=0)
    return np.where(any_, np.argmax(below, axis=0), h).astype(np.int64)


def _lab(frame: np.ndarray) -> np.ndarray:
    """[H, W, 3] float32 CIE Lab of the frame blurred a little against texture."""
    f = np.asarray(frame)
    f = f.astype(np.float32) / 255.0 if f.dtype == np.uint8 else f.astype(np.float32)
    return rgb_to_lab(cv2.GaussianBlur(np.ascontiguousarray(f), (3, 3), 0)).astype(np.float32)


_BINS = 16
_LO = np.array([0.0, -64.0, -64.0], np.float32)
_HI = np.array([100.0, 64.0, 64.0], np.float32)


def _bins(feat: np.ndarray) -> np.ndarray:
    q = np.clip(((feat - _LO) / (_HI - _LO) * _BINS).astype(np.int64), 0, _BINS - 1)
    return (q[..., 0] * _BINS + q[..., 1]) * _BINS + q[..., 2]


def _model(idx: np.ndarray) -> np.ndarray:
    """A colour histogram [B^3] of the binned pixels `idx`, blurred by one bin, normalised."""
    hist = np.bincount(idx, minlength=_BINS ** 3).astype(np.float32).reshape(_BINS, _BINS, _BINS)
    for ax in range(3):
        hist = 0.5 * hist + 0.25 * (np.roll(hist, 1, ax) + np.roll(hist, -1, ax))
    hist = hist.reshape(-1) + 0.01
    return hist / hist.sum()


def _nll(idx: np.ndarray, model: np.ndarray) -> np.ndarray:
    return -np.log(model[idx])


def _bhattacharyya(a: np.ndarray, b: np.ndarray) -> float:
    return float(-np.log(np.sum(np.sqrt(a * b))))


def _seam(sky_cost: np.ndarray, set_cost: np.ndarray, cap: np.ndarray, smooth: float) -> np.ndarray:
    """[W] boundary rows b in 0..cap[x] minimising the column costs plus `smooth` |b(x) - b(x-1)|."""
    h, w = sky_cost.shape
    top = np.vstack([np.zeros((1, w)), np.cumsum(sky_cost, axis=0)])              # [H+1, W] rows above b
    bottom = np.vstack([np.cumsum(set_cost[::-1], axis=0)[::-1], np.zeros((1, w))])  # rows from b down
    col = top + bottom
    rows = np.arange(h + 1)
    col[rows[:, None] > cap[None, :]] = np.inf
    step = smooth * np.abs(rows[:, None] - rows[None, :])                          # [b, b']
    acc = col[:, 0].copy()
    back = np.zeros((w, h + 1), np.int64)
    for x in range(1, w):
        tot = acc[None, :] + step                                                   # [b, b']
        back[x] = np.argmin(tot, axis=1)
        acc = tot[rows, back[x]] + col[:, x]
    out = np.zeros(w, np.int64)
    out[-1] = int(np.argmin(acc))
    for x in range(w - 1, 0, -1):
        out[x - 1] = back[x][out[x]]
    return out


def sky_region(frame: np.ndarray, objects: np.ndarray, horizon: np.ndarray, **kwargs: float) -> np.ndarray | None:
    """[H, W] bool: the sky of one frame [H, W, 3] (see the module docstring), or None where
    colour cannot tell: the rows above `sky_seam`'s boundary, less the objects' pixels."""
    seam = sky_seam(frame, objects, horizon, **kwargs)
    if seam is None:
        return None
    return (np.arange(objects.shape[0])[:, None] < seam[None, :]) & ~objects


def sky_seam(frame: np.ndarray, objects: np.ndarray, horizon: np.ndarray, seed_rows: float = 0.1,
             ground_rows: float = 0.6, smooth: float = 3.0, iters: int = 3, min_separation: float = 0.5,
             min_seed: int = 32) -> np.ndarray | None:
    """[W] int: per column of one frame [H, W, 3], the first row of the setting below the sky (see
    the module docstring), or None where colour cannot tell. `objects` [H, W] bool marks the
    objects' pixels (never sky), `horizon` [W] the rows above the ground plane's horizon per
    column (`horizon_rows`). Seeds: the sky from the top `seed_rows` of the image above the
    horizon, the setting from the lowest `ground_rows` of the rows below it (which the seam never
    enters); each needs `min_seed` pixels."""
    h, w = objects.shape
    if frame.shape[:2] != (h, w) or horizon.shape != (w,):
        raise ValueError(f"Expected a frame [H, W, 3], objects [H, W] and horizon [W] of one size, found "
                         f"{frame.shape}, {objects.shape}, {horizon.shape}")
    feat = _bins(_lab(frame))
    rows = np.arange(h)[:, None]
    free = ~objects
    hz = np.clip(horizon, 0, h)
    ground_top = hz + np.ceil((1.0 - ground_rows) * (h - hz)).astype(np.int64)          # [W]
    setting_seed = free & (rows >= ground_top[None, :])
    sky_seed = free & (rows < max(1, int(round(seed_rows * h)))) & (rows < hz[None, :])
    if sky_seed.sum() < min_seed or setting_seed.sum() < min_seed:
        return None
    cap = np.minimum(ground_top, h)                     # the seam stays above the setting's seed
    sky_m, set_m = _model(feat[sky_seed]), _model(feat[setting_seed])
    b = np.zeros(w, np.int64)
    for _ in range(iters):
        c_sky = np.where(free, _nll(feat, sky_m), 0.0)
        c_set = np.where(free, _nll(feat, set_m), 0.0)
        b = _seam(c_sky, c_set, cap, smooth)
        # refit from the seam's sides, two rows clear of it
        sky_px = free & (rows < b[None, :] - 2)
        set_px = free & (rows >= b[None, :] + 2)
        if sky_px.sum() < min_seed or set_px.sum() < min_seed:
            break
        sky_m, set_m = _model(feat[sky_px]), _model(feat[set_px])
    if _bhattacharyya(sky_m, set_m) < min_separation:
        return None
    return b
