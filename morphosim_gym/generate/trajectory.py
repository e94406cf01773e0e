"""Trajectory planner: language motion -> image-space key points and boxes -> world path.

Follows the paper's definitions:

* key points T = {(x_i, y_i, t_i)}: the object's image-space anchor (its ground contact
  point, or its centre for things that fly or swim) at each frame time t_i;
* boxes B_i = {(x, y): |x - x_i| <= Dx_i, |y - y_i| <= Dy_i}, with the tolerances Dx, Dy
  from the object's projected size (plus half a frame's displacement along the motion);
* velocities v_i = ||(x_{i+1} - x_i, y_{i+1} - y_i)|| / (t_{i+1} - t_i);
* velocity-scaled displacement: the step between key points is the nominal step at the
  asked velocity times lambda(v_i), so "quickly" spaces boxes farther apart than "slowly".
  lambda saturates so that a fast object still crosses at most ~85% of the frame: the
  travel over the clip is `travel_fraction(s) = 0.85 (1 - exp(-0.753 s))` of the image
  extent along the motion for a speed factor s (0.45 at s = 1, 0.27 at 0.5, 0.66 at 2).

The image-space plan is lifted to the world by intersecting each key point's camera ray
with the plane the object moves on (the ground, or a vertical plane facing the camera
for up/down motion and things that fly or swim), then bounces and zigzags are added in
the world and the final boxes are measured by projecting the object's 3D box. The
result keeps the object on screen: the path is shifted (and, if it must, shortened) to
fit inside a margin of the first frame's camera.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional, Sequence

import numpy as np

from ..scene.camera import Camera

__all__ = ["MotionRequest", "PlannedTrajectory", "plan_trajectory", "travel_fraction", "displacement_scale", "bounce_height",
           "PATHS"]

PATHS = ("straight", "bounce", "circle", "zigzag", "oscillate", "stop", "to")
_MAX_TRAVEL = 0.85
_K = 0.753          # travel_fraction(1) = 0.45
MARGIN = 0.04       # fraction of the image kept free at each border


def travel_fraction(speed: float) -> float:
    """Fraction of the image extent (along the motion) crossed over the clip at this speed factor."""
    return _MAX_TRAVEL * (1.0 - math.exp(-_K * max(float(speed), 0.0)))


def displacement_scale(speed: float) -> float:
    """lambda(v) * v / v_ref: how much farther apart the key points are than at normal speed."""
    return travel_fraction(speed) / travel_fraction(1.0)


@dataclass(frozen=True)
class MotionRequest:
    """What the language asked of one object's motion.

    Attributes:
        path: "straight", "bounce", "circle", "zigzag", "oscillate" (back and forth along the
            direction), "stop" or "to" (go to a landmark).
        direction: world unit vector of travel (straight, bounce, zigzag); z-up world.
        speed: speed factor (1 = normal; "slowly" ~ 0.5, "quickly" ~ 2).
        clockwise: circle direction as seen from above.
        start: world point to start from (e.g. "from the box"), if any.
        end: world point to reach for path "to" (e.g. "to the plate").
        center: world centre of a circle path.
        end_height: anchor height at the end of a "to" path (on top of a receptacle).
        clearance: a "to" path stops this many metres short of `end` (beside the landmark, not in it).
        start_clearance: and starts this many metres away from `start` towards `end`.
    """

    path: str = "straight"
    direction: tuple[float, float, float] = (1.0, 0.0, 0.0)
    speed: float = 1.0
    clockwise: bool = True
    start: Optional[tuple[float, float, float]] = None
    end: Optional[tuple[float, float, float]] = None
    center: Optional[tuple[float, float, float]] = None
    end_height: Optional[float] = None
    clearance: float = 0.0
    start_clearance: float = 0.0

    def __post_init__(self) -> None:
        if self.path not in PATHS:
            raise ValueError(f"Expected a path in {PATHS}, found {self.path!r}")
        if not (math.isfinite(self.speed) and self.speed > 0):
            raise ValueError(f"Expected speed > 0, found {self.speed}")
        d = np.asarray(self.direction, dtype=np.float64)
        if self.path in ("straight", "bounce", "zigzag", "oscillate") and (d.shape != (3,) or np.linalg.norm(d) < 1e-9):
            raise ValueError(f"Expected a non-zero world direction for a {self.path} path, found {self.direction}")
        if self.path == "to" and self.end is None:
            raise ValueError("Expected an end point (landmark) for a 'to' path, found none")


@dataclass
class PlannedTrajectory:
    """A planned motion: the paper's key points and boxes plus the world path.

    Attributes:
        times: [T] seconds.
        keypoints: [T, 2] image-space anchor (x right, y down, pixels) in the first camera.
        boxes: [T, 4] B_i as (x0, y0, x1, y1) pixels, in each frame's camera.
        velocities: [T-1] v_i, pixels per second, of the key points.
        lambdas: [T-1] lambda(v_i) used to space the key points.
        positions: [T, 3] world anchor positions.
        headings: [T] yaw (radians, about +z) the object faces.
        spins: [T] roll angle (radians) for rolling objects, about the axis across the heading.
        width, height: image size the pixels refer to.
    """

    times: np.ndarray
    keypoints: np.ndarray
    boxes: np.ndarray
    velocities: np.ndarray
    lambdas: np.ndarray
    positions: np.ndarray
    headings: np.ndarray
    spins: np.ndarray = field(default_factory=lambda: np.zeros(0))
    width: int = 0
    height: int = 0

    def boxes_normalized(self) -> np.ndarray:
        """[T, 4] boxes as fractions of the image size."""
        return self.boxes / np.array([self.width, self.height, self.width, self.height], dtype=np.float64)

    def to_dict(self) -> dict:
        """JSON-friendly summary (key points, boxes, velocities)."""
        return {"times": self.times.tolist(), "keypoints": self.keypoints.round(3).tolist(),
                "boxes": self.boxes.round(3).tolist(), "velocities": self.velocities.round(3).tolist(),
                "lambdas": self.lambdas.round(4).tolist()}


# ------------------------------------------------------------------ geometry
def _ray(camera: Camera, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    uv = np.atleast_2d(uv)
    d_cam = np.c_[(uv[:, 0] - camera.cx) / camera.fx, (uv[:, 1] - camera.cy) / camera.fy, np.ones(len(uv))]
    c2w = camera.camera_to_world
    d = d_cam @ c2w[:3, :3].T
    return np.broadcast_to(c2w[:3, 3], d.shape), d


def _lift(camera: Camera, uv: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """World points where the pixels' rays meet the plane normal . x = offset."""
    o, d = _ray(camera, uv)
    denom = d @ normal
    denom = np.where(np.abs(denom) < 1e-9, 1e-9, denom)
    s = (offset - o @ normal) / denom
    return o + s[:, None] * d


