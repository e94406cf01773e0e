"""Loading a mesh asset into plain arrays: `MeshPart`s of triangles with their material.

trimesh parses OBJ (with MTL and textures), GLB/GLTF and PLY; `pmd.py` reads 0 A.D.'s PMD (its
texture named by the record's `extra["texture"]`); `ac3d.py` reads AC3D (FlightGear), leaving out
the objects the record's `extra["skip"]` names, its textures modulated by their material's colour
as FlightGear draws them and their alpha kept as opacity; each part keeps its triangles in
the file's frame (scene-graph transforms applied), per-corner UVs when it has a texture, the
texture as float RGB, and the material's diffuse colour and opacity.
"""

from __future__ import annotations

import io
import warnings
from dataclasses import dataclass
from pathlib import PurePosixPath

import numpy as np
import trimesh

from .ac3d import read_ac3d
from .errors import AssetError, AssetWarning
from .files import AssetFiles
from .pmd import read_pmd
from .record import AssetRecord

__all__ = ["MeshPart", "load_mesh_parts"]

_FILE_TYPES = {".obj": "obj", ".glb": "glb", ".gltf": "gltf", ".ply": "ply", ".pmd": "pmd", ".ac": "ac3d"}


@dataclass
class MeshPart:
    """Triangles with one material.

    Attributes:
        triangles: corner positions in the file's frame. [M, 3, 3]
        uvs: per-corner texture coordinates, or None without a texture. [M, 3, 2]
        texture: RGB uint8, row 0 at the top (v = 1), or None. [H, W, 3]
        color: the diffuse colour, used without a texture. [3]
        opacity: the material's opacity in [0, 1].
        face_colors: per-face colours from the file (PLY/vertex colours), or None. [M, 3]
        alpha: the texture's opacity, uint8, where it has transparent texels (cut-out windows),
            else None; it multiplies `opacity` where the surface is sampled. [H, W]
    """

    triangles: np.ndarray
    uvs: np.ndarray | None
    texture: np.ndarray | None
    color: np.ndarray
    opacity: float = 1.0
    face_colors: np.ndarray | None = None
    alpha: np.ndarray | None = None


def _rgba(value, default=(0.7, 0.7, 0.7, 1.0)) -> np.ndarray:
    if value is None:
        return np.asarray(default, dtype=np.float64)
    c = np.asarray(value, dtype=np.float64).ravel()
    if c.size < 3:
        return np.asarray(default, dtype=np.float64)
    if c.max() > 1.0:
        c = c / 255.0
    return np.r_[c[:3], c[3] if c.size > 3 else 1.0].clip(0, 1)


def _image_array(image) -> np.ndarray | None:
    if image is None:
        return None
    try:
        arr = np.asarray(image.convert("RGB"), dtype=np.uint8)
    except Exception:  # noqa: BLE001 - a lazily decoded image can still fail here
        return None
    return arr if arr.ndim == 3 and arr.shape[0] > 0 and arr.shape[1] > 0 else None


def _material(visual) -> tuple[np.ndarray, np.ndarray | None]:
    """(diffuse RGBA [4], texture [H, W, 3] or None) of a trimesh visual."""
    mat = getattr(visual, "material", None)
    if mat is None:
        return _rgba(None), None
    if isinstance(mat, trimesh.visual.material.PBRMaterial):
        return _rgba(mat.baseColorFactor), _image_array(mat.baseColorTexture)
    return _rgba(getattr(mat, "diffuse", None)), _image_array(getattr(mat, "image", None))


def _part(mesh: trimesh.Trimesh) -> MeshPart | None:
    faces = np.asarray(mesh.faces)
    if faces.size == 0:
        return None
    verts = np.asarray(mesh.vertices, dtype=np.float64)
    tris = verts[faces]
    visual = mesh.visual
    if isinstance(visual, trimesh.visual.ColorVisuals):
        colors = (np.asarray(visual.face_colors, dtype=np.float64)[:, :3] / 255.0
                  if visual.kind in ("face", "vertex") else None)
        return MeshPart(tris, None, None, _rgba(None)[:3], 1.0, colors)
    rgba, tex = _material(visual)
    uv = getattr(visual, "uv", None)
    uvs = None
    if tex is not None and uv is not None and len(uv) == len(verts):
        uvs = np.asarray(uv, dtype=np.float64)[faces]
    return MeshPart(tris, uvs, tex if uvs is not None else None, rgba[:3], float(rgba[3]))


def load_mesh_parts(record: AssetRecord, files: AssetFiles | None = None) -> list[MeshPart]:
    """The triangles and materials of a mesh asset.

    Raises:
        AssetError: the file is missing, too large, unparsable or has no triangles (the message
            names the file).
    """
    files = files or AssetFiles(record)
    name = record.member or record.path
    file_type = _FILE_TYPES.get(PurePosixPath(name.lower()).suffix)
    if file_type is None:
        raise AssetError(f"Expected a mesh file ({', '.join(_FILE_TYPES)}), found {files.label}")
    data = files.main()
    if file_type == "pmd":
        return [_pmd_part(files, data)]
    if file_type == "ac3d":
        return _ac3d_parts(files, data)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            scene = trimesh.load(io.BytesIO(data), file_type=file_type, resolver=files.resolver(), force="scene",
                                 process=False)
        meshes = [m for m in _world_meshes(scene)]
    except AssetError:
        raise
    except Exception as exc:  # noqa: BLE001 - trimesh raises many types for malformed files
        raise AssetError(f"Cannot parse the mesh {files.label} ({type(exc).__name__}: {exc})") from None
    parts = [p for p in (_part(m) for m in meshes) if p is not None]
    if not parts:
        raise AssetError(f"The mesh {files.label} has no triangles")
    return parts


