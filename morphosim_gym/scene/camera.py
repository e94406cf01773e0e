"""`Camera`: a pinhole camera with OpenCV axes (x right, y down, z forward), world z-up.

This module is the one place that converts between our camera frame and MuJoCo's
(x right, y up, looking along -z).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

__all__ = ["Camera", "MUJOCO_TO_OPENCV", "camera_path", "CAMERA_PATHS"]

# Columns of a MuJoCo camera's frame expressed in the OpenCV camera frame: flip y and z.
MUJOCO_TO_OPENCV = np.diag([1.0, -1.0, -1.0])


def _vec3(x: Any, name: str) -> np.ndarray:
    v = np.asarray(x, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"Expected {name} as 3 finite numbers, found {np.asarray(x).tolist()!r}")
    return v


@dataclass(frozen=True, eq=False)
class Camera:
    """A pinhole camera.

    Attributes:
        width, height: image size in pixels.
        fx, fy, cx, cy: intrinsics in pixels; pixel (row i, column j) has its centre at
            image coordinates (j + 0.5, i + 0.5).
        world_to_camera: [4, 4] rigid transform taking world points to OpenCV camera coordinates.
        near: Gaussians closer than this (camera z, metres) are not drawn.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    world_to_camera: np.ndarray = field(default_factory=lambda: np.eye(4))
    near: float = 0.01

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1 or v > 16384:
                raise ValueError(f"Expected {name} as an integer in [1, 16384], found {v!r}")
            object.__setattr__(self, name, int(v))
        for name in ("fx", "fy", "cx", "cy", "near"):
            v = float(getattr(self, name))
            if not math.isfinite(v):
                raise ValueError(f"Expected a finite {name}, found {v}")
            object.__setattr__(self, name, v)
        if self.fx <= 0 or self.fy <= 0:
            raise ValueError(f"Expected fx, fy > 0, found fx={self.fx}, fy={self.fy}")
        if self.near <= 0:
            raise ValueError(f"Expected near > 0, found {self.near}")
        m = np.array(self.world_to_camera, dtype=np.float64)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)):
            raise ValueError(f"Expected world_to_camera as a finite 4x4 matrix, found shape {m.shape}")
        r = m[:3, :3]
        if not np.allclose(r @ r.T, np.eye(3), atol=1e-5) or np.linalg.det(r) < 0.99:
            raise ValueError("Expected world_to_camera to be a rigid transform (rotation + translation), "
                             "found a matrix whose 3x3 block is not a rotation")
        if not np.allclose(m[3], [0, 0, 0, 1]):
            raise ValueError(f"Expected world_to_camera's last row to be [0, 0, 0, 1], found {m[3].tolist()}")
        m.setflags(write=False)
        object.__setattr__(self, "world_to_camera", m)

    # ------------------------------------------------------------ constructors
    @staticmethod
    def intrinsics_from_fov(width: int, height: int, fov_y_deg: float) -> tuple[float, float, float, float]:
        """(fx, fy, cx, cy) for square pixels, a centred principal point and a vertical field of view."""
        fov = float(fov_y_deg)
        if not (0.0 < fov < 180.0):
            raise ValueError(f"Expected fov_y_deg in (0, 180), found {fov_y_deg}")
        f = 0.5 * height / math.tan(math.radians(fov) / 2.0)
        return f, f, width / 2.0, height / 2.0

    @classmethod
    def from_pose(cls, camera_to_world: np.ndarray, width: int, height: int, fov_y_deg: float = 60.0,
                  near: float = 0.01) -> "Camera":
        """Camera from a [4, 4] camera-to-world transform (OpenCV axes) and a vertical field of view."""
        c2w = np.asarray(camera_to_world, dtype=np.float64)
        if c2w.shape != (4, 4):
            raise ValueError(f"Expected camera_to_world of shape (4, 4), found {c2w.shape}")
        fx, fy, cx, cy = cls.intrinsics_from_fov(width, height, fov_y_deg)
        return cls(width, height, fx, fy, cx, cy, _invert_rigid(c2w), near)

    @classmethod
    def look_at(cls, eye: Sequence[float], target: Sequence[float], width: int = 128, height: int = 128,
                fov_y_deg: float = 60.0, up: Sequence[float] = (0.0, 0.0, 1.0), near: float = 0.01) -> "Camera":
        """Camera at `eye` looking at `target`, with image up as close to `up` as possible.

        Examples:
            >>> cam = Camera.look_at(eye=(0, -4, 2), target=(0, 0, 0.5), width=128, height=128, fov_y_deg=60)
            >>> cam.position.round(3).tolist()
            [0.0, -4.0, 2.0]
        """
        eye_v, target_v, up_v = _vec3(eye, "eye"), _vec3(target, "target"), _vec3(up, "up")
        forward = target_v - eye_v
        dist = np.linalg.norm(forward)
        if dist < 1e-9:
            raise ValueError("Expected eye and target to differ, found the same point")
        forward /= dist
        right = np.cross(forward, up_v)
        if np.linalg.norm(right) < 1e-9:
            raise ValueError(f"Expected up not parallel to the viewing direction, found up={up_v.tolist()} "
                             f"and direction {forward.round(4).tolist()}")
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        c2w = np.eye(4)
        c2w[:3, 0], c2w[:3, 1], c2w[:3, 2], c2w[:3, 3] = right, down, forward, eye_v
        return cls.from_pose(c2w, width, height, fov_y_deg, near)

    # ----------------------------------------------------------------- MuJoCo
    @classmethod
    def from_mujoco(cls, cam_xpos: Sequence[float], cam_xmat: Sequence[float], cam_fovy: float,
                    width: int, height: int, near: float = 0.01) -> "Camera":
        """Camera from MuJoCo's `data.cam_xpos[i]`, `data.cam_xmat[i]` (9 numbers, row-major) and
        `model.cam_fovy[i]` (degrees)."""
        pos = _vec3(cam_xpos, "cam_xpos")
        xmat = np.asarray(cam_xmat, dtype=np.float64).reshape(3, 3)
        c2w = np.eye(4)
        c2w[:3, :3] = xmat @ MUJOCO_TO_OPENCV
        c2w[:3, 3] = pos
        return cls.from_pose(c2w, width, height, float(cam_fovy), near)

    @classmethod
    def from_mujoco_camera(cls, model: Any, data: Any, camera: int | str, width: int, height: int,
                           near: float = 0.01) -> "Camera":
        """Camera from a named (or indexed) camera of a MuJoCo model, after `mj_forward`."""
        import mujoco

        if isinstance(camera, str):
            cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
            if cam_id < 0:
                names = [model.camera(i).name for i in range(model.ncam)]
                raise ValueError(f"Expected a camera of the model, found {camera!r}; cameras: {names}")
        else:
            cam_id = int(camera)
            if not 0 <= cam_id < model.ncam:
                raise ValueError(f"Expected a camera index in [0, {model.ncam}), found {cam_id}")
        return cls.from_mujoco(data.cam_xpos[cam_id], data.cam_xmat[cam_id], model.cam_fovy[cam_id],
                               width, height, near)

    def to_mujoco(self) -> tuple[np.ndarray, np.ndarray, float]:
        """(cam_xpos [3], cam_xmat [9] row-major, cam_fovy in degrees) as MuJoCo would report them."""
        c2w = self.camera_to_world
        xmat = c2w[:3, :3] @ MUJOCO_TO_OPENCV
        return c2w[:3, 3].copy(), xmat.reshape(9), self.fov_y_deg

    # ------------------------------------------------------------- properties
    @property
    def camera_to_world(self) -> np.ndarray:
        """[4, 4] inverse of `world_to_camera`."""
        return _invert_rigid(self.world_to_camera)

    @property
    def position(self) -> np.ndarray:
        """[3] camera centre in world coordinates."""
        return self.camera_to_world[:3, 3]

    @property
    def forward(self) -> np.ndarray:
        """[3] viewing direction (camera +z) in world coordinates."""
        return self.world_to_camera[2, :3].copy()

    @property
    def K(self) -> np.ndarray:
        """[3, 3] intrinsic matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def fov_y_deg(self) -> float:
        """Vertical field of view in degrees."""
        return math.degrees(2.0 * math.atan(0.5 * self.height / self.fy))

    @property
    def fov_x_deg(self) -> float:
        """Horizontal field of view in degrees."""
        return math.degrees(2.0 * math.atan(0.5 * self.width / self.fx))

    # ------------------------------------------------------------- operations
    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates [..., 2] (x right, y down) and camera depth [...] of world points [..., 3]."""
        p = np.asarray(points, dtype=np.float64)
        pc = p @ self.world_to_camera[:3, :3].T + self.world_to_camera[:3, 3]
        z = pc[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = np.stack([self.fx * pc[..., 0] / z + self.cx, self.fy * pc[..., 1] / z + self.cy], axis=-1)
        return uv, z

    def project_point(self, point: np.ndarray) -> tuple[float, float, float]:
        """(x, y, depth) of one world point [3] as floats: `project`'s values for it, to the bit
        (the per-step task path, without `project`'s array bookkeeping)."""
        pc = (np.asarray(point, dtype=np.float64) @ self.world_to_camera[:3, :3].T + self.world_to_camera[:3, 3]).tolist()
        z = pc[2]
        if z == 0.0:
            uv = self.project(point)[0]
            return float(uv[0]), float(uv[1]), z
        return self.fx * pc[0] / z + self.cx, self.fy * pc[1] / z + self.cy, z

    def pixel_centres(self) -> np.ndarray:
        """[H, W, 2] pixel coordinates (x, y) of every pixel's centre."""
        jj, ii = np.meshgrid(np.arange(self.width) + 0.5, np.arange(self.height) + 0.5)
        return np.stack([jj, ii], -1)

    def unproject(self, uv: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """World points [..., 3] for pixel coordinates [..., 2] at camera depths [...]."""
        uv = np.asarray(uv, dtype=np.float64)
        z = np.asarray(depth, dtype=np.float64)
        pc = np.stack([(uv[..., 0] - self.cx) / self.fx * z, (uv[..., 1] - self.cy) / self.fy * z, z], axis=-1)
        c2w = self.camera_to_world
        return pc @ c2w[:3, :3].T + c2w[:3, 3]

    def with_pose(self, world_to_camera: np.ndarray) -> "Camera":
        """Same intrinsics, another pose."""
        return Camera(self.width, self.height, self.fx, self.fy, self.cx, self.cy, world_to_camera, self.near)

    def resized(self, width: int, height: int) -> "Camera":
        """Same pose and field of view at another resolution."""
        sx, sy = width / self.width, height / self.height
        return Camera(width, height, self.fx * sx, self.fy * sy, self.cx * sx, self.cy * sy,
                      self.world_to_camera, self.near)

    def orbit(self, yaw_deg: float, center: Sequence[float], pitch_deg: float = 0.0) -> "Camera":
        """This camera rotated by `yaw_deg` about the world z axis through `center` (then by
        `pitch_deg` about the camera's own x axis through `center`), still looking the same way
        relative to the centre."""
        c = _vec3(center, "center")
        yaw = math.radians(yaw_deg)
        rz = np.array([[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0, 0, 1.0]])
        c2w = self.camera_to_world.copy()
        if pitch_deg:
            axis = c2w[:3, 0]
            p = math.radians(pitch_deg)
            k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            rp = np.eye(3) + math.sin(p) * k + (1 - math.cos(p)) * (k @ k)
        else:
            rp = np.eye(3)
        rot = rz @ rp
        c2w[:3, :3] = rot @ c2w[:3, :3]
        c2w[:3, 3] = rot @ (c2w[:3, 3] - c) + c
        return self.with_pose(_invert_rigid(c2w))

    def to_dict(self) -> dict:
        """JSON-friendly description (intrinsics and pose)."""
        return {"width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy, "cx": self.cx,
                "cy": self.cy, "near": self.near, "world_to_camera": self.world_to_camera.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> "Camera":
        """Inverse of `to_dict`."""
        return cls(d["width"], d["height"], d["fx"], d["fy"], d["cx"], d["cy"],
                   np.asarray(d["world_to_camera"]), d.get("near", 0.01))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Camera):
            return NotImplemented
        return (self.width, self.height, self.fx, self.fy, self.cx, self.cy, self.near) == (
            other.width, other.height, other.fx, other.fy, other.cx, other.cy, other.near
        ) and np.array_equal(self.world_to_camera, other.world_to_camera)

    def __hash__(self) -> int:
        return hash((self.width, self.height, self.fx, self.fy, self.cx, self.cy, self.near,
                     self.world_to_camera.tobytes()))

    def __repr__(self) -> str:
        pos = np.round(self.position, 3).tolist()
        return f"Camera({self.width}x{self.height}, fov_y={self.fov_y_deg:.1f}deg, position={pos})"


def _orbit_path(spec: Any, base: Camera, centre: np.ndarray, tau: np.ndarray) -> list[Camera]:
    sign = -1.0 if spec.direction == "clockwise" else 1.0
    total = sign * min(360.0, 120.0 * float(spec.speed))
    return [base.orbit(total * s, center=centre) for s in tau]


def _pan_path(spec: Any, base: Camera, centre: np.ndarray, tau: np.ndarray) -> list[Camera]:
    sign = -1.0 if spec.direction == "right" else 1.0     # turning right is a negative yaw about +z
    total = sign * min(60.0, 25.0 * float(spec.speed))
    pos = base.position
    return [base.orbit(total * s, center=pos) for s in tau]


def _dolly_path(spec: Any, base: Camera, centre: np.ndarray, tau: np.ndarray) -> list[Camera]:
    """Along the view axis, in (default) or out."""
    sign = -1.0 if spec.direction == "out" else 1.0
    dist = float(np.linalg.norm(base.position - centre))
    travel = sign * min(0.6, 0.3 * float(spec.speed)) * dist
    out = []
    for s in tau:
        c2w = base.camera_to_world.copy()
        c2w[:3, 3] += base.forward * travel * s
        w2c = np.linalg.inv(c2w)
        out.append(base.with_pose(w2c))
    return out


# camera motion name -> (spec, base camera, centre, tau [T] in [0, 1]) -> per-frame cameras
CAMERA_PATHS = {"orbit": _orbit_path, "pan": _pan_path, "dolly": _dolly_path}


def camera_path(spec: Any, base: Camera, centre: np.ndarray, num_frames: int) -> list[Camera]:
    """Per-frame cameras for a camera spec (`.motion` fixed, orbit, pan or dolly, `.direction`,
    `.speed`; e.g. `language.CameraSpec`) starting from `base`, orbiting or dollying about `centre`.
    `spec` None is a fixed camera."""
    if spec is None or spec.motion == "fixed" or num_frames == 1:
        return [base] * num_frames
    path = CAMERA_PATHS.get(spec.motion)
    if path is None:
        raise ValueError(f"Expected a camera motion in {['fixed', *CAMERA_PATHS]}, found {spec.motion!r}")
    return path(spec, base, centre, np.linspace(0.0, 1.0, num_frames))


def _invert_rigid(m: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    r = m[:3, :3]
    out[:3, :3] = r.T
    out[:3, 3] = -r.T @ m[:3, 3]
    return out
