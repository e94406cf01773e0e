"""Camera conversions between the browser viewer (viser) and our `Camera`.

viser reports each client's camera as `wxyz` and `position` with `P_world = R @ p_camera + t`,
where R (the rotation of the quaternion `wxyz`, scalar first) has the camera's axes as its
columns, and the camera axes follow OpenCV: x right, y down, z forward (the look direction).
Its `fov` is the vertical field of view in radians. Our `Camera` uses the same camera axes
and the same world frame (we set viser's up direction to world +z), so the conversion is:

    camera_to_world = [[R, position], [0, 0, 0, 1]]        (no axis flips)
    Camera.from_pose(camera_to_world, width, height, fov_y_deg=degrees(fov))

The rendered image fills the browser's canvas: we render at the canvas's aspect ratio with
the same vertical field of view, at a capped resolution (`render_size`).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..scene import Camera
from ..scene.rotations import matrix_to_quat, quat_to_matrix

__all__ = ["camera_from_viewer", "viewer_pose", "viewer_view", "render_size"]


def camera_from_viewer(wxyz: Sequence[float], position: Sequence[float], fov_y: float, width: int, height: int,
                       near: float = 0.01) -> Camera:
    """Our `Camera` for a viser client camera.

    Args:
        wxyz: [4] rotation camera -> world as a quaternion, scalar first.
        position: [3] camera centre in world coordinates.
        fov_y: vertical field of view in radians.
        width, height: image size to render at.
        near: near clipping distance in metres.

    Returns:
        Camera: same pose and vertical field of view, OpenCV axes.
    """
    q = np.asarray(wxyz, dtype=np.float64)
    p = np.asarray(position, dtype=np.float64)
    if q.shape != (4,) or not np.all(np.isfinite(q)) or np.linalg.norm(q) < 1e-9:
        raise ValueError(f"Expected wxyz as 4 finite numbers (a rotation), found {np.asarray(wxyz).tolist()!r}")
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"Expected position as 3 finite numbers, found {np.asarray(position).tolist()!r}")
    fov = float(fov_y)
    if not (0.0 < fov < math.pi):
        raise ValueError(f"Expected fov_y in (0, pi) radians, found {fov_y!r}")
    c2w = np.eye(4)
    c2w[:3, :3] = quat_to_matrix(q / np.linalg.norm(q))
    c2w[:3, 3] = p
    return Camera.from_pose(c2w, int(width), int(height), math.degrees(fov), near)


def viewer_pose(camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(wxyz [4], position [3]) of a `Camera` in viser's convention (inverse of `camera_from_viewer`)."""
    c2w = camera.camera_to_world
    return matrix_to_quat(c2w[:3, :3]), c2w[:3, 3].copy()


def viewer_view(camera: Camera, target: Sequence[float]) -> dict:
    """What to assign to a viser camera (`position`, `look_at`, `up_direction`, `fov`) so that it
    shows what `camera` shows (for a camera without roll, as `Camera.look_at` makes) while orbiting
    about `target` (a point on or near the optical axis; it is moved onto the axis at the same depth)
    with world z up."""
    c2w = camera.camera_to_world
    pos = c2w[:3, 3]
    forward = c2w[:3, 2]
    depth = float(np.dot(np.asarray(target, dtype=np.float64) - pos, forward))
    look_at = pos + max(depth, 1e-3) * forward
    # Orbit about world z (z-up, as our cameras): viser keeps the image's up as close to this as it can,
    # which gives back the camera's own orientation when it has no roll. Looking straight up or down,
    # world z says nothing about roll: use the camera's own image up.
    up = np.array([0.0, 0.0, 1.0]) if abs(forward[2]) < 0.999 else -c2w[:3, 1]
    return {"position": pos.copy(), "look_at": look_at, "up_direction": up, "fov": math.radians(camera.fov_y_deg)}


def render_size(aspect: float, long_side: int) -> tuple[int, int]:
    """(width, height) for a canvas of this aspect ratio (width / height) whose longer side is
    `long_side` pixels; both even and at least 16."""
    a = float(aspect)
    if not (math.isfinite(a) and a > 0):
        a = 1.0
    a = min(max(a, 0.1), 10.0)
    long_side = int(long_side)
    if a >= 1.0:
        w, h = long_side, long_side / a
    else:
        w, h = long_side * a, long_side
    return max(16, 2 * int(round(w / 2))), max(16, 2 * int(round(h / 2)))
