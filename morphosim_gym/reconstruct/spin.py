"""An object's spin about the line of sight, read from its own pixels.

Optical flow over a small textured object mostly sees its translation: on a rolling ball about
35 px across (128 px frames) the clip's DIS tracks turn it by about a tenth of its real turn.
Aligning the object's pixels in consecutive frames with a Euclidean warp (ECC, inside its mask)
reads the in-image rotation directly; chained from a reference frame, those angles become 3D
rotations about the ray from the camera to the object, pivoting on the object's centre.

Only the clip's frames, masks and cameras are read (never `clip.ground_truth`).
"""

from __future__ import annotations

import cv2
import numpy as np

from ..scene import GeneratedClip
from .lifting import off_border

__all__ = ["WORLD_UP", "spin_angles", "spin_poses"]

#: the world's up direction (the ground is a plane z = const, cameras stand upright about z)
WORLD_UP = np.array([0.0, 0.0, 1.0])


def spin_angles(clip: GeneratedClip, instance: int, min_pixels: int = 24, iterations: int = 100,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """In-image rotation (radians, image x towards image y) of an instance from each frame k to
    k + 1 ([T - 1]), and which pairs were measured ([T - 1] bool): ECC with a Euclidean warp of
    frame k's grey pixels inside the instance's mask onto frame k + 1, started from the mask
    centroids' shift; ECC's correlation coefficient of each pair ([T - 1], 0 where not
    measured); and that of the same alignment without rotation (a translation warp; [T - 1]),
    which tells a real turn (the rotation aligns the pixels far better) from a warp that found
    a rotation to trade off something else (still background seen through a mug's handle).
    Pairs where the mask is small or touches the border, or either ECC does not converge, are
    not measured (angle 0)."""
    T = clip.num_frames
    angles = np.zeros(max(T - 1, 0))
    ok = np.zeros(max(T - 1, 0), bool)
    corr = np.zeros(max(T - 1, 0))
    still = np.zeros(max(T - 1, 0))
    if clip.masks is None or T < 2:
        return angles, ok, corr, still
    gray = [cv2.cvtColor(np.ascontiguousarray(f), cv2.COLOR_RGB2GRAY).astype(np.float32) for f in clip.frames]
    kernel = np.ones((3, 3), np.uint8)
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, int(iterations), 1e-5)
    for k in range(T - 1):
        m0, m1 = clip.masks[k] == instance, clip.masks[k + 1] == instance
        if not all(m.sum() >= min_pixels and off_border(m) for m in (m0, m1)):
            continue
        inner = cv2.erode(m0.astype(np.uint8), kernel)
        if inner.sum() < min_pixels // 2:
            continue
        start = np.eye(2, 3, dtype=np.float32)
        start[:, 2] = np.argwhere(m1).mean(0)[::-1] - np.argwhere(m0).mean(0)[::-1]
        try:
            rho, warp = cv2.findTransformECC(gray[k], gray[k + 1], start.copy(), cv2.MOTION_EUCLIDEAN, criteria,
                                             inner, 3)
            rho_t, _ = cv2.findTransformECC(gray[k], gray[k + 1], start.copy(), cv2.MOTION_TRANSLATION, criteria,
                                            inner, 3)
        except cv2.error:           # no convergence (a uniform patch): not measured
            continue
        angles[k], ok[k], corr[k], still[k] = float(np.arctan2(warp[1, 0], warp[0, 0])), True, float(rho), float(rho_t)
    return angles, ok, corr, still


def _about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of `angle` radians about a unit `axis` (right hand)."""
    rot, _ = cv2.Rodrigues(np.asarray(axis, np.float64).reshape(3) * float(angle))
    return rot


def spin_poses(clip: GeneratedClip, reference: int, centre: np.ndarray, trans: np.ndarray, angles: np.ndarray,
               up: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rigid poses (rotations [T, 3, 3], translations [T, 3], reference-frame world points to each
    frame) of an object whose centre, at world `centre` in the reference frame, moves by `trans`
    [T, 3] and which turns by `angles` [T - 1] (`spin_angles`) about the ray from frame k's camera
    to its centre between frames k and k + 1.

    With a world `up` direction the object rolls instead: it turns about the ray's part
    perpendicular to `up` (a ball rolling on the ground turns about a horizontal axis), by the
    image's turn over the cosine between that axis and the ray (the image sees only the turn's
    part along the line of sight); rays within 30 degrees of vertical (up or down) keep the ray
    as the axis."""
    T = clip.num_frames
    rots = np.tile(np.eye(3), (T, 1, 1))
    c = np.asarray(centre, np.float64)
    u = None if up is None else np.asarray(up, np.float64) / np.linalg.norm(up)

    def ray(k: int) -> np.ndarray:
        d = c + trans[k] - clip.cameras[k].position
        n = np.linalg.norm(d)
        return d / n if n > 0 else clip.cameras[k].camera_to_world[:3, 2]

    def turn(k: int, angle: float) -> np.ndarray:
        d = ray(k)
        if u is None:
            return _about(d, angle)
        flat = d - (d @ u) * u
        cos = float(np.linalg.norm(flat))
        if cos < np.cos(np.radians(60.0)):
            return _about(d, angle)
        return _about(flat / cos, angle / cos)

    for k in range(reference, T - 1):                       # forward from the reference
        rots[k + 1] = turn(k, angles[k]) @ rots[k]
    for k in range(reference - 1, -1, -1):                  # backward: undo the turn k -> k + 1
        rots[k] = turn(k, -angles[k]) @ rots[k + 1]
    # the centre follows its own path: x_t = R_t (x - c) + c + trans_t
    return rots, c + trans - np.einsum("tij,j->ti", rots, c)
