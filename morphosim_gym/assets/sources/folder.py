"""A user folder of meshes (OBJ, GLB/GLTF, PLY, AC3D) and 3DGS `.ply` files.

Folders come from `$MORPHOSIM_ASSETS` (several separated by `os.pathsep`) or `--assets DIR`.
One up axis and unit per folder: y-up and metres (the glTF convention) unless the folder holds a
`morphosim_assets.json` such as `{"up_axis": "z", "unit_scale": 0.001, "licence": "CC-BY 4.0"}`.
A file's category is its parent folder's name when it sits in a sub-folder ("dogs/corgi.glb" ->
"dogs"), else "object".
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..record import UP_AXES, AssetRecord
from .base import FileStat, file_stats, slug, unique_ids, warn_skip

__all__ = ["ENV_VAR", "MESH_SUFFIXES", "SETTINGS_FILE", "FolderSource", "folders_from_env"]

MESH_SUFFIXES = (".obj", ".glb", ".gltf", ".ply", ".ac")
ENV_VAR = "MORPHOSIM_ASSETS"
SETTINGS_FILE = "morphosim_assets.json"
_SETTINGS = {"up_axis": str, "unit_scale": (int, float), "licence": str}
_PLY_SPLAT_FIELDS = (b"f_dc_0", b"opacity", b"scale_0", b"rot_0")


def folders_from_env() -> list[Path]:
    """The folders named in `$MORPHOSIM_ASSETS`."""
    value = os.environ.get(ENV_VAR, "")
    return [Path(p) for p in value.split(os.pathsep) if p.strip()]


def _is_splat_ply(path: Path) -> bool:
    """Whether a `.ply` header declares 3DGS fields (then it is a splat, not a mesh)."""
    with open(path, "rb") as f:
        head = f.read(4096)
    header = head.split(b"end_header", 1)[0]
    return any(name in header for name in _PLY_SPLAT_FIELDS)


class FolderSource:
    """Meshes and splats found under one folder (recursively)."""

    name = "folder"

    def __init__(self, folder: str | os.PathLike, up_axis: str | None = None, unit_scale: float | None = None,
                 licence: str | None = None) -> None:
        self.folder = Path(folder)
        given = {"up_axis": up_axis, "unit_scale": unit_scale, "licence": licence}
        settings = {"up_axis": "y", "unit_scale": 1.0, "licence": "user-provided", **self._settings_file()}
        settings.update({k: v for k, v in given.items() if v is not None})
        self.up_axis, self.unit_scale, self.licence = settings["up_axis"], float(settings["unit_scale"]), \
            settings["licence"]

    def _settings_file(self) -> dict:
        """The folder's `morphosim_assets.json`, checked (`ValueError` naming the file and key)."""
        path = self.folder / SETTINGS_FILE
        if not path.is_file():
            return {}
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ValueError(f"Cannot read the asset folder settings {path}: {exc}") from None
        if not isinstance(data, dict):
            raise ValueError(f"Expected a JSON object in {path}, found {type(data).__name__}")  # noqa: TRY004
        for key, value in data.items():
            if key not in _SETTINGS:
                raise ValueError(f"Unknown key {key!r} in {path} (expected {', '.join(_SETTINGS)})")
            if not isinstance(value, _SETTINGS[key]) or isinstance(value, bool):
                raise ValueError(f"Expected {key!r} in {path} to be {_SETTINGS[key]}, found {value!r}")  # noqa: TRY004
        if "up_axis" in data and data["up_axis"] not in UP_AXES:
            raise ValueError(f"Expected 'up_axis' in {path} among {UP_AXES}, found {data['up_axis']!r}")
        if "unit_scale" in data and not data["unit_scale"] > 0:
            raise ValueError(f"Expected 'unit_scale' in {path} > 0, found {data['unit_scale']!r}")
        return data

    def files(self) -> list[Path]:
        """The asset files under the folder, sorted."""
        if not self.folder.is_dir():
            return []
        return sorted(p for p in self.folder.rglob("*") if p.suffix.lower() in MESH_SUFFIXES and p.is_file())

    def fingerprint(self) -> list[FileStat]:
        return file_stats([*self.files(), self.folder / SETTINGS_FILE])

    def records(self) -> list[AssetRecord]:
        out = []
        collection = slug(self.folder.name)
        for path in self.files():
            try:
                kind = "splat" if path.suffix.lower() == ".ply" and _is_splat_ply(path) else "mesh"
            except OSError as exc:
                warn_skip(path, f"unreadable ({exc})")
                continue
            rel = path.relative_to(self.folder)
            category = rel.parent.name if rel.parent != Path(".") else "object"
            name = path.stem.replace("_", " ").replace("-", " ")
            out.append(AssetRecord(
                id=f"{self.name}/{collection}/{slug(str(rel.with_suffix('')))}", name=name, category=category,
                source=self.name, licence=self.licence, kind=kind, path=str(path), up_axis=self.up_axis,
                unit_scale=self.unit_scale, tags=tuple(w for w in slug(name).split("-") if w)))
        return unique_ids(out)
