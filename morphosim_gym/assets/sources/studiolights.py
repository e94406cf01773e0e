"""HDR sky panoramas: Blender's CC0 studio-light worlds (equirectangular EXR, z-up)."""

from __future__ import annotations

import os
from pathlib import Path

from ..record import AssetRecord
from .base import FileStat, file_stats

__all__ = ["DEFAULT_DIR", "StudioLightsSource"]

DEFAULT_DIR = "/usr/share/blender/datafiles/studiolights/world"
LICENCE = "CC0 (Greg Zaal, HDRI Haven)"


class StudioLightsSource:
    """Every `.exr` panorama in a folder (default: Debian's `blender-data` worlds)."""

    name = "studiolights"

    def __init__(self, folder: str | os.PathLike = DEFAULT_DIR) -> None:
        self.folder = Path(folder)

    @classmethod
    def discover(cls) -> StudioLightsSource | None:
        src = cls()
        return src if src.files() else None

    def files(self) -> list[Path]:
        return sorted(self.folder.glob("*.exr")) if self.folder.is_dir() else []

    def fingerprint(self) -> list[FileStat]:
        return file_stats(self.files())

    def records(self) -> list[AssetRecord]:
        return [AssetRecord(id=f"{self.name}/world/{p.stem}", name=p.stem, category="sky", source=self.name,
                            licence=LICENCE, kind="sky", path=str(p), tags=("sky", "hdri", "panorama"), up_axis="z")
                for p in self.files()]