def _box_corners(half: np.ndarray, anchor_is_base: bool) -> np.ndarray:
    hx, hy, hz = half
    zs = (0.0, 2 * hz) if anchor_is_base else (-hz, hz)
    return np.array([[x, y, z] for x in (-hx, hx) for y in (-hy, hy) for z in zs])


def _project_boxes(cameras: Sequence[Camera], positions: np.ndarray, headings: np.ndarray, half: np.ndarray,
                   anchor_is_base: bool, pad: np.ndarray) -> np.ndarray:
    corners = _box_corners(half, anchor_is_base)
    boxes = np.empty((len(positions), 4))
    for i, (p, yaw) in enumerate(zip(positions, headings)):
        c, s = math.cos(yaw), math.sin(yaw)
        rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        uv, z = cameras[min(i, len(cameras) - 1)].project(corners @ rot.T + p)
        if np.any(z <= 1e-6):
            uv = uv[z > 1e-6] if np.any(z > 1e-6) else np.zeros((1, 2))
        boxes[i] = [uv[:, 0].min() - pad[i, 0], uv[:, 1].min() - pad[i, 1], uv[:, 0].max() + pad[i, 0],
                    uv[:, 1].max() + pad[i, 1]]
    return boxes


# ------------------------------------------------------------------ planner
def plan_trajectory(
    request: MotionRequest,
    cameras: Sequence[Camera],
    num_frames: int,
    fps: float,
    half_extent: Sequence[float],
    anchor: Sequence[float],
    vertical_plane: bool = False,
    rolls: bool = False,
    keep_on_screen: bool = True,
) -> PlannedTrajectory:
    """Plan one object's motion.

    Args:
        request: the motion asked for.
        cameras: the generation camera per frame (or one fixed camera); key points refer to the first.
        num_frames, fps: clip length.
        half_extent: [3] the object's half size (x forward, y left, z up), metres.
        anchor: [3] world point the path is centred on (the object's rest anchor: ground contact
            point, or centre for things that fly or swim).
        vertical_plane: move on the vertical plane facing the camera through `anchor` (flying,
            swimming) instead of the horizontal plane z = anchor z.
        rolls: the object rolls along the ground (spins follow distance / radius).
        keep_on_screen: shift / shorten the path so every box stays inside the first camera's frame.

    Returns:
        PlannedTrajectory.
    """
    if num_frames < 1:
        raise ValueError(f"Expected num_frames >= 1, found {num_frames}")
    cam0 = cameras[0]
    W, H = cam0.width, cam0.height
    T = num_frames
    times = np.arange(T) / float(fps)
    anchor = np.asarray(anchor, dtype=np.float64)
    half = np.asarray(half_extent, dtype=np.float64)
    forward = cam0.forward
    if vertical_plane:
        normal = np.array([forward[0], forward[1], 0.0])
        normal = normal / max(np.linalg.norm(normal), 1e-9)
    else:
        normal = np.array([0.0, 0.0, 1.0])
    offset = float(normal @ anchor)
    direction = np.asarray(request.direction, dtype=np.float64)
    direction = direction / max(np.linalg.norm(direction), 1e-12)
    if not vertical_plane and abs(direction[2]) > 0.7 and request.path in ("straight", "bounce", "zigzag", "oscillate"):
        # rising / sinking: move on the vertical plane through the anchor
        vertical_plane = True
        normal = np.array([forward[0], forward[1], 0.0]) / max(np.linalg.norm(forward[:2]), 1e-9)
        offset = float(normal @ anchor)
    scale = displacement_scale(request.speed)
    centre_uv = cam0.project(anchor)[0]

    def plan_image(scale_mult: float, shift: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(keypoints, velocities, lambdas, world positions) for a travel multiplier and image shift."""
        if request.path in ("straight", "bounce", "zigzag", "oscillate"):
            step_w = anchor + 0.05 * direction
            u = cam0.project(step_w)[0] - cam0.project(anchor)[0]
            if np.linalg.norm(u) < 1e-6:
                u = np.array([1.0, 0.0])
            u = u / np.linalg.norm(u)
            extent = abs(u[0]) * W + abs(u[1]) * H
            d0 = travel_fraction(1.0) * extent / max(T - 1, 1)           # nominal step at speed 1
            v = np.full(max(T - 1, 0), request.speed * d0 * fps)         # v_i at the asked speed
            lam = np.full_like(v, scale * scale_mult / request.speed)     # lambda(v_i)
            nominal = np.arange(T)[:, None] * d0 * u                      # key points at v_ref
            steps = lam[:, None] * request.speed * np.diff(nominal, axis=0)
            if request.path == "oscillate":                                # out and back along the direction
                swing = np.cos(np.linspace(0, 2 * math.pi, T))
                steps = steps * (-np.sign(np.diff(swing)) * 2.0)[:, None] if T > 1 else steps
            kp = np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
            start_uv = cam0.project(np.asarray(request.start))[0] if request.start is not None else None
            kp = kp + (start_uv if start_uv is not None else centre_uv - kp[-1] / 2) + shift
            pos = _lift(cam0, kp, normal, offset)
            return kp, v, lam, pos
        if request.path == "circle":
            centre = np.asarray(request.center if request.center is not None else anchor, dtype=np.float64)
            radius = _circle_radius(cam0, centre, half) * min(1.0, scale_mult)
            turns = displacement_scale(request.speed)
            sign = -1.0 if request.clockwise else 1.0
            ang0 = math.atan2(cam0.position[1] - centre[1], cam0.position[0] - centre[0])  # start nearest the camera
            nominal_ang = np.linspace(0, 2 * math.pi, T)
            lam = np.full(max(T - 1, 0), turns)
            ang = ang0 + sign * np.concatenate([[0.0], np.cumsum(lam * np.diff(nominal_ang))])
            pos = centre + np.c_[radius * np.cos(ang), radius * np.sin(ang), np.zeros(T)]
            pos[:, 2] = anchor[2]
            kp = cam0.project(pos)[0] + shift
            v = np.linalg.norm(np.diff(kp, axis=0), axis=1) * fps / np.maximum(lam, 1e-9)
            pos = _lift(cam0, kp, np.array([0, 0, 1.0]), anchor[2]) if np.any(shift) else pos
            return kp, v, lam, pos
        if request.path == "to":
            end = np.asarray(request.end, dtype=np.float64)
            end = end.copy()
            end[2] = anchor[2]
            if request.start is not None:
                start = np.asarray(request.start, dtype=np.float64).copy()
                start[2] = anchor[2]
            else:
                right = cam0.camera_to_world[:3, 0].copy()
                right[2] = 0.0
                right /= max(np.linalg.norm(right), 1e-9)
                # start across the frame from the landmark (left of it if it sits right of centre)
                end_uv = cam0.project(end)[0]
                sign = -1.0 if end_uv[0] >= W / 2 else 1.0
                start = end + sign * right * _ground_span(cam0, end) * 0.45 * scale_mult
            if request.clearance > 0 or request.start_clearance > 0:
                approach = end - start
                dist = float(np.linalg.norm(approach))
                unit = approach / max(dist, 1e-9)
                end = end - unit * min(request.clearance, 0.45 * dist)
                start = start + unit * min(request.start_clearance, 0.45 * dist)
            uv0, uv1 = cam0.project(start)[0], cam0.project(end)[0]
            frac_arrive = min(1.0, 0.8 / max(scale, 1e-6))
            n_move = max(1, int(round(frac_arrive * (T - 1))))
            tau = np.minimum(np.arange(T) / n_move, 1.0)
            ease = 1 - (1 - tau) ** 2                                     # ease out into the landmark
            kp = uv0 + ease[:, None] * (uv1 - uv0)                       # the landmark does not move
            v = np.linalg.norm(np.diff(kp, axis=0), axis=1) * fps
            lam = np.full(max(T - 1, 0), scale)
            pos = _lift(cam0, kp, np.array([0, 0, 1.0]), anchor[2])
            return kp, v, lam, pos
        # stop
        kp = np.tile(centre_uv + shift, (T, 1))
        pos = _lift(cam0, kp, normal, offset)
        return kp, np.zeros(max(T - 1, 0)), np.ones(max(T - 1, 0)), pos

    shift = np.zeros(2)
    mult = 1.0
    for _ in range(8):
        kp, v, lam, pos = plan_image(mult, shift)
        pos = _decorate(request, pos, direction, half, times, min(1.0, mult))
        headings = _headings(request, pos, direction, cam0)
        pad = np.zeros((T, 2))
        boxes = _project_boxes(cameras, pos, headings, half, not vertical_plane, pad)
        if not keep_on_screen:
            break
        lo = np.array([W * MARGIN, H * MARGIN])
        hi = np.array([W * (1 - MARGIN), H * (1 - MARGIN)])
        first = _project_boxes([cam0], pos, headings, half, not vertical_plane, pad)
        bmin, bmax = first[:, :2].min(0), first[:, 2:].max(0)
        span, room = bmax - bmin, hi - lo
        if np.all(bmin >= lo - 1e-6) and np.all(bmax <= hi + 1e-6):
            break
        if np.any(span > room) or request.path == "to":
            mult *= 0.85 * float(np.min(np.where(span > room, room / np.maximum(span, 1e-9), 1.0)))
        else:
            shift = shift + np.where(bmin < lo, lo - bmin, 0.0) + np.where(bmax > hi, hi - bmax, 0.0)
    # image-space tolerance: half a frame's displacement along the motion (the paper's velocity term)
    disp = np.vstack([np.diff(kp, axis=0), np.zeros((1, 2))])
    boxes = boxes + np.c_[-np.abs(disp) / 2, np.abs(disp) / 2]
    spins = np.zeros(T)
    if rolls:
        ground = pos.copy()
        ground[:, 2] = 0.0
        dist = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(ground, axis=0), axis=1))])
        spins = dist / max(float(half[2]), 1e-6)
    return PlannedTrajectory(times=times, keypoints=kp, boxes=boxes, velocities=v, lambdas=lam, positions=pos,
                             headings=headings, spins=spins, width=W, height=H)


def _ground_span(camera: Camera, point: np.ndarray) -> float:
    """Width of the camera's view (metres) at the depth of `point`."""
    depth = float(camera.project(point)[1])
    return max(depth, 1e-3) * camera.width / camera.fx


def _circle_radius(camera: Camera, centre: np.ndarray, half: np.ndarray) -> float:
    span = _ground_span(camera, centre)
    return max(0.22 * span, 2.5 * float(max(half[0], half[1])))


def bounce_height(half: np.ndarray) -> float:
    """Peak height of a bounce path's hops for an object of this half size."""
    return 1.2 * 2.0 * float(half[2])


def _decorate(request: MotionRequest, pos: np.ndarray, direction: np.ndarray, half: np.ndarray,
              times: np.ndarray, shrink: float = 1.0) -> np.ndarray:
    """Add the world-space parts of bounce and zigzag paths (`shrink` < 1 when the path had to be
    shortened to stay on screen)."""
    T = len(pos)
    tau = np.linspace(0.0, 1.0, T)
    out = pos.copy()
    if request.path == "bounce":
        hops = 3
        out[:, 2] += bounce_height(half) * shrink * np.abs(np.sin(math.pi * hops * tau))
    elif request.path == "zigzag":
        lateral = np.cross([0.0, 0.0, 1.0], direction)
        if np.linalg.norm(lateral) < 1e-6:
            lateral = np.array([1.0, 0.0, 0.0])
        lateral /= np.linalg.norm(lateral)
        travel = float(np.linalg.norm(pos[-1] - pos[0]))
        amp = max(0.12 * travel, 1.5 * float(half[1]))
        zig = 4
        tri = 2 * np.abs(2 * ((tau * zig) % 1.0) - 1) - 1             # triangle wave in [-1, 1]
        out += amp * tri[:, None] * lateral
    return out


def _headings(request: MotionRequest, pos: np.ndarray, direction: np.ndarray, camera: Camera) -> np.ndarray:
    """Yaw per frame: facing the horizontal velocity; still objects face the travel direction
    or, without one, across the view (camera right)."""
    T = len(pos)
    vel = np.gradient(pos[:, :2], axis=0) if T > 1 else np.zeros((1, 2))
    speed = np.linalg.norm(vel, axis=1)
    right = camera.camera_to_world[:3, 0]
    if request.path in ("straight", "bounce", "zigzag", "oscillate") and np.linalg.norm(direction[:2]) > 1e-6:
        default = math.atan2(direction[1], direction[0])
    else:
        default = math.atan2(right[1], right[0])
    yaw = np.where(speed > 1e-6, np.arctan2(vel[:, 1], vel[:, 0]), np.nan)
    if request.path == "zigzag":
        yaw = np.full(T, math.atan2(direction[1], direction[0]))
    if np.all(np.isnan(yaw)):
        return np.full(T, default)
    # hold the last known heading through stops, then unwrap for smooth interpolation
    first = int(np.flatnonzero(~np.isnan(yaw))[0])
    yaw[:first] = yaw[first]
    for i in range(1, T):
        if np.isnan(yaw[i]):
            yaw[i] = yaw[i - 1]
    return np.unwrap(yaw)
