"""Scene and clip files: `save_scene` / `load_scene`, `save_clip` / `load_clip` (the container format
is in `container.py`, single frames as `.ply` in `ply.py`).

Identical arrays are stored once, so an edited scene that carries its undo history costs little
more than the scene itself. Writes are atomic (temporary file + rename). Every problem reading a
file is a `SceneFileError` whose message names the file.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from .clip import GeneratedClip
from .container import FORMAT_VERSION, SceneFileError, peek_kind, read_container, write_container
from .features import FeatureDecoder
from .gaussians import Gaussians
from .motion import Motion
from .ply import export_ply, read_ply
from .scene4d import Scene4D, cameras_from_dicts, objects_from_dicts, provenance_from_dict

__all__ = ["SceneFileError", "save_scene", "load_scene", "save_clip", "load_clip", "export_ply", "read_ply",
           "FORMAT_VERSION", "peek_kind"]

# content errors of a file whose checksums hold (a crafted file): all reported as SceneFileError
_CONTENT_ERRORS = (KeyError, TypeError, ValueError, AttributeError, IndexError, OverflowError, RecursionError)


def _content_error(path: str | os.PathLike, kind: str, exc: BaseException) -> SceneFileError:
    if isinstance(exc, KeyError):
        return SceneFileError(f"{path}: corrupted {kind} content (missing {exc})")
    return SceneFileError(f"{path}: invalid {kind} content ({type(exc).__name__}: {str(exc)[:200]})")


# --------------------------------------------------------------------- scene
def _scene_chain(scene: Scene4D) -> list[Scene4D]:
    chain = []
    s: Scene4D | None = scene
    while s is not None:
        chain.append(s)
        s = s.parent
    return chain[::-1]


def save_scene(scene: Scene4D, path: str | os.PathLike, history: bool = True) -> Path:
    """Write a scene (and, with `history`, the scenes it was edited from, for `undo`) to one file.

    Examples:
        >>> save_scene(scene, "bus.msim"); load_scene("bus.msim")  # doctest: +SKIP
    """
    chain = _scene_chain(scene) if history else [scene]
    arrays: dict[str, np.ndarray] = {}
    metas = []
    for i, s in enumerate(chain):
        metas.append(s.metadata())
        arrays.update({f"{i}/{k}": v for k, v in s.arrays().items()})
    return write_container(path, "scene", {"scenes": metas}, arrays)


def _scene_from(meta: dict, arrays: dict[str, np.ndarray], parent: Scene4D | None) -> Scene4D:
    g = Gaussians(**{k: arrays.get(f"gaussians/{k}") for k in
                     ("means", "quats", "scales", "opacities", "colors", "features", "object_ids")})
    motion = Motion(**{k: arrays[f"motion/{k}"] for k in
                       ("rotations", "translations", "skin_nodes", "skin_weights", "node_objects")},
                    shown=arrays.get("motion/shown"))
    decoders = {}
    for name, dm in meta["decoders"].items():
        prefix = f"decoders/{name}/"
        decoders[name] = FeatureDecoder.from_arrays(
            name, {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}, dm["normalize"])
    # Motion normalises quaternions on construction; keep the stored bits exactly.
    motion.rotations = arrays["motion/rotations"]
    return Scene4D(gaussians=g, motion=motion, objects=objects_from_dicts(meta["objects"]), fps=meta["fps"],
                   cameras=cameras_from_dicts(meta["cameras"]), decoders=decoders,
                   provenance=provenance_from_dict(meta["provenance"]), background=tuple(meta["background"]),
                   parent=parent, sky=arrays.get("sky"), sensor=tuple(tuple(e) for e in meta.get("sensor", ())))


def load_scene(path: str | os.PathLike) -> Scene4D:
    """Read a scene written by `save_scene`, bit-exact, with its undo history."""
    meta, arrays = read_container(path, "scene")
    try:
        scene = None
        for i, m in enumerate(meta["scenes"]):
            prefix = f"{i}/"
            scene = _scene_from(m, {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}, scene)
    except SceneFileError:
        raise
    except _CONTENT_ERRORS as exc:
        raise _content_error(path, "scene", exc) from None
    if scene is None:
        raise SceneFileError(f"{path}: invalid scene content (no scenes)")
    return scene


# ---------------------------------------------------------------------- clip
def save_clip(clip: GeneratedClip, path: str | os.PathLike) -> Path:
    """Write a clip (frames, cameras, priors, and its ground truth if any) to one file."""
    arrays = {"frames": clip.frames}
    for name in ("depth", "masks", "tracks", "track_visible"):
        if getattr(clip, name) is not None:
            arrays[name] = getattr(clip, name)
    meta: dict[str, Any] = {"cameras": [c.to_dict() for c in clip.cameras], "fps": clip.fps,
                            "labels": {str(k): v for k, v in clip.labels.items()}, "prompt": clip.prompt,
                            "info": clip.info, "ground_truth": None}
    if clip.ground_truth is not None:
        gt = clip.ground_truth
        meta["ground_truth"] = gt.metadata()
        arrays.update({f"gt/{k}": v for k, v in gt.arrays().items()})
    return write_container(path, "clip", meta, arrays)


def load_clip(path: str | os.PathLike) -> GeneratedClip:
    """Read a clip written by `save_clip`."""
    meta, arrays = read_container(path, "clip")
    try:
        gt = None
        if meta.get("ground_truth") is not None:
            gt = _scene_from(meta["ground_truth"], {k[3:]: v for k, v in arrays.items() if k.startswith("gt/")},
                             None)
        return GeneratedClip(frames=arrays["frames"], cameras=cameras_from_dicts(meta["cameras"]), fps=meta["fps"],
                             depth=arrays.get("depth"), masks=arrays.get("masks"),
                             labels={int(k): v for k, v in meta["labels"].items()}, tracks=arrays.get("tracks"),
                             track_visible=arrays.get("track_visible"), prompt=meta.get("prompt", ""),
                             ground_truth=gt, info=meta.get("info", {}))
    except SceneFileError:
        raise
    except _CONTENT_ERRORS as exc:
        raise _content_error(path, "clip", exc) from None


