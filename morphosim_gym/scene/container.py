"""The on-disk container of scenes and clips: a checksummed JSON header and raw array blobs.

Layout of format version 2 (little-endian):

    b"MORPHOSIM4D\\0"  magic (12 bytes)
    uint32            format version (2)
    uint64            header length in bytes
    header            UTF-8 JSON: kind, metadata, blob table, array table, size and SHA-256 of the data
    32 bytes          SHA-256 of everything before it (magic, version, length, header)
    padding           to a multiple of 64 bytes
    data              the blobs, each 64-byte aligned

Every blob (a run of bytes) is listed once; arrays name a blob, a dtype and a shape whose size
equals the blob's, so identical arrays (an edited scene's undo history) are stored and loaded once.
The reader trusts nothing it has not checked: the header checksum, the data checksum, blob ranges
inside the data and disjoint, dtypes from a short numeric list, shapes that fit their blob. Version 1
files (no header checksum, one byte range per array) are still read, with the same range checks.
Every problem is a `SceneFileError` naming the file.
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import atomic_write

__all__ = ["FORMAT_VERSION", "MAGIC", "SceneFileError", "peek_kind", "read_container", "write_container"]

MAGIC = b"MORPHOSIM4D\0"
FORMAT_VERSION = 2
_ALIGN = 64
_PREFIX = struct.Struct("<IQ")
_DIGEST = 32
_MAX_NDIM = 8
_DTYPES = frozenset(np.dtype(t).str for t in ("|b1", "|u1", "|i1", "<u2", "<i2", "<u4", "<i4", "<u8", "<i8",
                                              "<f2", "<f4", "<f8"))


class SceneFileError(ValueError):
    """A scene, clip or .ply file that cannot be read: wrong kind, newer version, truncated or corrupted.
    The message names the file and the problem."""


# ------------------------------------------------------------------- writing
def write_container(path: str | os.PathLike, kind: str, metadata: dict, arrays: dict[str, np.ndarray]) -> Path:
    """Write `metadata` (JSON) and named arrays as one container file of this `kind` (atomically)."""
    blob_index: dict[str, int] = {}
    blobs: list[dict] = []
    table: list[dict] = []
    data = bytearray()
    for name, arr in arrays.items():
        a = np.ascontiguousarray(arr)
        if a.dtype.str not in _DTYPES:
            raise ValueError(f"Expected a numeric array for {name!r}, found dtype {a.dtype}")
        raw = a.tobytes()
        digest = hashlib.sha256(raw).hexdigest()
        if digest not in blob_index:
            data.extend(b"\0" * ((-len(data)) % _ALIGN))
            blob_index[digest] = len(blobs)
            blobs.append({"offset": len(data), "nbytes": len(raw)})
            data.extend(raw)
        table.append({"name": name, "dtype": a.dtype.str, "shape": list(a.shape), "blob": blob_index[digest]})
    header = {"kind": kind, "metadata": metadata, "blobs": blobs, "arrays": table, "data_nbytes": len(data),
              "data_sha256": hashlib.sha256(bytes(data)).hexdigest()}
    hbytes = json.dumps(header, separators=(",", ":"), allow_nan=False).encode("utf-8")
    prefix = MAGIC + _PREFIX.pack(FORMAT_VERSION, len(hbytes)) + hbytes
    prefix += hashlib.sha256(prefix).digest()
    prefix += b"\0" * ((-len(prefix)) % _ALIGN)
    return atomic_write(path, [prefix, bytes(data)])


# ------------------------------------------------------------------- reading
class _Reader:
    """One read of one file; `fail` raises a `SceneFileError` naming it."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, problem: str) -> SceneFileError:
        return SceneFileError(f"{self.path}: {problem}")

    def raw(self) -> bytes:
        try:
            return self.path.read_bytes()
        except FileNotFoundError:
            raise self.fail("no such file") from None
        except IsADirectoryError:
            raise self.fail("is a directory, not a file") from None
        except OSError as exc:
            raise self.fail(f"cannot be read ({exc.strerror or exc})") from None

    def header(self, raw: bytes) -> tuple[int, dict, int]:
        """(version, header, data start) after checking the magic, the version and (v2) the checksum."""
        start = len(MAGIC) + _PREFIX.size
        if len(raw) < start or raw[: len(MAGIC)] != MAGIC:
            raise self.fail(f"not a MorphoSim file (expected magic {MAGIC!r} at the start)")
        version, hlen = _PREFIX.unpack_from(raw, len(MAGIC))
        if version > FORMAT_VERSION:
            raise self.fail(f"written in format version {version}, this morphosim_gym reads up to "
                            f"{FORMAT_VERSION}; upgrade morphosim_gym")
        if version not in _LAYOUTS:
            raise self.fail(f"unknown format version {version} (corrupted)")
        digest_len = _DIGEST if version >= 2 else 0
        end = start + hlen
        if end + digest_len > len(raw):
            raise self.fail(f"truncated (header needs {end + digest_len} bytes, file has {len(raw)})")
        if digest_len and hashlib.sha256(raw[:end]).digest() != raw[end:end + digest_len]:
            raise self.fail("corrupted (checksum of the header does not match)")
        try:
            header = json.loads(raw[start:end].decode("utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError) as exc:
            raise self.fail(f"corrupted header ({type(exc).__name__}: {str(exc)[:80]})") from None
        if not isinstance(header, dict):
            raise self.fail(f"corrupted header (expected a JSON object, found {type(header).__name__})")
        end += digest_len
        return version, header, end + ((-end) % _ALIGN)

    def data(self, raw: bytes, header: dict, data_start: int) -> memoryview:
        expected = _int(header.get("data_nbytes"), -1)
        have = len(raw) - data_start
        if have != expected:
            raise self.fail(f"truncated or padded (data section has {have} bytes, "
                            f"expected {header.get('data_nbytes')!r})")
        data = memoryview(raw)[data_start:]
        if hashlib.sha256(data).hexdigest() != header.get("data_sha256"):
            raise self.fail("corrupted (checksum of the array data does not match)")
        return data

    def dtype(self, entry: dict) -> np.dtype:
        text = entry.get("dtype")
        if not isinstance(text, str) or text not in _DTYPES:
            raise self.fail(f"array {entry.get('name')!r} has dtype {text!r}, expected one of {sorted(_DTYPES)}")
        return np.dtype(text)

    def shape(self, entry: dict) -> tuple[int, ...]:
        shape = entry.get("shape")
        if (not isinstance(shape, list) or len(shape) > _MAX_NDIM
                or not all(type(d) is int and d >= 0 for d in shape)):
            raise self.fail(f"array {entry.get('name')!r} has shape {shape!r}, expected up to {_MAX_NDIM} "
                            f"non-negative integers")
        return tuple(shape)

    def ranges(self, ranges: list[tuple[int, int]], size: int) -> None:
        """Byte ranges (offset, nbytes) must lie in the data and be disjoint (identical ones are one blob)."""
        end = 0
        for off, n in sorted(set(ranges)):
            if off < end:
                raise self.fail(f"corrupted blob table (byte range {off}..{off + n} overlaps another)")
            if off + n > size:
                raise self.fail(f"corrupted blob table (byte range {off}..{off + n} is past the data's {size} bytes)")
            end = off + n


def _int(x: Any, default: int) -> int:
    return x if type(x) is int else default


def _table(r: _Reader, header: dict, key: str) -> list[dict]:
    rows = header.get(key)
    if not isinstance(rows, list) or not all(isinstance(e, dict) for e in rows):
        raise r.fail(f"corrupted header ('{key}' is not a list of objects)")
    return rows


def _v1_ranges(r: _Reader, header: dict, size: int) -> list[tuple[str, np.dtype, tuple, tuple[int, int]]]:
    out = []
    for e in _table(r, header, "arrays"):
        off, n = _int(e.get("offset"), -1), _int(e.get("nbytes"), -1)
        if off < 0 or n < 0:
            raise r.fail(f"array {e.get('name')!r} has offset {e.get('offset')!r} and size {e.get('nbytes')!r}")
        out.append((e.get("name"), r.dtype(e), r.shape(e), (off, n)))
    r.ranges([rng for *_, rng in out], size)
    return out


def _v2_ranges(r: _Reader, header: dict, size: int) -> list[tuple[str, np.dtype, tuple, tuple[int, int]]]:
    blobs = []
    for i, b in enumerate(_table(r, header, "blobs")):
        off, n = _int(b.get("offset"), -1), _int(b.get("nbytes"), -1)
        if off < 0 or n < 0:
            raise r.fail(f"blob {i} has offset {b.get('offset')!r} and size {b.get('nbytes')!r}")
        blobs.append((off, n))
    if len(set(blobs)) != len(blobs):
        raise r.fail("corrupted blob table (a byte range is listed twice)")
    r.ranges(blobs, size)
    out = []
    for e in _table(r, header, "arrays"):
        i = _int(e.get("blob"), -1)
        if not 0 <= i < len(blobs):
            raise r.fail(f"array {e.get('name')!r} names blob {e.get('blob')!r}, the file has {len(blobs)}")
        out.append((e.get("name"), r.dtype(e), r.shape(e), blobs[i]))
    return out


_LAYOUTS: dict[int, Callable[[_Reader, dict, int], list]] = {1: _v1_ranges, 2: _v2_ranges}


def _arrays(r: _Reader, entries: list, data: memoryview) -> dict[str, np.ndarray]:
    """Arrays of the table, each blob materialised once: arrays that share a blob share memory and
    are read-only (an in-place write would otherwise change its twin); others are writable copies."""
    uses: dict[tuple, int] = {}
    for name, dtype, shape, rng in entries:
        if not isinstance(name, str):
            raise r.fail(f"corrupted array table (name {name!r} is not a string)")
        if int(np.prod(shape, dtype=object)) * dtype.itemsize != rng[1]:
            raise r.fail(f"array {name!r} declares shape {list(shape)} of {dtype.str} "
                         f"({int(np.prod(shape, dtype=object)) * dtype.itemsize} bytes) for a blob of {rng[1]} bytes")
        uses[rng] = uses.get(rng, 0) + 1
    bases: dict[tuple, np.ndarray] = {}
    arrays: dict[str, np.ndarray] = {}
    for name, dtype, shape, rng in entries:
        if name in arrays:
            raise r.fail(f"corrupted array table (array {name!r} is listed twice)")
        if rng not in bases:
            base = np.frombuffer(data[rng[0]:rng[0] + rng[1]], dtype=np.uint8).copy()
            base.flags.writeable = uses[rng] == 1
            bases[rng] = base
        arrays[name] = bases[rng].view(dtype).reshape(shape)
    return arrays


def read_container(path: str | os.PathLike, kind: str) -> tuple[dict, dict[str, np.ndarray]]:
    """(metadata, arrays) of a container of this `kind`; `SceneFileError` naming the file otherwise."""
    r = _Reader(Path(path))
    raw = r.raw()
    version, header, data_start = r.header(raw)
    if header.get("kind") != kind:
        raise r.fail(f"holds a {header.get('kind')!r}, expected a {kind!r}")
    if not isinstance(header.get("metadata"), dict):
        raise r.fail("corrupted header ('metadata' is not an object)")
    data = r.data(raw, header, data_start)
    return header["metadata"], _arrays(r, _LAYOUTS[version](r, header, len(data)), data)


def peek_kind(path: str | os.PathLike) -> str:
    """The kind ("scene", "clip") a container holds, from its checked header, without reading its arrays."""
    r = _Reader(Path(path))
    _, header, _ = r.header(r.raw())
    kind = header.get("kind")
    if not isinstance(kind, str):
        raise r.fail(f"corrupted header (kind {kind!r})")
    return kind
