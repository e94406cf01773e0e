"""The converted-asset cache: `Gaussians` on disk under a content-hash key.

Entries are `.npz` files written atomically (temporary file + `os.replace`) that carry a sha256
of their arrays; a read that fails the check (a damaged or foreign file) warns, deletes the entry
and reports a miss, so the caller rebuilds it.
"""

from __future__ import annotations

import hashlib
import os
import warnings
import zipfile
from pathlib import Path

import numpy as np

from ..scene.gaussians import Gaussians
from ..scene.atomic import atomic_write_stream
from .errors import AssetWarning

__all__ = ["ConversionCache"]

_ARRAYS = ("means", "quats", "scales", "opacities", "colors")


def _digest(arrays: dict[str, np.ndarray]) -> bytes:
    h = hashlib.sha256()
    for name in _ARRAYS:
        a = np.ascontiguousarray(arrays[name], dtype=np.float32)
        h.update(name.encode())
        h.update(repr(a.shape).encode())
        h.update(a.tobytes())
    return h.digest()


class ConversionCache:
    """A folder of converted assets, one `<key>.npz` each (key: a hex content hash)."""

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)

    def path(self, key: str) -> Path:
        if not key or not all(c in "0123456789abcdef" for c in key):
            raise ValueError(f"Expected a lower-case hex cache key, found {key!r}")
        return self.root / key[:2] / f"{key}.npz"

    def get(self, key: str) -> Gaussians | None:
        """The cached Gaussians, or None (missing, or damaged: then warned about and removed)."""
        path = self.path(key)
        if not path.exists():
            return None
        try:
            with np.load(path, allow_pickle=False) as z:
                arrays = {name: z[name] for name in _ARRAYS}
                stored = bytes(z["digest"].astype(np.uint8))
            if stored != _digest(arrays):
                raise ValueError("checksum mismatch")
            return Gaussians(**arrays)
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
            warnings.warn(AssetWarning(f"Damaged asset cache entry {path} ({type(exc).__name__}: {exc}); "
                                       f"rebuilding it"), stacklevel=2)
            try:
                path.unlink()
            except OSError:
                pass
            return None

    def put(self, key: str, gaussians: Gaussians) -> Path:
        """Store `gaussians` under `key` (atomically)."""
        g = gaussians.numpy()
        arrays = {name: np.ascontiguousarray(getattr(g, name), dtype=np.float32) for name in _ARRAYS}
        digest = np.frombuffer(_digest(arrays), dtype=np.uint8)
        return atomic_write_stream(self.path(key), lambda f: np.savez(f, digest=digest, **arrays))
