"""World state: Gaussians, cameras, motion, 4D scenes, clips and their files.

Also the geometry every higher layer shares (the lowest layer that needs it owns it): `camera`
(`Camera`, `camera_path`), `rotations` (quaternions, `normal_quats`), `primitives` and `parts`
(shapes sampled as surface Gaussians), `lighting` (the fixed sun baked into colours).
"""

from .camera import Camera
from .clip import GeneratedClip
from .features import INSTANCE_DIM, FeatureDecoder, instance_codes
from .gaussians import Gaussians
from .io import SceneFileError, export_ply, load_clip, load_scene, read_ply, save_clip, save_scene
from .motion import Motion
from .scene4d import Provenance, Scene4D, SceneObject

__all__ = [
    "Camera", "GeneratedClip", "FeatureDecoder", "INSTANCE_DIM", "instance_codes", "Gaussians", "Motion", "Provenance", "Scene4D", "SceneObject",
    "SceneFileError", "save_scene", "load_scene", "save_clip", "load_clip", "export_ply", "read_ply",
]
