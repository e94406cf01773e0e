"""An object's spin about the line of sight, read from its own pixels.

Optical flow over a small textured object mostly sees its translation: on a rolling ball about
35 px across (128 px frames) the clip's DIS tracks turn it by about a tenth of its real turn.
Aligning the object's pixels in consecutive frames with a Euclidean warp (ECC, inside its mask)
reads the in-image rotation directly; chained from a reference frame, those angles become 3D
rotations about the ray from the camera to the object, pivoting on the object's centre.

Only the clip's frames, masks, depth prior and cameras are read (never `clip.ground_truth`).
"""

from __future__ import annotations

import cv2
import numpy as np

from ..scene import GeneratedClip

__all__ = ["spin_angles", "spin_poses", "texture_agreement"]


def _inside(mask: np.ndarray, min_pixels: int) -> bool:
    """Enough pixels, away from the image border (a mask cut by the border changes shape)."""
    return bool(mask.sum() >= min_pixels and not (mask[0].any() or mask[-1].any() or mask[:, 0].any()
                                                    or mask[:, -1].any()))


def spin_angles(clip: GeneratedClip, instance: int, min_pixels: int = 24, iterations: int = 100,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """In-image rotation (radians, image x towards image y) of an instance from each frame k to
    k + 1 ([T - 1]), and which pairs were measured ([T - 1] bool): ECC with a Euclidean warp of
    frame k's grey pixels inside the instance's mask onto frame k + 1, started from the mask
    centroids' shift, and ECC's correlation coefficient of each pair ([T - 1], 0 where not
    measured). Pairs where the mask is small or touches the border, or ECC does not converge,
    are not measured (angle 0)."""
    T = clip.num_frames
    angles = np.zeros(max(T - 1, 0))
    ok = np.zeros(max(T - 1, 0), bool)
    corr = np.zeros(max(T - 1, 0))
    if clip.masks is None or T < 2:
        return angles, ok, corr
    gray = [cv2.cvtColor(np.ascontiguousarray(f), cv2.COLOR_RGB2GRAY).astype(np.float32) for f in clip.frames]
    kernel = np.ones((3, 3), np.uint8)
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, int(iterations), 1e-5)
    for k in range(T - 1):
        m0, m1 = clip.masks[k] == instance, clip.masks[k + 1] == instance
        if not (_inside(m0, min_pixels) and _inside(m1, min_pixels)):
            continue
        inner = cv2.erode(m0.astype(np.uint8), kernel)
        if inner.sum() < min_pixels // 2:
            continue
        warp = np.eye(2, 3, dtype=np.float32)
        warp[:, 2] = np.argwhere(m1).mean(0)[::-1] - np.argwhere(m0).mean(0)[::-1]
        try:
            rho, warp = cv2.findTransformECC(gray[k], gray[k + 1], warp, cv2.MOTION_EUCLIDEAN, criteria, inner, 3)
        except cv2.error:           # no convergence (a uniform patch): not measured
            continue
        angles[k], ok[k], corr[k] = float(np.arctan2(warp[1, 0], warp[0, 0])), True, float(rho)
    return angles, ok, corr


def _about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of `angle` radians about a unit `axis` (right hand)."""
    rot, _ = cv2.Rodrigues(np.asarray(axis, np.float64).reshape(3) * float(angle))
    return rot


def spin_poses(clip: GeneratedClip, reference: int, centre: np.ndarray, trans: np.ndarray, angles: np.ndarray,
               ) -> tuple[np.ndarray, np.ndarray]:
    """Rigid poses (rotations [T, 3, 3], translations [T, 3], reference-frame world points to each
    frame) of an object whose centre, at world `centre` in the reference frame, moves by `trans`
    [T, 3] and which turns by `angles` [T - 1] (`spin_angles`) about the ray from frame k's camera
    to its centre between frames k and k + 1."""
    T = clip.num_frames
    rots = np.tile(np.eye(3), (T, 1, 1))
    c = np.asarray(centre, np.float64)

    def ray(k: int) -> np.ndarray:
        d = c + trans[k] - clip.cameras[k].position
        n = np.linalg.norm(d)
        return d / n if n > 0 else clip.cameras[k].camera_to_world[:3, 2]

    for k in range(reference, T - 1):                       # forward from the reference
        rots[k + 1] = _about(ray(k), angles[k]) @ rots[k]
    for k in range(reference - 1, -1, -1):                  # backward: undo the turn k -> k + 1
        rots[k] = _about(ray(k), -angles[k]) @ rots[k + 1]
    # the centre follows its own path: x_t = R_t (x - c) + c + trans_t
    return rots, c + trans - np.einsum("tij,j->ti", rots, c)


def texture_agreement(clip: GeneratedClip, instance: int, points: np.ndarray, colors: np.ndarray,
                      rots: np.ndarray, trans: np.ndarray, frames: np.ndarray) -> float:
    """How well the poses carry an instance's texture: the mean, over the given frames, of the
    correlation between the grey values of its reference points [n, 3] (colours [n, 3] in 0..1)
    and of the pixels the poses land them on, counting the points that land on the instance's
    mask there (`_coverage` judges the landing itself). Mean colours do not count (a red ball
    turned the wrong way is still red): near 1 when the pattern lines up, near 0 for a uniform
    object whatever the poses; 0 where fewer than 8 points land."""
    grey = colors @ _GREY
    scores = []
    for t in frames:
        uv, z = clip.cameras[t].project(points @ rots[t].T + trans[t])
        c, r = np.floor(uv[:, 0]).astype(int), np.floor(uv[:, 1]).astype(int)
        ok = (z > 0) & (c >= 0) & (c < clip.width) & (r >= 0) & (r < clip.height)
        hit = np.zeros(len(points), bool)
        hit[ok] = clip.masks[t][r[ok], c[ok]] == instance
        if hit.sum() < 8:
            scores.append(0.0)
            continue
        a = grey[hit] - grey[hit].mean()
        b = clip.frames[t][r[hit], c[hit]].astype(np.float64) / 255.0 @ _GREY
        b = b - b.mean()
        den = np.sqrt((a * a).sum() * (b * b).sum())
        scores.append(float((a * b).sum() / den) if den > 1e-12 else 0.0)
    return float(np.mean(scores)) if scores else 0.0


_GREY = np.array([0.299, 0.587, 0.114])
