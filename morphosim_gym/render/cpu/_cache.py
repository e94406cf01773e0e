"""Keep numba's on-disk cache of these kernels consistent with their sources.

numba keys a cached kernel on its own source file only: a kernel that calls (and so compiles
in) a function from another module of this package keeps the old machine code after that
other module changes, silently. Here the sources of all modules of this package are hashed,
and the package's cache entries are deleted when the hash differs from the one stamped in the
cache directory at the last import. Costs well under a millisecond per process.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["invalidate_stale_cache"]

_STAMP = "morphosim_render_cpu.sourcehash"


def _source_hash(pkg_dir: Path) -> str:
    h = hashlib.sha256()
    for f in sorted(pkg_dir.glob("*.py")):
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def _cache_dir(probe) -> Path:
    """The directory numba caches `probe` (a plain function of this package) into."""
    from numba.core.caching import FunctionCache

    return Path(FunctionCache(probe)._cache_path)


def invalidate_stale_cache(probe) -> None:
    """Delete this package's numba cache files if any of its sources changed since they were written."""
    try:
        pkg_dir = Path(__file__).resolve().parent
        digest = _source_hash(pkg_dir)
        cache_dir = _cache_dir(probe)
        cache_dir.mkdir(parents=True, exist_ok=True)
        stamp = cache_dir / _STAMP
        if stamp.is_file() and stamp.read_text().strip() == digest:
            return
        modules = {f.stem for f in pkg_dir.glob("*.py")}
        for f in cache_dir.iterdir():
            if f.suffix in (".nbi", ".nbc") and f.name.split(".", 1)[0] in modules:
                try:
                    f.unlink()
                except OSError:
                    pass
        tmp = cache_dir / f"{_STAMP}.{os.getpid()}"
        tmp.write_text(digest)
        os.replace(tmp, stamp)
    except Exception:  # never let cache bookkeeping break rendering; numba then just recompiles
        pass
