"""The converted-asset cache: `Gaussians` on disk under a content-hash key.

Entries are `.npz` files that carry a sha256 of their arrays. `get_or_build` goes through
`scene.diskcache.load_or_build`: an entry is verified on read, a damaged one (truncated, altered
or foreign) is removed with a `DamagedAssetCacheWarning` and built again, and writes are atomic
(temporary file + `os.replace`).
"""

from __future__ import annotations

import hashlib
import os
import warnings
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..scene.atomic import atomic_write_stream
from ..scene.container import SceneFileError
from ..scene.diskcache import DamagedCacheEntryWarning, load_or_build
from ..scene.gaussians import Gaussians
from .errors import AssetWarning

__all__ = ["ConversionCache", "DamagedAssetCacheWarning"]

_ARRAYS = ("means", "quats", "scales", "opacities", "colors")
_READ_ERRORS = (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile)


class DamagedAssetCacheWarning(DamagedCacheEntryWarning, AssetWarning):
    """A converted-asset cache entry failed its checksum on read; it was removed and is rebuilt."""


def _digest(arrays: dict[str, np.ndarray]) -> bytes:
    h = hashlib.sha256()
    for name in _ARRAYS:
        a = np.ascontiguousarray(arrays[name], dtype=np.float32)
        h.update(name.encode())
        h.update(repr(a.shape).encode())
        h.update(a.tobytes())
    return h.digest()


def read_entry(path: Path) -> Gaussians:
    """The Gaussians of a cache entry; `SceneFileError` naming the file when it fails its checks."""
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {name: z[name] for name in _ARRAYS}
            stored = bytes(z["digest"].astype(np.uint8))
        if stored != _digest(arrays):
            raise ValueError("checksum mismatch")
        return Gaussians(**arrays)
    except _READ_ERRORS as exc:
        raise SceneFileError(f"Damaged asset cache entry {path} ({type(exc).__name__}: {exc}); rebuilding it") \
            from exc


def write_entry(gaussians: Gaussians, path: Path) -> Path:
    """Store `gaussians` at `path` with the checksum of its arrays (atomically)."""
    g = gaussians.numpy()
    arrays = {name: np.ascontiguousarray(getattr(g, name), dtype=np.float32) for name in _ARRAYS}
    digest = np.frombuffer(_digest(arrays), dtype=np.uint8)
    return atomic_write_stream(path, lambda f: np.savez(f, digest=digest, **arrays))


class ConversionCache:
    """A folder of converted assets, one `<key>.npz` each (key: a hex content hash)."""

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)

    def path(self, key: str) -> Path:
        if not key or not all(c in "0123456789abcdef" for c in key):
            raise ValueError(f"Expected a lower-case hex cache key, found {key!r}")
        return self.root / key[:2] / f"{key}.npz"

    def get_or_build(self, key: str, build: Callable[[], Gaussians], label: str = "") -> Gaussians:
        """The cached Gaussians of `key`, else `build()` stored there. A damaged entry is rebuilt
        with a `DamagedAssetCacheWarning`; a failed write (read-only or full disk) costs only the
        caching, with an `AssetWarning` naming `label`."""
        return load_or_build(self.path(key), read_entry, build, lambda g, p: self._put_quietly(g, p, label),
                             warning=DamagedAssetCacheWarning)

    def get(self, key: str) -> Gaussians | None:
        """The cached Gaussians, or None (missing, or damaged: then warned about and removed)."""
        path = self.path(key)
        if not path.exists():
            return None
        try:
            return read_entry(path)
        except SceneFileError as exc:
            warnings.warn(DamagedAssetCacheWarning(str(exc)), stacklevel=2)
            try:
                path.unlink()
            except OSError:
                pass
            return None

    def put(self, key: str, gaussians: Gaussians) -> Path:
        """Store `gaussians` under `key` (atomically)."""
        return write_entry(gaussians, self.path(key))

    def _put_quietly(self, gaussians: Gaussians, path: Path, label: str) -> None:
        try:
            write_entry(gaussians, path)
        except OSError as exc:
            warnings.warn(AssetWarning(f"Could not cache {label or path.name} in {self.root} ({exc})"), stacklevel=4)
