"""MorphoSim Gym: a language-driven, editable 4D world simulator for robot learning.

Text becomes a dynamic 3D Gaussian scene that can be edited by language and observed
from any camera pose through a fast CPU splatting renderer, wrapped as Gymnasium
environments. See the README for the tour.

The public names below are imported on first use (PEP 562), so `import morphosim_gym`
and the `morphosim` command line start without torch, numba or MuJoCo; importing the
package still registers the MorphoSim/*-v0 Gymnasium ids (string entry points, nothing built).
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import Any

from . import parallel as _parallel  # noqa: F401  first: asks numba for a fork-safe threading layer (see it)
from . import envs as _envs  # noqa: F401,E402  registers the MorphoSim/*-v0 Gymnasium ids (string entry points)

__version__ = "0.1.0"

# Public name -> the module that defines it; imported when the name is first read.
_LAZY: dict[str, str] = {
    "BackendUnavailableError": "morphosim_gym.errors",
    "CommandError": "morphosim_gym.errors",
    "EditError": "morphosim_gym.errors",
    "UnknownBackendError": "morphosim_gym.errors",
    "LLMConfig": "morphosim_gym.language.llm",
    "DiffusionConfig": "morphosim_gym.generate.diffusion.backend",
    "Plan": "morphosim_gym.language",
    "parse": "morphosim_gym.language",
    "MorphoSim": "morphosim_gym.pipeline",
    "SimConfig": "morphosim_gym.pipeline",
    "GenerationConfig": "morphosim_gym.generate.compose",
    "RenderOutput": "morphosim_gym.render",
    "rasterize": "morphosim_gym.render",
    "render": "morphosim_gym.render",
    **{name: "morphosim_gym.scene" for name in (
        "Camera", "FeatureDecoder", "GeneratedClip", "Gaussians", "Motion", "Provenance", "Scene4D",
        "SceneFileError", "SceneObject", "export_ply", "load_clip", "load_scene", "read_ply", "save_clip",
        "save_scene")},
}

__all__ = [
    "MorphoSim", "SimConfig", "GenerationConfig", "LLMConfig", "DiffusionConfig",
    "BackendUnavailableError", "CommandError", "EditError", "UnknownBackendError", "Plan", "parse",
    "RenderOutput", "rasterize", "render",
    "Camera", "FeatureDecoder", "GeneratedClip", "Gaussians", "Motion", "Provenance", "Scene4D",
    "SceneFileError", "SceneObject", "export_ply", "load_clip", "load_scene", "read_ply", "save_clip",
    "save_scene",
]


def __getattr__(name: str) -> Any:
    """Import a public name's module on first access and cache the name here."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


class _Package(types.ModuleType):
    """This package's module type: `morphosim_gym.render` stays the function even after the
    `morphosim_gym.render` subpackage is imported (the import system binds submodules on their parent)."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "render" and isinstance(value, types.ModuleType):
            value = value.render
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
