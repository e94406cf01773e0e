"""MorphoSim Gym: a language-driven, editable 4D world simulator for robot learning.

Text becomes a dynamic 3D Gaussian scene that can be edited by language and observed
from any camera pose through a fast CPU splatting renderer, wrapped as Gymnasium
environments. See the README for the tour.
"""

from . import parallel as _parallel  # noqa: F401  first: asks numba for a fork-safe threading layer (see it)
from .errors import BackendUnavailableError, CommandError, EditError
from .language import Plan, parse
from .pipeline import MorphoSim, SimConfig
from .generate.compose import GenerationConfig
from .render import RenderOutput, rasterize, render
from .scene import (
    Camera,
    FeatureDecoder,
    GeneratedClip,
    Gaussians,
    Motion,
    Provenance,
    Scene4D,
    SceneFileError,
    SceneObject,
    export_ply,
    load_clip,
    load_scene,
    read_ply,
    save_clip,
    save_scene,
)

from . import envs as _envs  # noqa: E402,F401  registers the MorphoSim/*-v0 Gymnasium ids (string entry points)

__version__ = "0.1.0"

__all__ = [
    "MorphoSim", "SimConfig", "GenerationConfig",
    "BackendUnavailableError", "CommandError", "EditError", "Plan", "parse",
    "RenderOutput", "rasterize", "render",
    "Camera", "FeatureDecoder", "GeneratedClip", "Gaussians", "Motion", "Provenance", "Scene4D",
    "SceneFileError", "SceneObject", "export_ply", "load_clip", "load_scene", "read_ply", "save_clip",
    "save_scene",
]
