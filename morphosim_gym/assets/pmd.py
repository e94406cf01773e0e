"""A reader of 0 A.D.'s binary PMD meshes (written from the format's description, versions 2-4).

Layout, little-endian:

    "PSMD", u32 version, u32 data size (bytes after this field)
    u32 vertex count, [version >= 4: u32 UV sets per vertex]
    per vertex: f32 position[3], f32 normal[3], f32 uv[sets][2], u8 bones[4], f32 weights[4]
    u32 face count, per face: u16 corners[3]
    u32 bone count, per bone: f32 translation[3], f32 rotation[4] (rest pose)
    [version >= 2] u32 prop point count, per point: u32 name length, name, f32 translation[3],
        f32 rotation[4], u8 bone

Positions of skinned meshes are already in their rest pose, so the mesh reads as it stands.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

__all__ = ["PMD_MAGIC", "PmdMesh", "read_pmd", "write_pmd"]

PMD_MAGIC = b"PSMD"
VERSIONS = (2, 3, 4)
_BLEND_BYTES = 4 + 4 * 4
_BONE_BYTES = 7 * 4


@dataclass(frozen=True)
class PmdMesh:
    """The parts of a PMD the converter uses.

    Attributes:
        positions: vertex positions in the file's frame (y-up). [V, 3]
        normals: vertex normals. [V, 3]
        uvs: the first UV set (v = 0 at the image's bottom row, as OBJ). [V, 2]
        faces: vertex indices of each triangle. [F, 3]
        n_bones: bones of the skeleton (0 for a static prop).
        prop_points: names of the attachment points.
    """

    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    faces: np.ndarray
    n_bones: int = 0
    prop_points: tuple[str, ...] = ()


class _Cursor:
    """Bounded reads from a byte string; running past the end is a `ValueError` naming the part."""

    def __init__(self, data: bytes) -> None:
        self.data, self.at = data, 0

    def take(self, n: int, what: str) -> bytes:
        if n < 0 or self.at + n > len(self.data):
            raise ValueError(f"truncated PMD: {what} needs {n} bytes at offset {self.at}, "
                             f"{len(self.data) - self.at} left")
        out = self.data[self.at:self.at + n]
        self.at += n
        return out

    def u32(self, what: str) -> int:
        return struct.unpack("<I", self.take(4, what))[0]


def read_pmd(data: bytes) -> PmdMesh:
    """Parse PMD bytes.

    Raises:
        ValueError: not a PMD, an unsupported version, a truncated file or out-of-range faces.
    """
    cur = _Cursor(data)
    magic = cur.take(4, "the magic")
    if magic != PMD_MAGIC:
        raise ValueError(f"expected a PMD file starting with {PMD_MAGIC!r}, found {magic!r}")
    version = cur.u32("the version")
    if version not in VERSIONS:
        raise ValueError(f"expected PMD version in {VERSIONS}, found {version}")
    cur.u32("the data size")
    n_verts = cur.u32("the vertex count")
    n_uv = cur.u32("the UV set count") if version >= 4 else 1
    if n_uv < 1:
        raise ValueError("expected at least one UV set, found 0")
    stride = 24 + 8 * n_uv + _BLEND_BYTES
    raw = np.frombuffer(cur.take(n_verts * stride, f"{n_verts} vertices"), dtype=np.uint8).reshape(n_verts, stride)
    floats = raw[:, :24 + 8 * n_uv].copy().view("<f4").astype(np.float64)
    n_faces = cur.u32("the face count")
    faces = np.frombuffer(cur.take(n_faces * 6, f"{n_faces} faces"), dtype="<u2").reshape(n_faces, 3).astype(np.int64)
    if faces.size and int(faces.max()) >= n_verts:
        raise ValueError(f"a face names vertex {int(faces.max())} of {n_verts}")
    n_bones = cur.u32("the bone count")
    cur.take(n_bones * _BONE_BYTES, f"{n_bones} bones")
    props: list[str] = []
    if version >= 2:
        for _ in range(cur.u32("the prop point count")):
            props.append(cur.take(cur.u32("a prop point's name length"), "a prop point's name").decode("latin-1"))
            cur.take(7 * 4 + 1, "a prop point's pose")
    return PmdMesh(positions=floats[:, 0:3], normals=floats[:, 3:6], uvs=floats[:, 6:8], faces=faces,
                   n_bones=n_bones, prop_points=tuple(props))


def write_pmd(positions: np.ndarray, faces: np.ndarray, uvs: np.ndarray | None = None,
              normals: np.ndarray | None = None, version: int = 4) -> bytes:
    """A minimal static PMD (one UV set, no bones, no prop points): for tests and hand-made props."""
    pos = np.asarray(positions, dtype="<f4").reshape(-1, 3)
    n = len(pos)
    nrm = np.zeros((n, 3), "<f4") if normals is None else np.asarray(normals, "<f4").reshape(n, 3)
    uv = np.zeros((n, 2), "<f4") if uvs is None else np.asarray(uvs, "<f4").reshape(n, 2)
    blend = (b"\xff" * 4 + b"\x00" * 16)
    verts = b"".join(pos[i].tobytes() + nrm[i].tobytes() + uv[i].tobytes() + blend for i in range(n))
    tri = np.asarray(faces, dtype="<u2").reshape(-1, 3)
    body = struct.pack("<I", n) + (struct.pack("<I", 1) if version >= 4 else b"") + verts
    body += struct.pack("<I", len(tri)) + tri.tobytes() + struct.pack("<I", 0)
    if version >= 2:
        body += struct.pack("<I", 0)
    return PMD_MAGIC + struct.pack("<II", version, len(body)) + body
