"""The sweep's append-only result log: one JSON line per finished episode, durable on return.

`append` writes a whole line with one `write` on an `O_APPEND` descriptor and `fsync`s it
before returning, so a runner killed at any instant leaves every reported episode on disk and
at most a torn last line, which `load` drops (and `open` truncates before appending again).
A rerun reads the done keys and runs only the rest: nothing lost, nothing duplicated.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Iterator

__all__ = ["ResultStore", "atomic_write_bytes"]


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write a file so that readers see the old content or the new, never a part (temp + rename)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


class ResultStore:
    """JSON-lines records keyed by `record["key"]`.

    Args:
        path: the `.jsonl` file (created on first append).
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._fd: int | None = None

    def _lines(self) -> Iterator[dict]:
        if not self.path.exists():
            return
        data = self.path.read_bytes()
        for line in data.split(b"\n"):
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:          # a torn last line from a killed writer
                continue
            if isinstance(rec, dict) and "key" in rec:
                yield rec

    def load(self) -> dict[str, dict]:
        """Records by key (the first of any repeated key wins)."""
        out: dict[str, dict] = {}
        for rec in self._lines():
            out.setdefault(str(rec["key"]), rec)
        return out

    def open(self) -> None:
        """Open for appending, first cutting a torn last line (one without its newline)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if self.path.exists():
            data = self.path.read_bytes()
            if data and not data.endswith(b"\n"):
                with open(self.path, "r+b") as fh:
                    fh.truncate(data.rfind(b"\n") + 1)
                    fh.flush()
                    os.fsync(fh.fileno())
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def append(self, record: dict) -> None:
        """Append one record durably (a full line, fsync'd)."""
        if "key" not in record:
            raise ValueError(f"Expected a record with a 'key', found keys {sorted(record)}")
        if self._fd is None:
            self.open()
        line = (json.dumps(record, sort_keys=True, allow_nan=False) + "\n").encode()
        assert self._fd is not None
        written = os.write(self._fd, line)
        if written != len(line):                  # not expected for regular files; never leave half a line
            raise OSError(f"Short write to {self.path}: {written} of {len(line)} bytes")
        os.fsync(self._fd)

    def close(self) -> None:
        """Close the file."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> "ResultStore":
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
