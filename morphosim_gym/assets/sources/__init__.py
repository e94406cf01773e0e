"""Asset sources, found at run time: each is skipped when it is not installed.

`default_sources()` lists what this machine has: Sweet Home 3D furniture catalogues, robosuite's
objects, Blender's sky panoramas, 0 A.D.'s animals and props, LIBERO's groceries and kitchenware,
FlightGear's aircraft, vehicles, ships and buildings, and the user folders (`$MORPHOSIM_ASSETS`, `asset_dirs`).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence

from .base import AssetSource, FileStat
from .flightgear import FlightGearSource
from .folder import FolderSource, folders_from_env
from .libero import LiberoSource
from .robosuite import RobosuiteSource
from .studiolights import StudioLightsSource
from .sweethome3d import SweetHome3DSource
from .zero_ad import ZeroADSource

__all__ = [
    "SYSTEM_SOURCES",
    "AssetSource",
    "FileStat",
    "FlightGearSource",
    "FolderSource",
    "LiberoSource",
    "RobosuiteSource",
    "StudioLightsSource",
    "SweetHome3DSource",
    "ZeroADSource",
    "default_sources",
]

# name -> discover(): the sources installed system-wide (None when absent)
SYSTEM_SOURCES: dict[str, Callable[[], AssetSource | None]] = {
    SweetHome3DSource.name: SweetHome3DSource.discover,
    RobosuiteSource.name: RobosuiteSource.discover,
    StudioLightsSource.name: StudioLightsSource.discover,
    ZeroADSource.name: ZeroADSource.discover,
    LiberoSource.name: LiberoSource.discover,
    FlightGearSource.name: FlightGearSource.discover,
}


def default_sources(asset_dirs: Sequence[str | os.PathLike] = (), *, system: Sequence[str] | None = None,
                    use_env: bool = True) -> list[AssetSource]:
    """The sources available here.

    Args:
        asset_dirs: extra user folders of meshes.
        system: names of system sources to look for (default all of `SYSTEM_SOURCES`).
        use_env: also use the folders of `$MORPHOSIM_ASSETS`.
    """
    names = list(SYSTEM_SOURCES) if system is None else list(system)
    unknown = [n for n in names if n not in SYSTEM_SOURCES]
    if unknown:
        raise ValueError(f"Expected system sources among {sorted(SYSTEM_SOURCES)}, found {unknown}")
    out: list[AssetSource] = [s for s in (SYSTEM_SOURCES[n]() for n in names) if s is not None]
    folders = (folders_from_env() if use_env else []) + [os.fspath(d) for d in asset_dirs]
    out.extend(FolderSource(d) for d in folders)
    return out
