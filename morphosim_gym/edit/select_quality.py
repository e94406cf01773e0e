"""How well a selection covers its object in pictures: rendered selection against 2D masks.

What a user gets from "remove the car" is the pixels that change. So a selection is measured
where it is seen: from each given camera, the selected Gaussians' share of every pixel's
colour is rendered (the selection as a one-channel feature, blended like colour, so occluded
Gaussians count only as far as they show); a pixel is selected when at least half its colour
comes from the selection. Precision and recall are pooled over the views against the given
masks (for a generated clip, its ground-truth masks: evidence the fit never saw when its
priors were estimated).

Unlike comparing the selection with the Gaussians' own object ids, this does not depend on how
the reconstruction labelled its Gaussians, so it also measures a scene fitted to estimated masks.

A generated clip's masks follow the renderer's instance rule (the single Gaussian of largest
weight, if it outweighs what shows through), not this one: along a small object's outline the
object can give more than half a pixel's colour while one large ground Gaussian weighs most, so
even the generator's own scene with its object's exact Gaussians scores below 1 against them
(the bus at 128 px: precision 0.94). `share_masks` applies the selection's rule to the
generator's scene instead: masks of the same definition, which the exact selection meets.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..render import render
from ..scene import Camera, Scene4D
from .select import _with_features

__all__ = ["rendered_selection", "selection_against_masks", "share_masks"]


def rendered_selection(scene: Scene4D, mask: np.ndarray, camera: Camera, t: float, backend: str = "cpu") -> np.ndarray:
    """[H, W] share (0..1) of each pixel's colour that comes from the Gaussians in `mask` at time t."""
    mask = np.asarray(mask, bool)
    if mask.shape != (len(scene.gaussians),):
        raise ValueError(f"Expected a selection mask of shape ({len(scene.gaussians)},), found {mask.shape}")
    state = scene.at(t)
    out = render(_with_features(state, mask[:, None].astype(np.float32)), camera, backend=backend, features=True,
                 background=scene.background)
    return np.asarray(out.features[..., 0], np.float64)


def selection_against_masks(scene: Scene4D, mask: np.ndarray, cameras: Sequence[Camera], times: Sequence[float],
                            truth: np.ndarray, backend: str = "cpu") -> dict[str, float]:
    """Pixel precision and recall of a selection against [V, H, W] bool masks seen by `cameras` at `times`.

    Pooled over the views: precision = |selected & truth| / |selected|, recall = |selected & truth| /
    |truth| (1.0 where the denominator is empty)."""
    truth = np.asarray(truth)
    if truth.ndim != 3 or truth.dtype != bool:
        raise ValueError(f"Expected truth masks as [views, H, W] bool, found {truth.dtype} {truth.shape}")
    if not len(cameras) == len(times) == len(truth):
        raise ValueError(f"Expected one camera and one time per mask, found {len(cameras)} cameras, "
                         f"{len(times)} times, {len(truth)} masks")
    tp = sel = pos = 0
    for cam, t, gt in zip(cameras, times, truth):
        if gt.shape != (cam.height, cam.width):
            raise ValueError(f"Expected masks of {cam.height}x{cam.width} (the camera's size), found {gt.shape}")
        picked = rendered_selection(scene, mask, cam, float(t), backend) >= 0.5
        tp += int((picked & gt).sum())
        sel += int(picked.sum())
        pos += int(gt.sum())
    return {"precision": tp / sel if sel else 1.0, "recall": tp / pos if pos else 1.0}


def share_masks(scene: Scene4D, object_ids: Sequence[int], cameras: Sequence[Camera], times: Sequence[float],
                backend: str = "cpu") -> np.ndarray:
    """[V, H, W] bool: the pixels at least half of whose colour comes from the Gaussians of
    `object_ids` (the selection's rule, applied to the Gaussians of those objects: for a generated
    clip, its ground-truth scene), seen by `cameras` at `times`."""
    if len(cameras) != len(times):
        raise ValueError(f"Expected one time per camera, found {len(cameras)} cameras and {len(times)} times")
    mask = np.isin(np.asarray(scene.gaussians.object_ids), np.asarray(list(object_ids), np.int64))
    if not mask.any():
        raise ValueError(f"Expected object ids of the scene's Gaussians, found none of {list(object_ids)}")
    return np.stack([rendered_selection(scene, mask, cam, float(t), backend) >= 0.5 for cam, t in zip(cameras, times)])
