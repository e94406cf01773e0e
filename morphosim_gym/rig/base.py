"""`Rig`: a MuJoCo model of a camera rig or an agent, used for kinematics only.

MuJoCo never simulates the scene here: the world is a `Scene4D`. A rig's joints are set
kinematically (integrated from velocity commands and clipped to their ranges), then
`mj_kinematics` and `mj_camlight` give the poses of its links, sites and cameras. Any
camera of the model can become a `morphosim_gym.Camera` for rendering.

Rigs are modelled at a nominal size and scaled uniformly to the scene they are placed in
(a tabletop scene is ~1 m across, a street scene ~20 m): `place(..., scale=s)` multiplies
every body, geom, site and camera offset and every geom size by `s`.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..scene.camera import MUJOCO_TO_OPENCV, Camera
from ..scene.gaussians import Gaussians

__all__ = ["Rig", "RigState", "RIG_DIR", "yaw_quat", "AGENT_OBJECT_ID", "mujoco_camera", "POSED_MODEL_FIELDS"]

RIG_DIR = Path(__file__).resolve().parent
AGENT_OBJECT_ID = 100          # instance id the agent's own Gaussians render with
POSED_MODEL_FIELDS = ("body_pos", "body_ipos", "body_quat", "geom_pos", "geom_size", "site_pos", "site_size",
                      "cam_pos", "cam_quat", "cam_fovy")
"""The `MjModel` arrays a rig changes after construction (placement, scale, zoom, world cameras)."""
_SHARED_ATTRS = frozenset({"model", "data", "_skin", "_nominal", "_name_ids"})   # not part of a rig's episode state
_EYE4 = np.eye(4)


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError as exc:  # pragma: no cover - mujoco is a core dependency
        raise ImportError("Expected the mujoco package for rigs, found it missing; pip install mujoco") from exc
    return mujoco


def yaw_quat(yaw: float) -> np.ndarray:
    """[4] w, x, y, z rotation by `yaw` radians about world z."""
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


def mujoco_camera(cam_xpos: np.ndarray, cam_xmat: np.ndarray, fovy: float, width: int, height: int,
                  near: float) -> Camera:
    """`Camera.from_mujoco` for the per-step hot path: the same arithmetic, without re-validating
    what MuJoCo guarantees (an orthonormal `cam_xmat`, a finite position). Equal (==) to
    `Camera.from_mujoco(cam_xpos, cam_xmat, fovy, width, height, near)`."""
    rt = (np.asarray(cam_xmat, dtype=np.float64).reshape(3, 3) @ MUJOCO_TO_OPENCV).T   # world -> camera
    w2c = _EYE4.copy()
    w2c[:3, :3] = rt
    w2c[:3, 3] = -rt @ np.asarray(cam_xpos, dtype=np.float64)
    w2c.setflags(write=False)
    f = 0.5 * height / math.tan(math.radians(fovy) / 2.0)
    cam = object.__new__(Camera)
    vars(cam).update(width=int(width), height=int(height), fx=f, fy=f, cx=width / 2.0, cy=height / 2.0,
                     world_to_camera=w2c, near=float(near))    # a frozen dataclass: fields set past __setattr__
    return cam


@dataclass(frozen=True)
class RigState:
    """A rig's episode state (`Rig.get_state`): the posed model arrays, the joint positions and
    the rig's own attributes. Opaque; only `Rig.set_state` of the same rig class reads it."""

    model: dict[str, np.ndarray]
    qpos: np.ndarray
    attrs: dict[str, Any]


