"""An object's mask trimmed to the pixels the object covers most of.

Masks found by motion or colour take whole every pixel the object touches: along its outline a
pixel mixes the object's colour and the setting's behind it, and a mask 1 px too fat takes a rim
of setting with the object (an edit of the object then recolours that rim too). A pixel on the
rim belongs to the object when it is more the object's colour than the setting's: with `fg` the
mean colour of the object's pixels a pixel inside the rim and `bg` the mean colour of the setting's
pixels a pixel outside it, both within a `window` around it, the pixel's coverage is its colour
projected onto the line from `bg` to `fg` (0 at `bg`, 1 at `fg`); under one half it goes to the
setting. Where the two colours differ by less than `min_contrast` the pixel says nothing and
stays. The same holds against the sky (`backdrops`): a bird's rim against the sky mixes the two
the same way, and the sky, which no object covers, keeps the pixels the bird covers less than half of.
"""

from __future__ import annotations

from collections.abc import Iterable

import cv2
import numpy as np

__all__ = ["trim_rims"]

_K3 = np.ones((3, 3), np.uint8)


def _local_mean(frame: np.ndarray, mask: np.ndarray, window: int) -> tuple[np.ndarray, np.ndarray]:
    """([H, W, 3] mean colour of the `mask`ed pixels within `window` of each pixel, [H, W] their count)."""
    m = mask.astype(np.float32)
    n = cv2.boxFilter(m, -1, (window, window), normalize=False, borderType=cv2.BORDER_CONSTANT)
    s = np.stack([cv2.boxFilter(frame[..., c] * m, -1, (window, window), normalize=False,
                                borderType=cv2.BORDER_CONSTANT) for c in range(3)], -1)
    return s / np.maximum(n, 1e-6)[..., None], n


def trim_rims(frame: np.ndarray, ids: np.ndarray, objects: Iterable[int], setting_id: int = 0, window: int = 7,
              min_contrast: float = 20.0, backdrops: Iterable[int] = ()) -> np.ndarray:
    """[H, W] ids with each of `objects`' rim pixels against the setting (`setting_id`), then
    against each of `backdrops` (other ids behind every object: the sky's), that it covers less
    than half of given to that backdrop (see the module docstring). `frame` [H, W, 3] (uint8 or
    float in 0-255 units); the input `ids` is not changed."""
    if frame.shape[:2] != ids.shape:
        raise ValueError(f"Expected a frame [H, W, 3] and ids [H, W] of one size, found {frame.shape}, {ids.shape}")
    objects = list(objects)
    behind = [setting_id] + [b for b in backdrops if b != setting_id]
    if set(behind) & set(objects):
        raise ValueError(f"Expected backdrops that are not objects, found {sorted(set(behind) & set(objects))}")
    f = np.asarray(frame, np.float32)
    out = ids.copy()
    backs = {b: ids == b for b in behind}
    nears = {b: cv2.dilate(m.astype(np.uint8), _K3).astype(bool) for b, m in backs.items()}
    for k in objects:                  # objects only give up their own pixels: their order does not matter
        obj = (ids == k).astype(np.uint8)
        core = cv2.erode(obj, _K3).astype(bool)
        grown = cv2.dilate(obj, _K3).astype(bool)
        fg = None
        for b in behind:               # the setting first, then the other backdrops
            rim = (out == k) & ~core & nears[b]
            if not rim.any():
                continue
            if fg is None:
                fg, n_fg = _local_mean(f, core, window)
            bg, n_bg = _local_mean(f, backs[b] & ~grown, window)
            d = fg - bg
            dd = (d * d).sum(-1)
            cover = ((f - bg) * d).sum(-1) / np.maximum(dd, 1e-6)
            drop = rim & (n_fg > 0) & (n_bg > 0) & (dd >= min_contrast ** 2) & (cover < 0.5)
            out[drop] = b
    return out
