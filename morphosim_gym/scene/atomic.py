"""Atomic file writes (temporary file + rename) and the sweep of temporaries that killed writers left.

A temporary is named `.<target>.<host>.<pid>.<random>.tmp` next to its target, so a later writer can
tell whose it is: one whose process no longer runs on this host, or that is older than
`STALE_TEMP_SECONDS` (a writer on another host of a shared cache, or a reused pid), is removed.
"""

from __future__ import annotations

import os
import re
import socket
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO

__all__ = ["STALE_TEMP_SECONDS", "atomic_write", "atomic_write_stream", "atomic_write_text", "sweep_stale_temps"]

STALE_TEMP_SECONDS = 15 * 60      # no write of one file takes this long
_DEAD_GRACE_SECONDS = 2.0          # a temp file is created a moment before its writer is recorded
_TEMP = re.compile(r"^\..+\.(?P<host>[A-Za-z0-9-]{1,32})\.(?P<pid>\d{1,10})\.[^.]+\.tmp$")


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:32] or "host"


def atomic_write(path: str | os.PathLike, chunks: list[bytes]) -> Path:
    """Write `chunks` to `path` so readers see the old file or the whole new one, never a part."""
    def write(fh: IO[bytes]) -> None:
        for c in chunks:
            fh.write(c)

    return atomic_write_stream(path, write)


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write UTF-8 `text` to `path` atomically."""
    return atomic_write(path, [text.encode("utf-8")])


def atomic_write_stream(path: str | os.PathLike, write: Callable[[IO[bytes]], None]) -> Path:
    """Create `path` atomically: `write(fh)` fills a temporary file that then replaces `path`. If
    `write` raises, the temporary is removed and `path` is left as it was."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{_host()}.{os.getpid()}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)          # mkstemp makes 0600 files; give the usual permissions
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def _pid_running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:                  # someone else's live process
        return True
    except (OverflowError, OSError):
        return False
    return True


def _is_stale(entry: Path, now: float, host: str) -> bool:
    if not entry.name.startswith("."):
        return False
    try:
        age = now - entry.stat().st_mtime
    except FileNotFoundError:
        return False
    if age > STALE_TEMP_SECONDS:                 # any writer's, including those of older versions
        return True
    m = _TEMP.match(entry.name)
    return m is not None and m["host"] == host and age > _DEAD_GRACE_SECONDS and not _pid_running(int(m["pid"]))


def sweep_stale_temps(directory: str | os.PathLike) -> list[Path]:
    """Remove the temporaries of writers that died in `directory` (not recursive); the paths removed."""
    directory = Path(directory)
    if not directory.is_dir():
        return []
    now, host, removed = time.time(), _host(), []
    for entry in directory.iterdir():
        if entry.name.endswith(".tmp") and _is_stale(entry, now, host):
            try:
                entry.unlink()
                removed.append(entry)
            except FileNotFoundError:
                pass
    return removed
