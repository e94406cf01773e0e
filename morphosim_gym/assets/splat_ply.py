"""Standard 3D Gaussian Splatting `.ply` files <-> `Gaussians`.

Fields (per vertex, float32): x, y, z; f_dc_0..2 (degree-0 spherical-harmonic colour);
opacity (a logit); scale_0..2 (log standard deviations); rot_0..3 (w, x, y, z, unnormalised).
Higher-order f_rest_* fields are read past and ignored. Binary (either byte order, any scalar
type) and ASCII. `morphosim_gym.scene.io.export_ply` writes such files.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..scene.gaussians import Gaussians
from .errors import AssetError

__all__ = ["REQUIRED_FIELDS", "SH_C0", "read_splat_ply"]

SH_C0 = 0.28209479177387814   # the degree-0 spherical-harmonic constant
REQUIRED_FIELDS = ("x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity",
                   "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3")
_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
              "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
              "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
_FORMATS = {"binary_little_endian": "<", "binary_big_endian": ">", "ascii": None}


def _header(data: bytes, path: str) -> tuple[str, int, list[tuple[str, str]], int]:
    """(format, vertex count, [(field, numpy type)], header length) of a PLY with one vertex element first."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise AssetError(f"Expected a PLY file, found no 'ply ... end_header' header in {path}")
    body_start = data.index(b"\n", end) + 1
    lines = data[:end].decode("ascii", errors="replace").splitlines()
    fmt, count, fields, element = None, 0, [], None
    for line in lines:
        words = line.split()
        if not words:
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            element = words[1]
            if element == "vertex":
                count = int(words[2])
            elif not fields:
                raise AssetError(f"Expected the vertex element first in {path}, found {element!r}")
        elif words[0] == "property" and element == "vertex":
            if words[1] == "list":
                raise AssetError(f"Expected scalar vertex properties in {path}, found a list property")
            if words[1] not in _PLY_TYPES:
                raise AssetError(f"Unknown PLY property type {words[1]!r} in {path}")
            fields.append((words[2], _PLY_TYPES[words[1]]))
    if fmt not in _FORMATS:
        raise AssetError(f"Expected a PLY format in {sorted(_FORMATS)}, found {fmt!r} in {path}")
    return fmt, count, fields, body_start


def _ascii_columns(data: bytes, start: int, count: int, names: list[str], path: str) -> dict[str, np.ndarray]:
    try:
        table = np.loadtxt(data[start:].decode("ascii").splitlines()[:count], dtype=np.float64, ndmin=2)
    except ValueError as exc:
        raise AssetError(f"Unreadable ASCII body in {path}: {exc}") from None
    if table.shape != (count, len(names)):
        raise AssetError(f"Expected {count} rows of {len(names)} values in {path}, found {table.shape}")
    return {f: table[:, i] for i, f in enumerate(names)}


def _binary_columns(data: bytes, start: int, count: int, fields: list[tuple[str, str]], order: str,
                    path: str) -> dict[str, np.ndarray]:
    dtype = np.dtype([(f, order + t) for f, t in fields])
    if len(data) - start < count * dtype.itemsize:
        raise AssetError(f"The 3DGS file {path} is truncated: {count} vertices need "
                         f"{count * dtype.itemsize} bytes, found {len(data) - start}")
    arr = np.frombuffer(data, dtype=dtype, count=count, offset=start)
    return {f: arr[f].astype(np.float64) for f, _ in fields}


def _activated(col: dict[str, np.ndarray], path: str) -> Gaussians:
    """3DGS's stored parameters (logit, log scale, SH DC) -> activated `Gaussians`."""
    def stack(keys: tuple[str, ...]) -> np.ndarray:
        return np.stack([col[k] for k in keys], axis=1)

    quats = stack(("rot_0", "rot_1", "rot_2", "rot_3"))
    quats[np.linalg.norm(quats, axis=1) < 1e-12] = (1, 0, 0, 0)
    try:
        return Gaussians(means=stack(("x", "y", "z")), quats=quats,
                         scales=np.exp(np.clip(stack(("scale_0", "scale_1", "scale_2")), -30, 30)),
                         opacities=1.0 / (1.0 + np.exp(-np.clip(col["opacity"], -60, 60))),
                         colors=np.clip(0.5 + SH_C0 * stack(("f_dc_0", "f_dc_1", "f_dc_2")), 0, 1))
    except ValueError as exc:
        raise AssetError(f"Invalid Gaussians in {path}: {exc}") from None


def read_splat_ply(path: str | os.PathLike, data: bytes | None = None) -> Gaussians:
    """The Gaussians of a 3DGS `.ply`, in the file's own frame.

    Args:
        path: the file (named in errors).
        data: its bytes, when already read (then `path` is only a label).

    Raises:
        AssetError: not a PLY, a required field missing (named), a truncated body, or invalid values.
    """
    path = str(path)
    if data is None:
        try:
            data = Path(path).read_bytes()
        except OSError as exc:
            raise AssetError(f"Cannot read {path}: {exc}") from None
    fmt, count, fields, start = _header(data, path)
    names = [f for f, _ in fields]
    missing = [f for f in REQUIRED_FIELDS if f not in names]
    if missing:
        raise AssetError(f"The 3DGS file {path} has no {missing[0]!r} field (found {', '.join(names) or 'none'})")
    order = _FORMATS[fmt]
    col = _ascii_columns(data, start, count, names, path) if order is None else \
        _binary_columns(data, start, count, fields, order, path)
    return _activated(col, path)
