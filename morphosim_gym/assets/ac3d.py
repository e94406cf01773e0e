"""AC3D `.ac` meshes (FlightGear's model format): materials, an object tree, textured polygons.

A file is a header line (`AC3Db`, `AC3Dc`...), `MATERIAL` lines (`MATERIAL "name" rgb r g b amb ...
trans t`, one a line), and one `OBJECT world` whose `kids` nest `group` and `poly` objects. An object
may give `name`, `data` (n characters of text, which may span lines), `texture "file"`, `texrep u v`,
`texoff u v`, `rot` (9 numbers, a row-major 3x3), `loc` (3 numbers), `numvert n` (n lines of x y z,
sometimes followed by a normal) and `numsurf n` (n surfaces: `SURF 0xFT` with its type T, 0 a
polygon, 1 a closed line, 2 a line, 4 a triangle strip, `mat i` and `refs k`, k lines of
`vertex u v`), and ends with `kids n`, its n children. A child's vertices are placed by its
parents, root first: p_file = M_parent @ (rot @ p + loc), as OpenSceneGraph's and SimGear's readers
do. Polygons become triangle fans (FlightGear's are convex: triangles and quads), strips are
unrolled, lines are dropped; UVs are `uv * texrep + texoff` with v running up the image.

Textures are looked up by `find_texture`: as written next to the file, by base name in its folder,
its `Textures/` subfolder and the folder above (and its `Textures/`), then by base name ignoring case.

Examples:
    >>> model = read_ac3d(b'AC3Db\\nMATERIAL "m" rgb 1 0 0 amb 0 0 0 emis 0 0 0 spec 0 0 0 shi 0 trans 0\\n'
    ...                   b'OBJECT world\\nkids 1\\nOBJECT poly\\nloc 0 0 5\\nnumvert 3\\n0 0 0\\n1 0 0\\n0 1 0\\n'
    ...                   b'numsurf 1\\nSURF 0x10\\nmat 0\\nrefs 3\\n0 0 0\\n1 1 0\\n2 0 1\\nkids 0\\n')
    >>> model.parts[0].triangles.shape, model.parts[0].triangles[0, :, 2].tolist()
    ((1, 3, 3), [5.0, 5.0, 5.0])
"""

from __future__ import annotations

import os
import re
import shlex
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["AC3DMaterial", "AC3DModel", "AC3DPart", "find_texture", "read_ac3d", "texture_names"]

_MATERIAL = re.compile(r'^MATERIAL\s+"([^"]*)"\s*(.*)$')
_TEXTURE = re.compile(r'^\s*texture\s+("[^"]*"|\S+)', re.MULTILINE)
_LINE_TYPES = (1, 2)        # closed line, line: no area
_STRIP = 4                  # triangle strip (AC3D 8)


@dataclass(frozen=True)
class AC3DMaterial:
    """A `MATERIAL` line: its name, diffuse colour [3] in [0, 1] and opacity (1 - trans)."""

    name: str
    rgb: tuple[float, float, float] = (0.8, 0.8, 0.8)
    opacity: float = 1.0


@dataclass
class AC3DPart:
    """The triangles of one (texture, material) pair, in the file's frame.

    Attributes:
        triangles: corner positions. [M, 3, 3]
        uvs: per-corner texture coordinates (texrep and texoff applied), None without a texture. [M, 3, 2]
        texture: the texture's name as the file writes it, or None.
        material: index into `AC3DModel.materials` (-1: none).
        objects: the names of the objects it came from (first few).
    """

    triangles: np.ndarray
    uvs: np.ndarray | None
    texture: str | None
    material: int
    objects: list[str] = field(default_factory=list)


@dataclass
class AC3DModel:
    """What `read_ac3d` found: parts, materials, and what it left out (line surfaces, kids a `kids`
    count promised but the file lacks at its end, the names of skipped objects)."""

    parts: list[AC3DPart]
    materials: list[AC3DMaterial]
    objects: int = 0
    lines_dropped: int = 0
    missing_kids: int = 0
    skipped: list[str] = field(default_factory=list)

    @property
    def n_triangles(self) -> int:
        return sum(len(p.triangles) for p in self.parts)

    def bounds(self) -> np.ndarray | None:
        """[[min x, y, z], [max x, y, z]] of every triangle corner, or None without triangles. [2, 3]"""
        if not self.parts:
            return None
        corners = np.concatenate([p.triangles.reshape(-1, 3) for p in self.parts])
        return np.stack([corners.min(axis=0), corners.max(axis=0)])

    def material(self, index: int) -> AC3DMaterial:
        """The material of an index (a default grey for one the file does not define)."""
        return self.materials[index] if 0 <= index < len(self.materials) else AC3DMaterial("")