def _pmd_part(files: AssetFiles, data: bytes) -> MeshPart:
    """One textured part of a 0 A.D. PMD mesh; its colour texture is `extra["texture"]` (a missing or
    unreadable one warns, naming it, and the part takes the default colour)."""
    try:
        pmd = read_pmd(data)
    except ValueError as exc:
        raise AssetError(f"Cannot parse the mesh {files.label} ({exc})") from None
    if len(pmd.faces) == 0:
        raise AssetError(f"The mesh {files.label} has no triangles")
    texture = None
    name = str(files.record.extra.get("texture", ""))
    if name:
        try:
            texture = _decode_image(files.texture_member())
        except (AssetError, OSError, ValueError) as exc:
            warnings.warn(AssetWarning(f"Texture {name!r} of {files.label} is unreadable ({exc}); using the "
                                       f"material colour"), stacklevel=3)
    uvs = pmd.uvs[pmd.faces] if texture is not None else None     # v runs up the image, as MeshPart's
    return MeshPart(pmd.positions[pmd.faces], uvs, texture,
                    _rgba(None)[:3])


def _ac3d_parts(files: AssetFiles, data: bytes) -> list[MeshPart]:
    """The parts of an AC3D file, one per (texture, material); a missing or unreadable texture warns
    once, naming it, and its parts take the material colour."""
    try:
        model = read_ac3d(data, files.label, tuple(files.record.extra.get("skip", ())))
    except ValueError as exc:
        raise AssetError(f"Cannot parse the mesh {exc}") from None
    if model.n_triangles == 0:
        raise AssetError(f"The mesh {files.label} has no triangles")
    images: dict[str, tuple[np.ndarray, np.ndarray | None] | None] = {}
    parts = []
    for p in model.parts:
        material = model.material(p.material)
        rgb = np.asarray(material.rgb, dtype=np.float64).clip(0, 1)
        image = _ac3d_texture(files, p.texture, images) if p.texture else None
        if image is None:
            parts.append(MeshPart(p.triangles, None, None, rgb, material.opacity))
            continue
        texture = (image[0] * rgb + 0.5).clip(0, 255).astype(np.uint8)   # FlightGear modulates by the material
        parts.append(MeshPart(p.triangles, p.uvs, texture, rgb, material.opacity, alpha=image[1]))
    return parts


def _ac3d_texture(files: AssetFiles, name: str, images: dict) -> tuple[np.ndarray, np.ndarray | None] | None:
    """(RGB, alpha or None) of an AC3D part's texture; None, warned once, when missing or unreadable."""
    if name not in images:
        try:
            blob = files.ac3d_texture(name)
            if blob is None:
                raise ValueError("not found next to the file")
            images[name] = _decode_rgba(blob)
        except (AssetError, OSError, ValueError) as exc:
            warnings.warn(AssetWarning(f"Texture {name!r} of {files.label} is unreadable ({exc}); using the "
                                       f"material colour"), stacklevel=4)
            images[name] = None
    return images[name]


def _decode_rgba(blob: bytes) -> tuple[np.ndarray, np.ndarray | None]:
    """(RGB uint8 [H, W, 3], alpha uint8 [H, W] or None when every texel is opaque) of an image file."""
    from PIL import Image

    try:
        with Image.open(io.BytesIO(blob)) as im:
            rgba = np.asarray(im.convert("RGBA"), dtype=np.uint8)
    except Exception as exc:  # noqa: BLE001 - PIL raises many types for a bad image
        raise ValueError(f"{type(exc).__name__}: {exc}") from None
    if rgba.ndim != 3 or rgba.shape[0] == 0 or rgba.shape[1] == 0:
        raise ValueError("an empty image")
    alpha = rgba[..., 3]
    return np.ascontiguousarray(rgba[..., :3]), (np.ascontiguousarray(alpha) if alpha.min() < 255 else None)


def _decode_image(blob: bytes | None) -> np.ndarray | None:
    """RGB uint8 of an image file's bytes (DDS with DXT1/3/5 included, by Pillow): `_decode_rgba`'s
    colour channels."""
    return None if blob is None else _decode_rgba(blob)[0]


def _world_meshes(scene: trimesh.Scene) -> list[trimesh.Trimesh]:
    """Every triangle mesh of a scene with its node transform applied."""
    out = []
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        geom = scene.geometry.get(geom_name)
        if not isinstance(geom, trimesh.Trimesh):
            continue
        if not np.allclose(transform, np.eye(4)):
            geom = geom.copy()
            geom.apply_transform(transform)
        out.append(geom)
    return out
