"""Rig layer: MJCF camera rigs and agents (kinematics only), their cameras and their Gaussians.

    from morphosim_gym.rig import PanTiltRig, FreeCameraRig, ArmRig
    arm = ArmRig()
    arm.place(base=(0, 0.5, 0), facing=(0, 0, 0), reach=0.6)
    cam = arm.camera("wrist", 84, 84)        # a morphosim_gym.Camera
    g = arm.gaussians()                      # the arm as Gaussians, to render with a scene

MJCF files ship in this package: `pan_tilt.xml`, `free_camera.xml`, `arm6.xml`.
"""

from .base import AGENT_OBJECT_ID, POSED_MODEL_FIELDS, RIG_DIR, Rig, RigState, yaw_quat
from .rigs import RIGS, ArmRig, FreeCameraRig, PanTiltRig
from .skin import AgentSkin, geom_part

__all__ = ["Rig", "RigState", "POSED_MODEL_FIELDS", "PanTiltRig", "FreeCameraRig", "ArmRig", "RIGS", "AgentSkin",
           "geom_part", "AGENT_OBJECT_ID", "RIG_DIR", "yaw_quat"]