class _Lines:
    """The file's lines with their numbers; `next()` skips blank ones, `fail` names file and line."""

    def __init__(self, text: str, label: str) -> None:
        self.lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        if self.lines[-1] == "":
            self.lines.pop()            # the final line end: the file's last line is its last text
        self.label, self.i = label, 0

    @property
    def number(self) -> int:
        """The 1-based number of the line last read."""
        return self.i

    def next(self, what: str) -> str:
        while self.i < len(self.lines):
            line = self.lines[self.i].strip()
            self.i += 1
            if line:
                return line
        raise self.fail(f"the file ends where {what} was expected")

    def at_end(self) -> bool:
        return all(not line.strip() for line in self.lines[self.i:])

    def skip_chars(self, n: int) -> None:
        """Skip the n characters of a `data` block (they may span lines; each line end counts one)."""
        got = 0
        while got < n and self.i < len(self.lines):
            got += len(self.lines[self.i]) + 1
            self.i += 1

    def fail(self, message: str) -> ValueError:
        return ValueError(f"{self.label}, line {self.number}: {message}")


def _numbers(lines: _Lines, line: str, n: int, start: int = 1) -> list[float]:
    """The n numbers after the keyword of `line` (`ValueError` naming the line when missing or bad)."""
    words = line.split()
    try:
        values = [float(w) for w in words[start:start + n]]
    except ValueError:
        raise lines.fail(f"expected {n} numbers after {words[0]!r}, found {' '.join(words[start:])!r}") from None
    if len(values) < n:
        raise lines.fail(f"expected {n} numbers after {words[0]!r}, found {len(values)}")
    return values


def _count(lines: _Lines, line: str) -> int:
    """The count after a keyword (`numvert 8`, `kids 2`)."""
    words = line.split()
    if len(words) < 2 or not words[1].isdigit():
        raise lines.fail(f"expected a count after {words[0]!r}, found {' '.join(words[1:])!r}")
    return int(words[1])


def _quoted(text: str) -> str:
    """A quoted (or bare) word: `"Textures/hull.png"` -> `Textures/hull.png`."""
    try:
        words = shlex.split(text.strip(), posix=True)
    except ValueError:
        words = [text.strip().strip('"')]
    return words[0] if words else ""


def _material(lines: _Lines, line: str) -> AC3DMaterial:
    m = _MATERIAL.match(line)
    if m is None:
        raise lines.fail(f"expected MATERIAL \"name\" rgb r g b ..., found {line[:60]!r}")
    words = m.group(2).split()
    rgb = (0.8, 0.8, 0.8)
    trans = 0.0
    if "rgb" in words:
        rgb = tuple(_numbers(lines, " ".join(words), 3, words.index("rgb") + 1))
    if "trans" in words:
        trans = _numbers(lines, " ".join(words), 1, words.index("trans") + 1)[0]
    return AC3DMaterial(m.group(1), rgb, float(np.clip(1.0 - trans, 0.0, 1.0)))


@dataclass
class _Object:
    """One OBJECT's own fields while it is read."""

    kind: str
    name: str = ""
    texture: str | None = None
    texrep: np.ndarray = field(default_factory=lambda: np.ones(2))
    texoff: np.ndarray = field(default_factory=lambda: np.zeros(2))
    rot: np.ndarray = field(default_factory=lambda: np.eye(3))
    loc: np.ndarray = field(default_factory=lambda: np.zeros(3))
    verts: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    surfaces: list[tuple[int, int, np.ndarray, np.ndarray, int]] = field(default_factory=list)


def _vertices(lines: _Lines, n: int) -> np.ndarray:
    out = np.empty((n, 3))
    for k in range(n):
        out[k] = _numbers(lines, lines.next(f"vertex {k + 1} of {n}"), 3, start=0)
    return out


