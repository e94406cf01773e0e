"""A file cache entry that is verified on read: a damaged one is discarded (with a warning) and built
again, and temporaries that killed writers left in its directory are swept."""

from __future__ import annotations

import os
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from .atomic import sweep_stale_temps
from .container import SceneFileError

__all__ = ["DamagedCacheEntryWarning", "load_or_build"]

T = TypeVar("T")
_SWEEP_EVERY_SECONDS = 60.0
_last_sweep: dict[Path, float] = {}


class DamagedCacheEntryWarning(RuntimeWarning):
    """A cache entry failed its checks on read; it was removed and is being built again."""


def _sweep(directory: Path) -> None:
    now = time.monotonic()
    if now - _last_sweep.get(directory, -_SWEEP_EVERY_SECONDS) >= _SWEEP_EVERY_SECONDS:
        _last_sweep[directory] = now
        sweep_stale_temps(directory)


def load_or_build(path: str | os.PathLike, load: Callable[[Path], T], build: Callable[[], T],
                  save: Callable[[T, Path], object],
                  warning: type[DamagedCacheEntryWarning] = DamagedCacheEntryWarning) -> T:
    """The value stored at `path` if it reads back (its checksums hold), else `build()` saved there.

    `load` must raise `SceneFileError` for a file it cannot trust; such an entry is deleted with a
    `DamagedCacheEntryWarning` (or the subclass `warning`) naming it, so the next call does not fail
    on it again.
    """
    path = Path(path)
    if path.exists():
        try:
            return load(path)
        except SceneFileError as exc:
            warnings.warn(f"Discarding a damaged cache entry and building it again: {exc}",
                          warning, stacklevel=3)
            try:
                path.unlink()
            except FileNotFoundError:
                pass
    _sweep(path.parent)
    value = build()
    save(value, path)
    return value
