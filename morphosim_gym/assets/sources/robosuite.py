"""robosuite's textured object meshes (bread, can, cereal, lemon, milk, bottle): z-up, metres.

Only the installed files are read (importing robosuite itself fails without its optional
dependencies). Each object's MJCF (`objects/<name>.xml`) gives the mesh scale; the OBJ next to
the mesh it names carries the UVs and an MTL whose texture path climbs out of the mesh folder.
"""

from __future__ import annotations

import importlib.util
import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..record import AssetRecord
from .base import FileStat, file_stats, warn_skip

__all__ = ["RobosuiteSource", "robosuite_objects_dir"]

LICENCE = "MIT (robosuite)"
# robosuite's object names -> (category, tags)
_CATEGORIES: dict[str, tuple[str, tuple[str, ...]]] = {
    "bread": ("food", ("bread", "loaf")),
    "can": ("can", ("soda", "drink", "tin")),
    "cereal": ("box", ("cereal", "food", "carton")),
    "lemon": ("fruit", ("lemon", "food")),
    "milk": ("carton", ("milk", "drink", "bottle")),
    "bottle": ("bottle", ("glass", "drink")),
}


def robosuite_objects_dir() -> Path | None:
    """robosuite's `models/assets/objects` folder, found without importing robosuite."""
    try:
        spec = importlib.util.find_spec("robosuite")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    folder = Path(next(iter(spec.submodule_search_locations))) / "models" / "assets" / "objects"
    return folder if folder.is_dir() else None


def _obj_extents(text: str) -> np.ndarray:
    verts = np.array([[float(x) for x in line.split()[1:4]] for line in text.splitlines() if line.startswith("v ")])
    if verts.size == 0:
        raise ValueError("no vertices")
    return verts.max(axis=0) - verts.min(axis=0)


class RobosuiteSource:
    """The objects of an installed robosuite (or of a folder laid out like its `objects/`)."""

    name = "robosuite"

    def __init__(self, folder: str | os.PathLike) -> None:
        self.folder = Path(folder)

    @classmethod
    def discover(cls) -> RobosuiteSource | None:
        folder = robosuite_objects_dir()
        return cls(folder) if folder is not None else None

    def _pairs(self) -> list[tuple[str, Path, Path]]:
        """(name, MJCF, OBJ) of each object that has both."""
        out = []
        for xml in sorted(self.folder.glob("*.xml")):
            name = xml.stem
            obj = self.folder / "meshes" / f"{name}.obj"
            if name in _CATEGORIES and obj.is_file():
                out.append((name, xml, obj))
        return out

    def fingerprint(self) -> list[FileStat]:
        return file_stats(p for _, xml, obj in self._pairs() for p in (xml, obj))

    def records(self) -> list[AssetRecord]:
        out = []
        for name, xml, obj in self._pairs():
            try:
                scale = self._mesh_scale(xml)
                size = _obj_extents(obj.read_text(errors="replace")) * scale
            except (OSError, ET.ParseError, ValueError) as exc:
                warn_skip(obj, f"unreadable robosuite object ({type(exc).__name__}: {exc})")
                continue
            category, tags = _CATEGORIES[name]
            out.append(AssetRecord(
                id=f"{self.name}/objects/{name}", name=name, category=category, source=self.name, licence=LICENCE,
                kind="mesh", path=str(obj), tags=tags, up_axis="z", unit_scale=1.0,
                size_m=tuple(round(float(s), 6) for s in size), creator="robosuite",
                extra={"mesh_scale": [float(s) for s in scale]}))
        return out

    @staticmethod
    def _mesh_scale(xml: Path) -> np.ndarray:
        mesh = ET.parse(xml).getroot().find("./asset/mesh")
        text = mesh.get("scale", "1 1 1") if mesh is not None else "1 1 1"
        scale = np.array([float(x) for x in re.split(r"\s+", text.strip())])
        if scale.shape != (3,) or scale.min() <= 0:
            raise ValueError(f"bad mesh scale {text!r}")
        return scale
