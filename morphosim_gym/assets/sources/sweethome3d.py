"""Sweet Home 3D furniture catalogues (`.sh3f` zips): names, categories, sizes and licences.

Each zip holds `PluginFurnitureCatalog.properties` (Java properties: `name#3=Bed`,
`category#3=Bedroom`, `width#3=160` in cm...) and the OBJ+MTL models with their textures.
Models are y-up; Sweet Home 3D stretches each model to its width (x), height (y) and depth (z).
"""

from __future__ import annotations

import os
import re
import zipfile
from pathlib import Path

from ..record import AssetRecord
from .base import FileStat, file_stats, slug, unique_ids, warn_skip

__all__ = ["DEFAULT_DIR", "SweetHome3DSource", "parse_properties"]

DEFAULT_DIR = "/usr/share/sweethome3d/furniture"
CATALOG = "PluginFurnitureCatalog.properties"
_ESCAPE = re.compile(r"\\u([0-9a-fA-F]{4})|\\(.)")


def _unescape(text: str) -> str:
    return _ESCAPE.sub(lambda m: chr(int(m.group(1), 16)) if m.group(1) else m.group(2), text)


def parse_properties(text: str) -> dict[str, str]:
    """Java `.properties` text -> dict (comments, line continuations and \\uXXXX escapes handled)."""
    out: dict[str, str] = {}
    lines = iter(text.splitlines())
    for line in lines:
        line = line.lstrip()
        if not line or line[0] in "#!":
            continue
        while line.endswith("\\") and not line.endswith("\\\\"):
            line = line[:-1] + next(lines, "").lstrip()
        m = re.match(r"((?:\\.|[^=:\s])+)\s*[=:\s]\s*(.*)$", line)
        if m:
            out[_unescape(m.group(1))] = _unescape(m.group(2)).strip()
    return out


def _entries(props: dict[str, str]) -> dict[int, dict[str, str]]:
    """Group `key#N=value` into {N: {key: value}}."""
    out: dict[int, dict[str, str]] = {}
    for key, value in props.items():
        head, sep, num = key.rpartition("#")
        if sep and num.isdigit():
            out.setdefault(int(num), {})[head] = value
    return out


def _size_and_rotation(e: dict[str, str]) -> tuple[tuple[float, float, float], tuple[float, ...] | None]:
    """(width, depth, height) in cm and the 9-number model rotation (or None) of one entry."""
    size_cm = (float(e["width"]), float(e["depth"]), float(e["height"]))
    if min(size_cm) <= 0:
        raise ValueError(f"non-positive size {size_cm}")
    rotation = tuple(float(x) for x in e["modelRotation"].split()) if "modelRotation" in e else None
    if rotation is not None and len(rotation) != 9:
        raise ValueError(f"a rotation of {len(rotation)} numbers, not 9")
    return size_cm, rotation


class SweetHome3DSource:
    """Every `.sh3f` catalogue in a folder (default: the Debian `sweethome3d-furniture` one)."""

    name = "sweethome3d"

    def __init__(self, folder: str | os.PathLike = DEFAULT_DIR) -> None:
        self.folder = Path(folder)

    @classmethod
    def discover(cls) -> SweetHome3DSource | None:
        """The installed catalogues, or None when there are none."""
        src = cls()
        return src if src.catalogues() else None

    def catalogues(self) -> list[Path]:
        """The `.sh3f` files of the folder, sorted."""
        return sorted(self.folder.glob("*.sh3f")) if self.folder.is_dir() else []

    def fingerprint(self) -> list[FileStat]:
        return file_stats(self.catalogues())

    def records(self) -> list[AssetRecord]:
        out: list[AssetRecord] = []
        for zpath in self.catalogues():
            try:
                out.extend(self._catalogue_records(zpath))
            except (zipfile.BadZipFile, KeyError, OSError, UnicodeDecodeError) as exc:
                warn_skip(zpath, f"not a readable furniture catalogue ({type(exc).__name__}: {exc})")
        return unique_ids(out)

    def _catalogue_records(self, zpath: Path) -> list[AssetRecord]:
        with zipfile.ZipFile(zpath) as z:
            props = parse_properties(z.read(CATALOG).decode("latin-1"))
            members = set(z.namelist())
        licence = props.get("license", "unknown")
        collection = slug(zpath.stem)
        out = []
        for num, e in sorted(_entries(props).items()):
            record = self._entry_record(zpath, collection, licence, num, e, members)
            if record is not None:
                out.append(record)
        return out

    def _entry_record(self, zpath: Path, collection: str, licence: str, num: int, e: dict[str, str],
                      members: set[str]) -> AssetRecord | None:
        member = e.get("model", "").lstrip("/")
        where = f"{zpath}!{member or f'entry #{num}'}"
        if not member.lower().endswith(".obj"):
            warn_skip(where, f"entry #{num} has no OBJ model")
            return None
        if member not in members:
            warn_skip(where, f"entry #{num} names a model the catalogue does not contain")
            return None
        try:
            size_cm, rotation = _size_and_rotation(e)
        except (KeyError, ValueError) as exc:
            warn_skip(where, f"entry #{num} has a missing or bad size or rotation ({exc})")
            return None
        tags = tuple(t.strip().lower() for t in e.get("tags", "").split(",") if t.strip())
        return AssetRecord(
            id=f"{self.name}/{collection}/{slug(Path(member).stem)}", name=e.get("name", Path(member).stem),
            category=e.get("category", "Miscellaneous"), source=self.name, licence=licence, kind="mesh",
            path=str(zpath), member=member, tags=tags, up_axis="y", unit_scale=0.01,
            size_m=tuple(round(s / 100.0, 6) for s in size_cm), model_rotation=rotation,
            creator=e.get("creator", ""), extra={"collection": zpath.stem})
