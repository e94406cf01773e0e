"""`asset_gaussians`: an asset as `Gaussians` in its object frame, converted once and cached.

    >>> from morphosim_gym.assets import AssetIndex, asset_gaussians
    >>> index = AssetIndex.load()                                     # doctest: +SKIP
    >>> horse, _ = index.search("horse", k=1)[0]                      # doctest: +SKIP
    >>> g = asset_gaussians(horse, budget=20000)                      # doctest: +SKIP
    >>> g.means.shape                                                 # doctest: +SKIP
    (20000, 3)
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..scene.gaussians import Gaussians
from ..scene.rotations import matrix_to_quat, quat_multiply
from .cache import ConversionCache
from .convert import ConversionParams, mesh_to_gaussians, splat_to_object
from .errors import AssetError
from .files import MAX_FILE_BYTES, AssetFiles
from .frame import UP_ROTATIONS, SizeSpec
from .index import AssetIndex, default_cache_dir
from .mesh import load_mesh_parts
from .record import AssetRecord
from .splat_ply import read_splat_ply

__all__ = ["CONVERSION_VERSION", "asset_gaussians", "conversion_key", "default_conversion_cache", "splat_setting"]

CONVERSION_VERSION = 1   # bump when the conversion's output changes for the same inputs


def default_conversion_cache() -> ConversionCache:
    """The cache under `default_cache_dir()/converted`."""
    return ConversionCache(default_cache_dir() / "converted")


def conversion_key(record: AssetRecord, params: ConversionParams, files: AssetFiles) -> str:
    """sha256 of the source files' bytes, the record's frame fields, the parameters and the version."""
    meta = {"version": CONVERSION_VERSION, "kind": record.kind, "up": record.up_axis, "unit": record.unit_scale,
            "size": record.size_m, "rotation": record.model_rotation, "params": params.key()}
    if record.extra.get("skip"):     # objects an AC3D record leaves out change the geometry
        meta["skip"] = list(record.extra["skip"])
    return hashlib.sha256((json.dumps(meta, sort_keys=True) + files.content_hash()).encode()).hexdigest()


def _convert_mesh(record: AssetRecord, files: AssetFiles, params: ConversionParams) -> Gaussians:
    return mesh_to_gaussians(load_mesh_parts(record, files), record, params)


def _convert_splat(record: AssetRecord, files: AssetFiles, params: ConversionParams) -> Gaussians:
    return splat_to_object(read_splat_ply(files.label, files.main()), record, params)


Converter = Callable[[AssetRecord, AssetFiles, ConversionParams], Gaussians]
_CONVERTERS: dict[str, Converter] = {
    "mesh": _convert_mesh,
    "splat": _convert_splat,
}


def asset_gaussians(asset: AssetRecord | str, budget: int = 20000, size_m: SizeSpec = None, *, seed: int = 0,
                    index: AssetIndex | None = None, cache: ConversionCache | bool | None = True,
                    params: ConversionParams | None = None, max_bytes: int = MAX_FILE_BYTES) -> Gaussians:
    """The asset as Gaussians in its object frame: z-up, metres, base centred at the origin.

    Args:
        asset: a record, or an id looked up in `index` (default `AssetIndex.load()`).
        budget: number of Gaussians (a mesh gets exactly this many; a splat at most this many).
        size_m: None (the asset's real-world size), the longest side in metres, or 3 extents (x, y, z).
        seed: the surface-sampling seed.
        cache: True (the default cache), a `ConversionCache`, or False/None for no caching.
        params: full conversion parameters (then `budget`, `size_m` and `seed` are ignored).
        max_bytes: refuse a file larger than this.

    Raises:
        AssetError: a missing, broken, too large or unsupported file (the message names it).
    """
    record = asset if isinstance(asset, AssetRecord) else (index or AssetIndex.load()).get(asset)
    convert = _CONVERTERS.get(record.kind)
    if convert is None:
        raise AssetError(f"Expected a mesh or splat asset, found kind {record.kind!r} for {record.id} "
                         f"(a sky panorama loads with morphosim_gym.assets.load_sky)")
    params = params or ConversionParams(budget=budget, size_m=size_m, seed=seed)
    store = default_conversion_cache() if cache is True else (cache or None)
    files = AssetFiles(record, max_bytes=max_bytes)
    try:
        if store is None:
            return _convert(convert, record, files, params)
        key = conversion_key(record, params, files)
        return store.get_or_build(key, lambda: _convert(convert, record, files, params), label=record.id)
    finally:
        files.close()


def _convert(convert: Converter, record: AssetRecord, files: AssetFiles, params: ConversionParams) -> Gaussians:
    """Run a converter; numerical or shape failures become an `AssetError` naming the file."""
    try:
        return convert(record, files, params)
    except AssetError:
        raise
    except (ValueError, IndexError, ArithmeticError, MemoryError) as exc:
        raise AssetError(f"Cannot convert {files.label} ({type(exc).__name__}: {exc})") from exc


def splat_setting(path: str | os.PathLike, up_axis: str = "z", unit_scale: float = 1.0) -> Gaussians:
    """A whole 3DGS `.ply` scene as a background setting: rotated to z-up and scaled to metres,
    not moved or subsampled."""
    if up_axis not in UP_ROTATIONS:
        raise ValueError(f"Expected up_axis in {sorted(UP_ROTATIONS)}, found {up_axis!r}")
    g = read_splat_ply(Path(path))
    rot = UP_ROTATIONS[up_axis]
    quats = quat_multiply(np.broadcast_to(matrix_to_quat(rot), g.quats.shape), g.quats)
    return Gaussians(means=g.means.astype(np.float64) @ rot.T * unit_scale, quats=quats,
                     scales=g.scales * unit_scale, opacities=g.opacities, colors=g.colors)
