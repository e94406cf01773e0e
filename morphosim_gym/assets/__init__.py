"""Assets: real meshes, 3DGS splats and sky panoramas as `Gaussians` and skies.

The layer sits above `scene` and below `generate`: sources found at run time (`sources`), an
index cached on disk (`AssetIndex`), mesh -> `Gaussians` conversion with a content-hash cache
(`asset_gaussians`), 3DGS `.ply` files (`read_splat_ply`, `splat_setting`) and
HDR skies (`load_sky`). Text search takes an embedding function as an argument, so this layer
never imports `language`.
"""

from __future__ import annotations

from .api import CONVERSION_VERSION, asset_gaussians, conversion_key, default_conversion_cache, splat_setting
from .cache import ConversionCache
from .convert import ConversionParams, mesh_to_gaussians, normals_to_quats
from .errors import AssetError, AssetWarning
from .index import AssetIndex, default_cache_dir
from .record import AssetRecord
from .sky import Sky, load_sky
from .sources import AssetSource, FolderSource, default_sources
from .splat_ply import read_splat_ply

__all__ = [
           "CONVERSION_VERSION",
           "AssetError",
           "AssetIndex",
           "AssetRecord",
           "AssetSource",
           "AssetWarning",
           "ConversionCache",
           "ConversionParams",
           "FolderSource",
           "Sky",
           "asset_gaussians",
           "conversion_key",
           "default_cache_dir",
           "default_conversion_cache",
           "default_sources",
           "load_sky",
           "mesh_to_gaussians",
           "normals_to_quats",
           "read_splat_ply",
           "splat_setting",
       ]
