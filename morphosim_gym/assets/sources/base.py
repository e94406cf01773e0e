"""What every asset source provides, and small helpers they share."""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Protocol, runtime_checkable

from ..errors import AssetWarning
from ..record import AssetRecord

__all__ = ["AssetSource", "FileStat", "file_stats", "slug", "unique_ids", "warn_skip"]

FileStat = tuple[str, int, int]   # (path, size in bytes, modification time in ns)


@runtime_checkable
class AssetSource(Protocol):
    """A place assets come from.

    `fingerprint()` must be cheap (file stats only): the index rebuilds a source's records only
    when its fingerprint changes. `records()` may read catalogues but never converts meshes; a
    broken entry is skipped with an `AssetWarning` naming the file.
    """

    name: str

    def fingerprint(self) -> list[FileStat]: ...

    def records(self) -> list[AssetRecord]: ...


def file_stats(paths: Iterable[str | os.PathLike]) -> list[FileStat]:
    """(path, size, mtime_ns) of each existing file, sorted by path; missing files are left out."""
    out = []
    for p in paths:
        try:
            st = os.stat(p)
        except OSError:
            continue
        out.append((str(p), int(st.st_size), int(st.st_mtime_ns)))
    return sorted(out)


def slug(text: str) -> str:
    """Lower-case id fragment: letters, digits and dashes."""
    s = re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")
    return s or "asset"


def unique_ids(records: list[AssetRecord]) -> list[AssetRecord]:
    """The records with repeated ids made unique by a "-2", "-3"... suffix (first one unchanged)."""
    from dataclasses import replace

    seen: dict[str, int] = {}
    out = []
    for r in records:
        n = seen.get(r.id, 0) + 1
        seen[r.id] = n
        out.append(r if n == 1 else replace(r, id=f"{r.id}-{n}"))
    return out


def warn_skip(path: str | Path, reason: str) -> None:
    """Warn that a file was skipped, naming it."""
    warnings.warn(AssetWarning(f"Skipping {path}: {reason}"), stacklevel=3)
