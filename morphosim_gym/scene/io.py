"""Files: scenes and clips in one versioned container, and single frames as standard 3DGS `.ply`.

Container layout (little-endian):

    b"MORPHOSIM4D\\0"  magic (12 bytes)
    uint32            format version
    uint64            header length in bytes
    header            UTF-8 JSON: kind, metadata, array table, SHA-256 of the data section
    padding           to a multiple of 64 bytes
    data              the raw array bytes, each blob 64-byte aligned

Identical arrays are stored once, so an edited scene that carries its undo history
costs little more than the scene itself. Writes are atomic (temporary file + rename).
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from .clip import GeneratedClip
from .features import FeatureDecoder
from .gaussians import Gaussians
from .motion import Motion
from .scene4d import Scene4D, cameras_from_dicts, objects_from_dicts, provenance_from_dict

__all__ = ["SceneFileError", "save_scene", "load_scene", "save_clip", "load_clip", "export_ply", "read_ply",
           "FORMAT_VERSION"]

MAGIC = b"MORPHOSIM4D\0"
FORMAT_VERSION = 1
_ALIGN = 64
_SH_C0 = 0.28209479177387814


class SceneFileError(ValueError):
    """A scene, clip or .ply file that cannot be read: wrong kind, newer version, truncated or corrupted."""


# ----------------------------------------------------------------- container
def _atomic_write(path: Path, chunks: list[bytes]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            for c in chunks:
                fh.write(c)
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


def write_container(path: str | os.PathLike, kind: str, metadata: dict, arrays: dict[str, np.ndarray]) -> Path:
    """Write `metadata` (JSON) and named arrays as one container file of this `kind`."""
    path = Path(path)
    blobs: dict[str, tuple[int, bytes]] = {}
    table = []
    data = bytearray()
    for name, arr in arrays.items():
        a = np.ascontiguousarray(arr)
        if a.dtype.hasobject:
            raise ValueError(f"Expected numeric array for {name!r}, found dtype {a.dtype}")
        raw = a.tobytes()
        digest = hashlib.sha256(raw).hexdigest()
        if digest not in blobs:
            pad = (-len(data)) % _ALIGN
            data.extend(b"\0" * pad)
            blobs[digest] = (len(data), raw)
            data.extend(raw)
        offset = blobs[digest][0]
        table.append({"name": name, "dtype": a.dtype.str, "shape": list(a.shape), "offset": offset,
                      "nbytes": len(raw)})
    header = {"kind": kind, "metadata": metadata, "arrays": table, "data_nbytes": len(data),
              "data_sha256": hashlib.sha256(bytes(data)).hexdigest()}
    hbytes = json.dumps(header, separators=(",", ":")).encode("utf-8")
    prefix = MAGIC + struct.pack("<IQ", FORMAT_VERSION, len(hbytes)) + hbytes
    prefix += b"\0" * ((-len(prefix)) % _ALIGN)
    _atomic_write(path, [prefix, bytes(data)])
    return path


def read_container(path: str | os.PathLike, kind: str) -> tuple[dict, dict[str, np.ndarray]]:
    """Read a container of this `kind`; `SceneFileError` saying what is wrong otherwise."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SceneFileError(f"{path}: no such file") from None
    if len(raw) < len(MAGIC) + 12 or raw[: len(MAGIC)] != MAGIC:
        raise SceneFileError(f"{path}: not a MorphoSim file (expected magic {MAGIC!r} at the start)")
    version, hlen = struct.unpack_from("<IQ", raw, len(MAGIC))
    if version > FORMAT_VERSION:
        raise SceneFileError(f"{path}: written in format version {version}, this morphosim_gym reads up to "
                             f"{FORMAT_VERSION}; upgrade morphosim_gym")
    start = len(MAGIC) + 12
    if start + hlen > len(raw):
        raise SceneFileError(f"{path}: truncated (header needs {start + hlen} bytes, file has {len(raw)})")
    try:
        header = json.loads(raw[start:start + hlen].decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise SceneFileError(f"{path}: corrupted header ({exc})") from None
    if header.get("kind") != kind:
        raise SceneFileError(f"{path}: holds a {header.get('kind')!r}, expected a {kind!r}")
    data_start = start + hlen + ((-(start + hlen)) % _ALIGN)
    data = raw[data_start:]
    if len(data) != header["data_nbytes"]:
        raise SceneFileError(f"{path}: truncated or padded (data section has {len(data)} bytes, "
                             f"expected {header['data_nbytes']})")
    if hashlib.sha256(data).hexdigest() != header["data_sha256"]:
        raise SceneFileError(f"{path}: corrupted (checksum of the array data does not match)")
    arrays = {}
    for entry in header["arrays"]:
        dtype = np.dtype(entry["dtype"])
        arr = np.frombuffer(data, dtype=dtype, count=entry["nbytes"] // max(dtype.itemsize, 1),
                            offset=entry["offset"])
        arrays[entry["name"]] = arr.reshape(entry["shape"]).copy()
    return header["metadata"], arrays


# --------------------------------------------------------------------- scene
def _scene_chain(scene: Scene4D) -> list[Scene4D]:
    chain = []
    s: Scene4D | None = scene
    while s is not None:
        chain.append(s)
        s = s.parent
    return chain[::-1]


def save_scene(scene: Scene4D, path: str | os.PathLike, history: bool = True) -> Path:
    """Write a scene (and, with `history`, the scenes it was edited from, for `undo`) to one file.

    Examples:
        >>> save_scene(scene, "bus.msim"); load_scene("bus.msim")  # doctest: +SKIP
    """
    chain = _scene_chain(scene) if history else [scene]
    arrays: dict[str, np.ndarray] = {}
    metas = []
    for i, s in enumerate(chain):
        metas.append(s.metadata())
        arrays.update({f"{i}/{k}": v for k, v in s.arrays().items()})
    return write_container(path, "scene", {"scenes": metas}, arrays)


def _scene_from(meta: dict, arrays: dict[str, np.ndarray], parent: Scene4D | None) -> Scene4D:
    g = Gaussians(**{k: arrays.get(f"gaussians/{k}") for k in
                     ("means", "quats", "scales", "opacities", "colors", "features", "object_ids")})
    motion = Motion(**{k: arrays[f"motion/{k}"] for k in
                       ("rotations", "translations", "skin_nodes", "skin_weights", "node_objects")})
    decoders = {}
    for name, dm in meta["decoders"].items():
        prefix = f"decoders/{name}/"
        decoders[name] = FeatureDecoder.from_arrays(
            name, {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}, dm["normalize"])
    # Motion normalises quaternions on construction; keep the stored bits exactly.
    motion.rotations = arrays["motion/rotations"]
    return Scene4D(gaussians=g, motion=motion, objects=objects_from_dicts(meta["objects"]), fps=meta["fps"],
                   cameras=cameras_from_dicts(meta["cameras"]), decoders=decoders,
                   provenance=provenance_from_dict(meta["provenance"]), background=tuple(meta["background"]),
                   parent=parent)


def load_scene(path: str | os.PathLike) -> Scene4D:
    """Read a scene written by `save_scene`, bit-exact, with its undo history."""
    meta, arrays = read_container(path, "scene")
    try:
        scene = None
        for i, m in enumerate(meta["scenes"]):
            prefix = f"{i}/"
            scene = _scene_from(m, {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}, scene)
    except (KeyError, TypeError) as exc:
        raise SceneFileError(f"{path}: corrupted scene content (missing {exc})") from None
    except ValueError as exc:
        raise SceneFileError(f"{path}: invalid scene content: {exc}") from None
    assert scene is not None
    return scene


# ---------------------------------------------------------------------- clip
def save_clip(clip: GeneratedClip, path: str | os.PathLike) -> Path:
    """Write a clip (frames, cameras, priors, and its ground truth if any) to one file."""
    arrays = {"frames": clip.frames}
    for name in ("depth", "masks", "tracks", "track_visible"):
        if getattr(clip, name) is not None:
            arrays[name] = getattr(clip, name)
    meta: dict[str, Any] = {"cameras": [c.to_dict() for c in clip.cameras], "fps": clip.fps,
                            "labels": {str(k): v for k, v in clip.labels.items()}, "prompt": clip.prompt,
                            "info": clip.info, "ground_truth": None}
    if clip.ground_truth is not None:
        gt = clip.ground_truth
        meta["ground_truth"] = gt.metadata()
        arrays.update({f"gt/{k}": v for k, v in gt.arrays().items()})
    return write_container(path, "clip", meta, arrays)


def load_clip(path: str | os.PathLike) -> GeneratedClip:
    """Read a clip written by `save_clip`."""
    meta, arrays = read_container(path, "clip")
    try:
        gt = None
        if meta.get("ground_truth") is not None:
            gt = _scene_from(meta["ground_truth"], {k[3:]: v for k, v in arrays.items() if k.startswith("gt/")},
                             None)
        return GeneratedClip(frames=arrays["frames"], cameras=cameras_from_dicts(meta["cameras"]), fps=meta["fps"],
                             depth=arrays.get("depth"), masks=arrays.get("masks"),
                             labels={int(k): v for k, v in meta["labels"].items()}, tracks=arrays.get("tracks"),
                             track_visible=arrays.get("track_visible"), prompt=meta.get("prompt", ""),
                             ground_truth=gt, info=meta.get("info", {}))
    except (KeyError, TypeError) as exc:
        raise SceneFileError(f"{path}: corrupted clip content (missing {exc})") from None
    except ValueError as exc:
        raise SceneFileError(f"{path}: invalid clip content: {exc}") from None


# ----------------------------------------------------------------------- ply
_PLY_SCALAR = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]


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
    path = Path(path)
    _atomic_write(path, [header.encode("ascii"), data.tobytes()])
    return path


