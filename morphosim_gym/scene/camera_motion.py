"""Per-frame cameras of a video: a still camera, or a smoothly turning one estimated from the frames.

The camera is taken to turn about its own centre (a pan / tilt, as a handheld or tripod camera
following something), which is what a homography between consecutive frames describes exactly:
`H = K R K^-1`. Corner features are tracked frame to frame (Lucas-Kanade), a homography is fitted
with RANSAC (moving objects are outliers), and the rotation that best turns the inliers' viewing
directions into their matches is solved in closed form (Kabsch / Wahba); the per-pair rotations
are smoothed over time and chained. When the rotation from the first frame straight to a few
later ones (or the chained rotation) stays under `still_deg`, the camera is still and every frame
gets the same camera. Translation of the camera is not estimated (a camera that walks is
approximated by one that turns).

World frame: z up, the ground plane z = 0; the first frame's camera stands `height` metres above
it at the origin, looking along +y, pitched down by `pitch_deg`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .camera import Camera

__all__ = ["CAMERA_MODES", "CameraMotion", "estimate_rotations", "slerp_cameras", "video_cameras"]

CAMERA_MODES = ("auto", "still", "pan")


@dataclass(frozen=True)
class CameraMotion:
    """Camera rotations of a clip relative to its first frame.

    Attributes:
        rotations: [T, 3, 3]; `x_t = R_t x_0` takes frame 0's camera coordinates to frame t's.
        still: True when the camera is taken as still (all rotations the identity).
        max_angle_deg: the largest chained rotation angle (before the still decision).
        inlier_ratio: median share of tracked features the homographies explain (1.0 for a still camera).
        failed_pairs: consecutive pairs with too few features to estimate (their rotation is the identity).
    """

    rotations: np.ndarray
    still: bool
    max_angle_deg: float
    inlier_ratio: float
    failed_pairs: list[int] = field(default_factory=list)


def _project_rotation(m: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(m)
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    return r


def _angle_deg(r: np.ndarray) -> float:
    return math.degrees(math.acos(float(np.clip((np.trace(r) - 1.0) / 2.0, -1.0, 1.0))))


def _pair_rotation(a: np.ndarray, b: np.ndarray, k: np.ndarray, max_corners: int) -> tuple[np.ndarray, float] | None:
    """Rotation taking camera a's coordinates to camera b's, and the RANSAC inlier share; None
    when too few features are tracked."""
    import cv2

    pts = cv2.goodFeaturesToTrack(a, maxCorners=max_corners, qualityLevel=0.01, minDistance=4, blockSize=5)
    if pts is None or len(pts) < 8:
        return None
    nxt, status, _ = cv2.calcOpticalFlowPyrLK(a, b, pts, None, winSize=(15, 15), maxLevel=3)
    ok = status.reshape(-1).astype(bool)
    if ok.sum() < 8:
        return None
    p0, p1 = pts.reshape(-1, 2)[ok], nxt.reshape(-1, 2)[ok]
    h, inliers = cv2.findHomography(p0, p1, cv2.RANSAC, 1.5)
    if h is None:
        return None
    keep = inliers.reshape(-1).astype(bool)
    if keep.sum() < 8:
        return None
    return _kabsch(_bearings(p0[keep], k), _bearings(p1[keep], k)), float(keep.mean())


def _bearings(px: np.ndarray, k: np.ndarray) -> np.ndarray:
    """[N, 3] unit viewing directions of pixels [N, 2] (camera coordinates)."""
    b = np.concatenate([px, np.ones((len(px), 1))], axis=1) @ np.linalg.inv(k).T
    return b / np.linalg.norm(b, axis=1, keepdims=True)


def _kabsch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation R minimising sum |b_i - R a_i|^2 (Wahba's problem, by SVD)."""
    return _project_rotation(b.T @ a)


def _direct_angles(gray: list[np.ndarray], k: np.ndarray, max_corners: int, probes: int = 6) -> list[float] | None:
    """Rotation angles from the first frame straight to a few later ones (no drift from chaining);
    None when one of them cannot be estimated (no overlap: the camera moved far)."""
    out = []
    for i in sorted(set(np.linspace(1, len(gray) - 1, probes).round().astype(int).tolist())):
        got = _pair_rotation(gray[0], gray[i], k, max_corners)
        if got is None:
            return None
        out.append(_angle_deg(got[0]))
    return out