class Rig:
    """A kinematic MuJoCo model loaded from an MJCF file of the package (or any path).

    Args:
        xml: file name in `morphosim_gym/rig/` or a path to an MJCF file.
        skin_budget: Gaussians used to draw the agent's geoms (see `AgentSkin`).

    Attributes:
        model, data: the MuJoCo model and data.
        scale: the current uniform scale (1 = nominal).
    """

    xml: str = ""
    root_body: str = ""

    def __init__(self, xml: str | None = None, skin_budget: int = 1500) -> None:
        mujoco = _mujoco()
        path = Path(xml or self.xml)
        if not path.is_absolute() and not path.exists():
            path = RIG_DIR / path
        if not path.exists():
            raise ValueError(f"Expected an MJCF file, found no file at {str(path)!r}")
        self.model = mujoco.MjModel.from_xml_path(str(path))
        self.data = mujoco.MjData(self.model)
        self._name_ids: dict[tuple[str, str], int] = {}    # (kind, name) -> id, looked up once (`_id`)
        self._nominal = {k: getattr(self.model, k).copy()
                         for k in ("body_pos", "body_ipos", "geom_pos", "geom_size", "site_pos", "site_size", "cam_pos")}
        self._root = self._id("body", self.root_body) if self.root_body else 1
        # cameras attached to the world body are posed by the env, not scaled with the rig
        self._world_cams = {i for i in range(self.model.ncam) if int(self.model.cam_bodyid[i]) == 0}
        self.scale = 1.0
        self._skin_budget = int(skin_budget)
        self._skin = None
        hinges = [j for j in range(self.model.njnt)
                  if int(self.model.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))]
        self.joint_names = tuple(self.model.joint(j).name for j in hinges)
        self._qadr = np.array([int(self.model.jnt_qposadr[j]) for j in hinges], dtype=np.int64)
        self.joint_range = np.array([self.model.jnt_range[j] for j in hinges], dtype=np.float64).reshape(-1, 2)
        self.forward()

    @property
    def _mj(self) -> Any:
        """The mujoco module (looked up, not stored: a module does not pickle)."""
        return _mujoco()

    # ------------------------------------------------------------ state
    def get_state(self) -> RigState:
        """A copy of everything an episode changes: the posed model arrays (`POSED_MODEL_FIELDS`),
        `qpos` and the rig's attributes (last action, zoom limits...). The compiled model, the
        MuJoCo data buffers and the skin are not copied."""
        m = self.model
        attrs = copy.deepcopy({k: v for k, v in vars(self).items() if k not in _SHARED_ATTRS})
        return RigState({f: getattr(m, f).copy() for f in POSED_MODEL_FIELDS}, self.data.qpos.copy(), attrs)

    def set_state(self, state: RigState) -> None:
        """Return to a `get_state` result (of this rig's class) and recompute the kinematics."""
        if not isinstance(state, RigState):
            raise TypeError(f"Expected a RigState from Rig.get_state(), found {type(state).__name__}")
        if state.qpos.shape != self.data.qpos.shape:
            raise ValueError(f"Expected a RigState of a {type(self).__name__} (qpos [{self.data.qpos.size}]), "
                             f"found qpos [{state.qpos.size}]")
        for f, value in state.model.items():
            getattr(self.model, f)[...] = value
        self.data.qpos[:] = state.qpos
        vars(self).update(copy.deepcopy(state.attrs))
        self.forward()

    # ------------------------------------------------------------ lookups
    def _id(self, kind: str, name: str) -> int:
        """The id of a body, site or camera of the model by name (looked up once; `ValueError`
        naming the model's ones for a name it lacks)."""
        i = self._name_ids.get((kind, name))
        if i is not None:
            return i
        obj = {"body": self._mj.mjtObj.mjOBJ_BODY, "site": self._mj.mjtObj.mjOBJ_SITE,
               "camera": self._mj.mjtObj.mjOBJ_CAMERA}[kind]
        i = self._mj.mj_name2id(self.model, obj, name)
        if i < 0:
            count = {"body": self.model.nbody, "site": self.model.nsite, "camera": self.model.ncam}[kind]
            names = [self._mj.mj_id2name(self.model, obj, k) for k in range(count)]
            raise ValueError(f"Expected a {kind} of the rig, found {name!r}; {kind}s: {names}")
        self._name_ids[(kind, name)] = i
        return i

    @property
    def camera_names(self) -> tuple[str, ...]:
        """Names of the model's cameras (any can be an observation camera)."""
        return tuple(self.model.camera(i).name for i in range(self.model.ncam))

    # ---------------------------------------------------------- placement
    def place(self, position: Sequence[float], quat: Sequence[float] = (1.0, 0.0, 0.0, 0.0),
              scale: float = 1.0) -> None:
        """Scale the rig uniformly and put its root body at `position` with orientation `quat`."""
        s = float(scale)
        if not (math.isfinite(s) and s > 0):
            raise ValueError(f"Expected a positive finite rig scale, found {scale!r}")
        m = self.model
        m.body_pos[:] = self._nominal["body_pos"] * s
        # geoms whose frame coincides with their body's inertial frame are posed from it
        # (MuJoCo's geom_sameframe), so the inertial offsets scale too
        m.body_ipos[:] = self._nominal["body_ipos"] * s
        m.geom_pos[:] = self._nominal["geom_pos"] * s
        m.geom_size[:] = self._nominal["geom_size"] * s
        m.site_pos[:] = self._nominal["site_pos"] * s
        m.site_size[:] = self._nominal["site_size"] * s
        for i in range(m.ncam):
            if i not in self._world_cams:
                m.cam_pos[i] = self._nominal["cam_pos"][i] * s
        m.body_pos[self._root] = np.asarray(position, dtype=np.float64)
        q = np.asarray(quat, dtype=np.float64)
        m.body_quat[self._root] = q / np.linalg.norm(q)
        self.scale = s

    def set_world_camera(self, name: str, camera: Camera) -> None:
        """Pose a camera fixed to the world body (e.g. a third-person view) like `camera`."""
        i = self._id("camera", name)
        if i not in self._world_cams:
            raise ValueError(f"Expected a camera fixed to the world body, found {name!r} on a moving body")
        pos, xmat, fovy = camera.to_mujoco()
        q = np.empty(4)
        self._mj.mju_mat2Quat(q, np.asarray(xmat, dtype=np.float64))
        self.model.cam_pos[i] = pos
        self.model.cam_quat[i] = q
        self.model.cam_fovy[i] = fovy

    def set_camera_fov(self, name: str, fov_y_deg: float) -> None:
        """Set a camera's vertical field of view (degrees)."""
        f = float(fov_y_deg)
        if not (math.isfinite(f) and 0.0 < f < 180.0):
            raise ValueError(f"Expected a field of view in (0, 180) degrees, found {fov_y_deg!r}")
        self.model.cam_fovy[self._id("camera", name)] = f

    # ------------------------------------------------------------- joints
    @property
    def qpos(self) -> np.ndarray:
        """[J] positions of the hinge and slide joints (a copy)."""
        return self.data.qpos[self._qadr].copy()

    def set_joints(self, q: Sequence[float]) -> None:
        """Set hinge/slide joint positions (clipped to their ranges)."""
        q = np.asarray(q, dtype=np.float64).reshape(len(self._qadr))
        r = self.joint_range
        self.data.qpos[self._qadr] = np.minimum(np.maximum(q, r[:, 0]), r[:, 1])    # np.clip's values, cheaper

    def integrate_joints(self, rates: np.ndarray, dt: float) -> None:
        """Move the hinge/slide joints by `rates` (rad/s or m/s) for `dt` seconds, within their ranges."""
        self.set_joints(self.qpos + np.asarray(rates, dtype=np.float64) * float(dt))

    # ------------------------------------------------------------ kinematics
    def forward(self) -> None:
        """Forward kinematics: link, geom, site and camera poses from `qpos`."""
        self._mj.mj_kinematics(self.model, self.data)
        self._mj.mj_camlight(self.model, self.data)

    def camera(self, name: str, width: int, height: int, near: float | None = None) -> Camera:
        """The named MJCF camera as a `Camera` (after `forward`); `near` defaults to 1% of the rig scale."""
        i = self._id("camera", name)
        if near is None:
            near = 0.01 * self.scale if i not in self._world_cams else 0.01
        return mujoco_camera(self.data.cam_xpos[i], self.data.cam_xmat[i], float(self.model.cam_fovy[i]),
                             width, height, max(float(near), 1e-4))

    def site_position(self, name: str) -> np.ndarray:
        """[3] world position of a site (a copy)."""
        return self.data.site_xpos[self._id("site", name)].copy()

    def body_position(self, name: str) -> np.ndarray:
        """[3] world position of a body (a copy)."""
        return self.data.xpos[self._id("body", name)].copy()

    # ------------------------------------------------------------- drawing
    def gaussians(self) -> Gaussians:
        """The agent's geoms as world Gaussians in the current pose (instance id `AGENT_OBJECT_ID`)."""
        if self._skin is None:
            from .skin import AgentSkin

            self._skin = AgentSkin(self.model, AGENT_OBJECT_ID, budget=self._skin_budget,
                                   geom_size=self._nominal["geom_size"])
        return self._skin.gaussians(self.data, self.scale)