def read_ply(path: str | os.PathLike) -> Gaussians:
    """Read a 3DGS `.ply` (binary little-endian, float properties) into activated `Gaussians`."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SceneFileError(f"{path}: no such file") from None
    end = raw.find(b"end_header\n")
    if not raw.startswith(b"ply\n") or end < 0:
        raise SceneFileError(f"{path}: not a PLY file (missing 'ply' / 'end_header')")
    lines = raw[:end].decode("ascii", errors="replace").splitlines()
    if "format binary_little_endian 1.0" not in lines:
        raise SceneFileError(f"{path}: expected 'format binary_little_endian 1.0'")
    n, props, in_vertex = 0, [], False
    for line in lines:
        parts = line.split()
        if parts[:2] == ["element", "vertex"]:
            n, in_vertex = int(parts[2]), True
        elif parts and parts[0] == "element":
            in_vertex = False
        elif parts[:1] == ["property"] and in_vertex:
            if parts[1] != "float":
                raise SceneFileError(f"{path}: expected float properties, found {parts[1]} {parts[-1]}")
            props.append(parts[-1])
    body = raw[end + len(b"end_header\n"):]
    need = n * len(props) * 4
    if len(body) < need:
        raise SceneFileError(f"{path}: truncated (expected {need} bytes of vertex data, found {len(body)})")
    missing = [k for k in ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
                           "rot_0", "rot_1", "rot_2", "rot_3"] if k not in props]
    if missing:
        raise SceneFileError(f"{path}: not a 3DGS ply, missing properties {missing}")
    data = np.frombuffer(body[:need], dtype="<f4").reshape(n, len(props)).astype(np.float64)
    col = {k: i for i, k in enumerate(props)}

    def take(*keys: str) -> np.ndarray:
        return data[:, [col[k] for k in keys]]

    return Gaussians(means=take("x", "y", "z"), quats=take("rot_0", "rot_1", "rot_2", "rot_3"),
                     scales=np.exp(take("scale_0", "scale_1", "scale_2")),
                     opacities=1.0 / (1.0 + np.exp(-data[:, col["opacity"]])),
                     colors=np.clip(take("f_dc_0", "f_dc_1", "f_dc_2") * _SH_C0 + 0.5, 0.0, 1.0))