def _surface(lines: _Lines, first: str) -> tuple[int, int, np.ndarray, np.ndarray, int]:
    """(type, material, vertex indices [k], uvs [k, 2], line number) of one `SURF` block."""
    words = first.split()
    if words[0].upper() != "SURF" or len(words) < 2:
        raise lines.fail(f"expected SURF 0x.., found {first[:60]!r}")
    start = lines.number
    try:
        kind = int(words[1], 16) & 0x0F
    except ValueError:
        raise lines.fail(f"expected SURF flags in hexadecimal, found {words[1]!r}") from None
    mat = -1
    while True:
        line = lines.next("mat or refs of a SURF")
        key = line.split()[0]
        if key == "mat":
            mat = int(_numbers(lines, line, 1)[0])
        elif key == "refs":
            k = _count(lines, line)
            refs = np.array([_ref(lines, lines.next(f"ref {j + 1} of {k}")) for j in range(k)]).reshape(k, 3)
            return kind, mat, refs[:, 0].astype(np.int64), refs[:, 1:], start
        else:
            raise lines.fail(f"expected mat or refs in a SURF, found {line[:60]!r}")


def _ref(lines: _Lines, line: str) -> list[float]:
    """(vertex index, u, v) of a ref line; u, v are 0 when it has none."""
    n = 3 if len(line.split()) >= 3 else 1
    return (_numbers(lines, line, n, start=0) + [0.0, 0.0])[:3]


def _triangles(kind: int, k: int) -> np.ndarray:
    """Corner indices [k - 2, 3] of a polygon's fan or a strip's triangles."""
    a = np.arange(k - 2)
    if kind == _STRIP:
        tri = np.stack([a, a + 1, a + 2], axis=1)
        tri[1::2] = tri[1::2][:, [1, 0, 2]]        # every other strip triangle turns the other way
        return tri
    return np.stack([np.zeros_like(a), a + 1, a + 2], axis=1)


class _Reader:
    """Reads the object tree depth first, collecting triangles by (texture, material)."""

    def __init__(self, lines: _Lines, skip: Sequence[str]) -> None:
        self.lines = lines
        self.skip = [re.compile(s, re.IGNORECASE) for s in skip]
        self.groups: dict[tuple[str | None, int], dict[str, list]] = {}
        self.objects = 0
        self.lines_dropped = 0
        self.missing_kids = 0
        self.skipped: list[str] = []

    def object(self, first: str, parent: np.ndarray, skipped: bool) -> None:
        """Read one OBJECT (its header line is `first`) and its kids; `parent` maps to the file frame [4, 4];
        a `skipped` parent's kids give no geometry."""
        lines = self.lines
        words = first.split()
        if words[0] != "OBJECT" or len(words) < 2:
            raise lines.fail(f"expected OBJECT <type>, found {first[:60]!r}")
        obj = _Object(words[1])
        self.objects += 1
        while True:
            line = lines.next(f"'kids' of the OBJECT {obj.name or obj.kind}")
            key = line.split()[0]
            if key == "kids":
                self._finish(obj, parent, skipped, _count(lines, line))
                return
            self._field(obj, key, line)

    def _field(self, obj: _Object, key: str, line: str) -> None:
        lines = self.lines
        if key == "name":
            obj.name = _quoted(line[4:])
        elif key == "data":
            lines.skip_chars(_count(lines, line))
        elif key == "texture":
            obj.texture = obj.texture or _quoted(line[7:]) or None     # later ones are extra layers
        elif key == "texrep":
            obj.texrep = np.array(_numbers(lines, line, 2))
        elif key == "texoff":
            obj.texoff = np.array(_numbers(lines, line, 2))
        elif key == "rot":
            obj.rot = np.array(_numbers(lines, line, 9)).reshape(3, 3)
        elif key == "loc":
            obj.loc = np.array(_numbers(lines, line, 3))
        elif key == "numvert":
            obj.verts = _vertices(lines, _count(lines, line))
        elif key == "numsurf":
            obj.surfaces = [_surface(lines, lines.next("SURF")) for _ in range(_count(lines, line))]
        elif key in ("OBJECT", "MATERIAL", "SURF", "refs", "mat"):
            raise lines.fail(f"expected an OBJECT field or 'kids', found {line[:60]!r}")
        # url, crease, subdiv, hidden, locked, folded, shader...: no geometry

    def _finish(self, obj: _Object, parent: np.ndarray, skipped: bool, kids: int) -> None:
        local = np.eye(4)
        local[:3, :3], local[:3, 3] = obj.rot, obj.loc
        world = parent @ local
        matched = bool(obj.name) and any(p.search(obj.name) for p in self.skip)
        if matched and not skipped:
            self.skipped.append(obj.name)
        skip = skipped or matched
        if not skip:
            self._emit(obj, world)
        for k in range(kids):
            if self.lines.at_end():         # a kids count above what the file holds (seen in FlightGear's)
                self.missing_kids += kids - k
                return
            self.object(self.lines.next("a kid OBJECT"), world, skip)

    def _emit(self, obj: _Object, world: np.ndarray) -> None:
        verts = obj.verts @ world[:3, :3].T + world[:3, 3]
        for kind, mat, idx, uv, line in obj.surfaces:
            if kind in _LINE_TYPES or len(idx) < 3:
                self.lines_dropped += 1
                continue
            if idx.min() < 0 or idx.max() >= len(verts):
                raise ValueError(f"{self.lines.label}, line {line}: SURF refers to vertex {int(idx.max())}, "
                                 f"but its OBJECT {obj.name or obj.kind} has {len(verts)}")
            tri = _triangles(kind, len(idx))
            group = self.groups.setdefault((obj.texture, mat), {"t": [], "uv": [], "names": []})
            group["t"].append(verts[idx[tri]])
            group["uv"].append((uv * obj.texrep + obj.texoff)[tri])
            if obj.name and obj.name not in group["names"] and len(group["names"]) < 8:
                group["names"].append(obj.name)

    def parts(self) -> list[AC3DPart]:
        return [AC3DPart(np.concatenate(g["t"]), np.concatenate(g["uv"]) if tex else None, tex, mat, g["names"])
                for (tex, mat), g in self.groups.items()]


