"""A user folder of meshes (OBJ, GLB/GLTF, PLY) and 3DGS `.ply` files.

Folders come from `$MORPHOSIM_ASSETS` (several separated by `os.pathsep`) or `--assets DIR`.
One up axis and unit per folder (default y-up, metres: the glTF convention). A file's category is
its parent folder's name when it sits in a sub-folder ("dogs/corgi.glb" -> "dogs"), else "object".
"""

from __future__ import annotations

import os
from pathlib import Path

from ..record import AssetRecord
from .base import FileStat, file_stats, slug, unique_ids, warn_skip

__all__ = ["ENV_VAR", "MESH_SUFFIXES", "FolderSource", "folders_from_env"]

MESH_SUFFIXES = (".obj", ".glb", ".gltf", ".ply")
ENV_VAR = "MORPHOSIM_ASSETS"
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

    def __init__(self, folder: str | os.PathLike, up_axis: str = "y", unit_scale: float = 1.0,
                 licence: str = "user-provided") -> None:
        self.folder = Path(folder)
        self.up_axis, self.unit_scale, self.licence = up_axis, unit_scale, licence

    def files(self) -> list[Path]:
        """The asset files under the folder, sorted."""
        if not self.folder.is_dir():
            return []
        return sorted(p for p in self.folder.rglob("*") if p.suffix.lower() in MESH_SUFFIXES and p.is_file())

    def fingerprint(self) -> list[FileStat]:
        return file_stats(self.files())

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