def _smooth(rotvecs: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing of [N, 3] rotation vectors over time (edges replicated)."""
    if sigma <= 0 or len(rotvecs) < 3:
        return rotvecs
    radius = max(1, int(math.ceil(2.5 * sigma)))
    w = np.exp(-0.5 * (np.arange(-radius, radius + 1) / sigma) ** 2)
    w /= w.sum()
    padded = np.pad(rotvecs, ((radius, radius), (0, 0)), mode="edge")
    return np.stack([np.convolve(padded[:, j], w, mode="valid") for j in range(3)], axis=1)


def estimate_rotations(frames: np.ndarray, k: np.ndarray, still_deg: float = 0.5, smooth_sigma: float = 1.0,
                       max_corners: int = 400) -> CameraMotion:
    """The camera rotation of every frame relative to the first (see the module docstring).

    Args:
        frames: [T, H, W, 3] uint8.
        k: [3, 3] intrinsics of the frames.
        still_deg: the camera is still when the chained rotation stays under this angle.
        smooth_sigma: Gaussian smoothing of the per-pair rotations, in frames (0: none).
        max_corners: features tracked per pair.
    """
    import cv2

    f = np.asarray(frames)
    t = len(f)
    gray = [cv2.cvtColor(np.ascontiguousarray(fr), cv2.COLOR_RGB2GRAY) for fr in f]
    direct = _direct_angles(gray, k, max_corners)
    if direct is not None and max(direct) < still_deg:
        return CameraMotion(np.repeat(np.eye(3)[None], t, axis=0), True, max(direct), 1.0, [])
    rotvecs, ratios, failed = [], [], []
    for i in range(t - 1):
        got = _pair_rotation(gray[i], gray[i + 1], k, max_corners)
        if got is None:
            failed.append(i)
            rotvecs.append(np.zeros(3))
            continue
        r, ratio = got
        rotvecs.append(cv2.Rodrigues(r)[0].reshape(3))
        ratios.append(ratio)
    rv = _smooth(np.array(rotvecs, np.float64).reshape(-1, 3), smooth_sigma)
    chain = [np.eye(3)]
    for v in rv:
        chain.append(cv2.Rodrigues(v.reshape(3, 1))[0] @ chain[-1])
    rotations = np.stack(chain)
    max_angle = max(_angle_deg(r) for r in rotations)
    still = max_angle < still_deg
    if still:
        rotations = np.repeat(np.eye(3)[None], t, axis=0)
    return CameraMotion(rotations, still, max_angle, float(np.median(ratios)) if ratios else 0.0, failed)


def _base_camera(width: int, height: int, fov_deg: float, camera_height: float, pitch_deg: float) -> Camera:
    p = math.radians(pitch_deg)
    eye = np.array([0.0, 0.0, camera_height])
    target = eye + np.array([0.0, math.cos(p), -math.sin(p)])
    return Camera.look_at(eye, target, width=width, height=height, fov_y_deg=fov_deg)


def video_cameras(frames: np.ndarray, fov_deg: float = 50.0, mode: str = "auto", camera_height: float = 1.6,
                  pitch_deg: float = 20.0, still_deg: float = 0.5) -> tuple[list[Camera], dict[str, Any]]:
    """One `Camera` per frame and a JSON-friendly summary of how they were found.

    Args:
        frames: [T, H, W, 3] uint8.
        fov_deg: vertical field of view of the frames (degrees).
        mode: "still" (one camera for all), "pan" (estimated rotations, even tiny ones) or "auto"
            (estimated; still when under `still_deg`).
        camera_height: metres above the ground plane.
        pitch_deg: downward tilt of the first frame's camera.
    """
    if mode not in CAMERA_MODES:
        raise ValueError(f"Expected camera mode in {CAMERA_MODES}, found {mode!r}")
    if not (isinstance(fov_deg, (int, float)) and 1.0 <= float(fov_deg) <= 170.0):
        raise ValueError(f"Expected fov_deg (vertical field of view) in [1, 170] degrees, found {fov_deg!r}")
    if not (math.isfinite(camera_height) and camera_height > 0):
        raise ValueError(f"Expected camera_height > 0 metres, found {camera_height!r}")
    if not (math.isfinite(pitch_deg) and -80.0 <= pitch_deg <= 89.0):
        raise ValueError(f"Expected pitch_deg in [-80, 89], found {pitch_deg!r}")
    t, h, w = np.asarray(frames).shape[:3]
    base = _base_camera(w, h, float(fov_deg), float(camera_height), float(pitch_deg))
    info: dict[str, Any] = {"mode": mode, "fov_y_deg": float(fov_deg), "height": float(camera_height),
                            "pitch_deg": float(pitch_deg), "model": "rotation about the camera centre"}
    if mode == "still":
        info["motion"] = "still"
        return [base] * t, info
    motion = estimate_rotations(frames, base.K, still_deg=still_deg if mode == "auto" else 0.0)
    info.update(motion="still" if motion.still else "pan", max_angle_deg=round(motion.max_angle_deg, 3),
                inlier_ratio=round(motion.inlier_ratio, 3), failed_pairs=motion.failed_pairs)
    if motion.still:
        return [base] * t, info
    cams = []
    for r in motion.rotations:
        w2c = np.array(base.world_to_camera)
        w2c[:3, :3] = r @ w2c[:3, :3]
        w2c[:3, 3] = -w2c[:3, :3] @ base.position
        cams.append(base.with_pose(w2c))
    return cams, info


def slerp_cameras(cameras: Sequence[Camera], times: Sequence[float], at: float) -> Camera:
    """The camera at time `at` between per-frame `cameras` at `times` (rotation slerp, position lerp)."""
    import cv2

    ts = np.asarray(times, np.float64)
    i = int(np.clip(np.searchsorted(ts, at) - 1, 0, len(ts) - 2))
    a, b = cameras[i], cameras[i + 1]
    u = float(np.clip((at - ts[i]) / (ts[i + 1] - ts[i]), 0.0, 1.0))
    ra, rb = a.world_to_camera[:3, :3], b.world_to_camera[:3, :3]
    rel = cv2.Rodrigues(np.ascontiguousarray(rb @ ra.T))[0]
    r = cv2.Rodrigues(rel * u)[0] @ ra
    pos = (1 - u) * a.position + u * b.position
    w2c = np.eye(4)
    w2c[:3, :3], w2c[:3, 3] = r, -r @ pos
    return a.with_pose(w2c)
