"""Single frames as standard 3DGS `.ply` files: export, and a reader that is exact for any valid PLY.

The reader parses the header's elements in order, so elements before `vertex` (and list properties
in them) are skipped by their real size; ascii, binary little- and big-endian are read; sizes are
checked against the file before anything is allocated. Problems are `SceneFileError`s naming the
file and what is wrong.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .atomic import atomic_write
from .container import SceneFileError
from .gaussians import Gaussians
from .scene4d import Scene4D

__all__ = ["export_ply", "read_ply"]

_SH_C0 = 0.28209479177387814
_PLY_SCALAR = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
_REQUIRED = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
             "rot_0", "rot_1", "rot_2", "rot_3"]
_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
          "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
          "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
_FORMATS = {"ascii": "", "binary_little_endian": "<", "binary_big_endian": ">"}
_MAX_HEADER = 1 << 20


def export_ply(source: Scene4D | Gaussians, path: str | os.PathLike, t: float = 0.0, sh_rest: bool = True) -> Path:
    """Write one frame as a standard 3DGS `.ply` (x y z, normals, f_dc_*, [f_rest_* zeros], opacity
    logit, log scale_*, rot_* w x y z) that common splat viewers open.

    Colours are stored as degree-0 spherical harmonics: f_dc = (rgb - 0.5) / C0.
    """
    g = source.at(t) if isinstance(source, Scene4D) else source.numpy()
    n = len(g)
    names = list(_PLY_SCALAR)
    if sh_rest:
        names += [f"f_rest_{i}" for i in range(45)]
    names += ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
    data = np.zeros((n, len(names)), dtype="<f4")
    col = {k: i for i, k in enumerate(names)}
    data[:, 0:3] = g.means
    data[:, col["f_dc_0"]:col["f_dc_0"] + 3] = (g.colors - 0.5) / _SH_C0
    op = np.clip(g.opacities.astype(np.float64), 1e-7, 1 - 1e-7)
    data[:, col["opacity"]] = np.log(op / (1 - op))
    data[:, col["scale_0"]:col["scale_0"] + 3] = np.log(g.scales)
    q = g.quats / np.linalg.norm(g.quats, axis=1, keepdims=True)
    data[:, col["rot_0"]:col["rot_0"] + 4] = q
    header = "ply\nformat binary_little_endian 1.0\ncomment written by morphosim_gym\n"
    header += f"element vertex {n}\n" + "".join(f"property float {k}\n" for k in names) + "end_header\n"
    return atomic_write(path, [header.encode("ascii"), data.tobytes()])


# ------------------------------------------------------------------- header
@dataclass
class _Element:
    name: str
    count: int
    scalars: list[tuple[str, str]] = field(default_factory=list)     # (name, numpy type code)
    lists: list[tuple[int, str, str]] = field(default_factory=list)  # (position, count type, item type)

    @property
    def width(self) -> int:
        return len(self.scalars) + len(self.lists)


def _fail(path: Path, problem: str) -> SceneFileError:
    return SceneFileError(f"{path}: {problem}")


def _type(path: Path, word: str, line: str) -> str:
    if word not in _TYPES:
        raise _fail(path, f"unknown property type {word!r} in header line {line!r}")
    return _TYPES[word]


@dataclass
class _Header:
    path: Path
    fmt: str | None = None
    elements: list[_Element] = field(default_factory=list)


def _h_format(h: _Header, parts: list[str]) -> bool:
    if len(parts) != 3 or parts[1] not in _FORMATS:
        return False
    h.fmt = _FORMATS[parts[1]]
    return True


def _h_element(h: _Header, parts: list[str]) -> bool:
    if len(parts) != 3 or not parts[2].isdigit():
        return False
    h.elements.append(_Element(parts[1], int(parts[2])))
    return True


def _h_property(h: _Header, parts: list[str]) -> bool:
    if not h.elements:
        return False
    el, line = h.elements[-1], " ".join(parts)
    if len(parts) == 3:
        el.scalars.append((parts[2], _type(h.path, parts[1], line)))
        return True
    if len(parts) == 5 and parts[1] == "list":
        el.lists.append((el.width, _type(h.path, parts[2], line), _type(h.path, parts[3], line)))
        return True
    return False


# header keyword -> reader of its line (False: malformed)
_HEADER_LINES = {"format": _h_format, "element": _h_element, "property": _h_property,
                 "comment": lambda h, parts: True, "obj_info": lambda h, parts: True}


def _parse_header(path: Path, raw: bytes) -> tuple[str, list[_Element], int]:
    """(format byte-order prefix or "" for ascii, elements in order, offset of the body)."""
    if not raw.startswith(b"ply"):
        raise _fail(path, "not a PLY file (missing 'ply' on the first line)")
    end = raw.find(b"end_header", 0, _MAX_HEADER)
    if end < 0:
        raise _fail(path, "not a PLY file (no 'end_header' in the first MiB)")
    body = end + len(b"end_header")
    body += 2 if raw[body:body + 2] == b"\r\n" else 1
    h = _Header(path)
    for line in raw[:end].decode("ascii", errors="replace").splitlines()[1:]:
        parts = line.split()
        if parts and not (parts[0] in _HEADER_LINES and _HEADER_LINES[parts[0]](h, parts)):
            raise _fail(path, f"malformed header line {line!r}")
    if h.fmt is None:
        raise _fail(path, f"expected a 'format' line with one of {sorted(_FORMATS)}")
    return h.fmt, h.elements, body


# --------------------------------------------------------------------- body
def _skip_binary(path: Path, raw: bytes, pos: int, el: _Element, order: str) -> int:
    """Offset after a binary element (rows walked one by one when it has list properties)."""
    if not el.lists:
        return pos + el.count * sum(np.dtype(t).itemsize for _, t in el.scalars)
    lists = {position: (ctype, itype) for position, ctype, itype in el.lists}
    scalar_types = iter(t for _, t in el.scalars)
    layout = [lists.get(i) or np.dtype(next(scalar_types)).itemsize for i in range(el.width)]
    for _ in range(el.count):
        for part in layout:
            if isinstance(part, int):
                pos += part
                continue
            ct = np.dtype(order + part[0])
            if pos + ct.itemsize > len(raw):
                raise _fail(path, f"truncated in element {el.name!r}")
            n = int(np.frombuffer(raw, ct, 1, pos)[0])
            if n < 0:
                raise _fail(path, f"negative list length {n} in element {el.name!r}")
            pos += ct.itemsize + n * np.dtype(part[1]).itemsize
        if pos > len(raw):
            raise _fail(path, f"truncated in element {el.name!r}")
    return pos


def _vertex_binary(path: Path, raw: bytes, pos: int, el: _Element, order: str) -> np.ndarray:
    dtype = np.dtype([(name, order + t) for name, t in el.scalars])
    need = el.count * dtype.itemsize
    if pos + need > len(raw):
        raise _fail(path, f"truncated (expected {need} bytes of vertex data, found {max(len(raw) - pos, 0)})")
    return np.frombuffer(raw, dtype, el.count, pos)


def _vertex_ascii(path: Path, lines: list[bytes], el: _Element) -> np.ndarray:
    if len(lines) < el.count:
        raise _fail(path, f"truncated (expected {el.count} vertex lines, found {len(lines)})")
    dtype = np.dtype([(name, t) for name, t in el.scalars])
    out = np.empty(el.count, dtype)
    for i, line in enumerate(lines[:el.count]):
        words = line.split()
        if len(words) != len(el.scalars):
            raise _fail(path, f"vertex line {i} has {len(words)} values, expected {len(el.scalars)}")
        try:
            out[i] = tuple(float(w) for w in words)
        except ValueError:
            raise _fail(path, f"vertex line {i} is not numbers: {line[:80]!r}") from None
    return out


def _ascii_lines(path: Path, raw: bytes, body: int, before: list[_Element]) -> list[bytes]:
    lines = [ln for ln in raw[body:].splitlines() if ln.strip()]
    skip = sum(el.count for el in before)
    if skip > len(lines):
        raise _fail(path, f"truncated (expected {skip} lines before the vertex element, found {len(lines)})")
    return lines[skip:]


def _vertices(path: Path, raw: bytes) -> np.ndarray:
    fmt, elements, body = _parse_header(path, raw)
    names = [el.name for el in elements]
    if "vertex" not in names:
        raise _fail(path, f"no 'vertex' element (elements: {names})")
    k = names.index("vertex")
    vertex = elements[k]
    if vertex.lists:
        raise _fail(path, "list properties in the 'vertex' element are not supported")
    props = [name for name, _ in vertex.scalars]
    if len(set(props)) != len(props):
        raise _fail(path, f"the vertex element lists a property twice ({props})")
    if fmt == "":
        return _vertex_ascii(path, _ascii_lines(path, raw, body, elements[:k]), vertex)
    pos = body
    for el in elements[:k]:
        pos = _skip_binary(path, raw, pos, el, fmt)
        if pos > len(raw):
            raise _fail(path, f"truncated in element {el.name!r}")
    return _vertex_binary(path, raw, pos, vertex, fmt)


def read_ply(path: str | os.PathLike) -> Gaussians:
    """Read a 3DGS `.ply` (any valid PLY: ascii or binary, any numeric property types, other
    elements before or after `vertex`) into activated `Gaussians`."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise _fail(path, "no such file") from None
    except OSError as exc:
        raise _fail(path, f"cannot be read ({exc.strerror or exc})") from None
    v = _vertices(path, raw)
    missing = [k for k in _REQUIRED if k not in (v.dtype.names or ())]
    if missing:
        raise _fail(path, f"not a 3DGS ply, the vertex element lacks properties {missing}")

    def take(*keys: str) -> np.ndarray:
        return np.stack([v[k].astype(np.float64) for k in keys], axis=1)

    try:
        with np.errstate(over="ignore"):
            return Gaussians(means=take("x", "y", "z"), quats=take("rot_0", "rot_1", "rot_2", "rot_3"),
                             scales=np.exp(take("scale_0", "scale_1", "scale_2")),
                             opacities=1.0 / (1.0 + np.exp(-v["opacity"].astype(np.float64))),
                             colors=np.clip(take("f_dc_0", "f_dc_1", "f_dc_2") * _SH_C0 + 0.5, 0.0, 1.0))
    except ValueError as exc:
        raise _fail(path, f"invalid Gaussians: {exc}") from None