def read_ac3d(data: bytes | str, label: str = "<ac3d>", skip: Sequence[str] = ()) -> AC3DModel:
    """The triangles of an AC3D file, grouped by texture and material, in the file's frame.

    Args:
        data: the file's bytes (read as Latin-1) or text.
        label: the file's name in error messages.
        skip: regular expressions (case-insensitive) searched in object names: a matching object
            and its kids give no geometry (a ship's wake plane, a shadow).

    Raises:
        ValueError: not an AC3D file, or broken; the message names `label` and the line.
    """
    text = data.decode("latin-1") if isinstance(data, bytes) else data
    lines = _Lines(text, label)
    head = lines.next("the AC3D header")
    if not head.startswith("AC3D"):
        raise lines.fail(f"expected an AC3D header (AC3Db...), found {head[:20]!r}")
    reader = _Reader(lines, skip)
    materials: list[AC3DMaterial] = []
    while not lines.at_end():
        line = lines.next("MATERIAL or OBJECT")
        if line.startswith("MATERIAL"):
            materials.append(_material(lines, line))
        elif line.startswith("OBJECT"):
            reader.object(line, np.eye(4), False)
        else:
            raise lines.fail(f"expected MATERIAL or OBJECT, found {line[:60]!r}")
    return AC3DModel(reader.parts(), materials, reader.objects, reader.lines_dropped, reader.missing_kids,
                     reader.skipped)


def texture_names(data: bytes | str) -> list[str]:
    """The texture names an AC3D file writes, once each, in order."""
    text = data.decode("latin-1") if isinstance(data, bytes) else data
    return list(dict.fromkeys(n for n in (_quoted(m) for m in _TEXTURE.findall(text)) if n))


def find_texture(folder: str | os.PathLike, name: str) -> Path | None:
    """The file of a texture an AC3D file in `folder` names, or None.

    Looked up as written (relative to `folder`), then by its base name in `folder`, `folder/Textures`,
    the folder above and its `Textures`, then by base name ignoring case in those folders.
    """
    folder = Path(folder)
    name = name.replace("\\", "/")
    base = name.rsplit("/", 1)[-1]
    places = [folder, folder / "Textures", folder.parent, folder.parent / "Textures"]
    for candidate in [folder / name, *(p / base for p in places)]:
        if candidate.is_file():
            return candidate
    lower = base.lower()
    for place in places:
        try:
            hit = next((f for f in sorted(os.listdir(place)) if f.lower() == lower), None)
        except OSError:
            continue
        if hit is not None and (place / hit).is_file():
            return place / hit
    return None
