"""`morphosim assets list|search|show`: what assets this machine has, find one, look at one.

The command line is the top layer, so `search` may use the language layer's MiniLM embeddings
(when installed) as the embedding function the asset index takes.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

__all__ = ["framing_camera", "register", "render_asset"]


_MODEL = "all-MiniLM-L6-v2 encode_table"   # names the embedding function in the on-disk vector cache


def register(sub: argparse._SubParsersAction) -> None:
    """Add `morphosim assets` and its subcommands."""
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--assets", action="append", default=[], metavar="DIR",
                        help="a folder of OBJ/GLB/PLY/AC3D files to add (repeatable; also $MORPHOSIM_ASSETS)")
    common.add_argument("--sources", default=None,
                        help="comma-separated system sources to use (default all installed: "
                             "sweethome3d,robosuite,studiolights,zero_ad,libero,flightgear; '' for none)")
    common.add_argument("--cache-dir", default=None, help="asset cache folder (default $MORPHOSIM_CACHE/assets)")
    common.add_argument("--refresh", action="store_true", help="re-read every source instead of the cached index")
    common.add_argument("--json", action="store_true", help="print JSON")

    p = sub.add_parser("assets", help="list, search and show the real assets (meshes, splats, skies)")
    asub = p.add_subparsers(dest="assets_command", metavar="ACTION", required=True)
    q = asub.add_parser("list", parents=[common], help="assets per source and per category")
    q.set_defaults(func=_list)
    q = asub.add_parser("search", parents=[common], help="assets matching a text (words, then embeddings)")
    q.add_argument("text")
    q.add_argument("-k", type=int, default=10, help="how many results (default 10)")
    q.add_argument("--no-embed", action="store_true", help="words only (skip the MiniLM embedding model)")
    q.add_argument("--kind", choices=("mesh", "splat", "sky"), default=None)
    q.set_defaults(func=_search)
    q = asub.add_parser("show", parents=[common], help="one asset's metadata; --render draws it")
    q.add_argument("id")
    q.add_argument("--render", metavar="PNG", default=None, help="render the converted asset to this image")
    q.add_argument("--budget", type=int, default=20000, help="Gaussians for the render (default 20000)")
    q.add_argument("--size", type=float, default=None, help="longest side in metres (default the real size)")
    q.add_argument("--width", type=int, default=256, help="image width and height in pixels (default 256)")
    q.set_defaults(func=_show)


def _index(args: argparse.Namespace):
    from .index import AssetIndex
    from .sources import default_sources

    system = None if args.sources is None else [s for s in args.sources.split(",") if s.strip()]
    return AssetIndex.build(default_sources(args.assets, system=system), cache_dir=args.cache_dir,
                            refresh=args.refresh)


def _list(args: argparse.Namespace) -> int:
    index = _index(args)
    summary = {"assets": len(index), "sources": index.counts_by_source(), "categories": index.counts_by_category()}
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"{len(index)} assets")
    for title, counts in (("source", summary["sources"]), ("category", summary["categories"])):
        print(f"\nper {title}:")
        for name, n in counts.items():
            print(f"  {n:5d}  {name}")
    return 0


def _embedder(args: argparse.Namespace):
    """The MiniLM embedding function, or None (asked not to, or not installed)."""
    if args.no_embed:
        return None
    from ..errors import BackendUnavailableError
    from ..language import embeddings

    if not embeddings.is_available():
        print("assets search: the MiniLM model is not installed; matching words only", file=sys.stderr)
        return None
    try:
        embeddings.load()
    except BackendUnavailableError as exc:
        print(f"assets search: {exc}; matching words only", file=sys.stderr)
        return None
    return embeddings.encode_table


def _search(args: argparse.Namespace) -> int:
    index = _index(args)
    embed = _embedder(args)
    hits = index.search(args.text, k=args.k, embed=embed, embed_name=_MODEL if embed else None, kind=args.kind)
    if args.json:
        print(json.dumps([{"id": r.id, "name": r.name, "category": r.category, "score": round(s, 4)}
                          for r, s in hits], indent=2))
        return 0
    if not hits:
        print(f"no asset matches {args.text!r}")
        return 1
    for r, s in hits:
        print(f"{s:6.3f}  {r.id}  ({r.name}; {r.category})")
    return 0


def framing_camera(gaussians, width: int = 256, fov_y_deg: float = 40.0):
    """A camera seeing the whole object from the front-right, slightly above (the object faces -y)."""
    from ..scene.camera import Camera

    lo, hi = gaussians.means.min(axis=0), gaussians.means.max(axis=0)
    centre = (lo + hi) / 2
    radius = max(float(np.linalg.norm(hi - lo)) / 2, 1e-3)
    direction = np.array([0.55, -1.0, 0.45])
    direction /= np.linalg.norm(direction)
    distance = 1.1 * radius / np.sin(np.radians(fov_y_deg) / 2)
    return Camera.look_at(eye=centre + distance * direction, target=centre, width=width, height=width,
                          fov_y_deg=fov_y_deg, near=max(distance - 2 * radius, 1e-3) * 0.1)


def render_asset(gaussians, path: str | Path, width: int = 256, background=(0.92, 0.92, 0.92)) -> np.ndarray:
    """Render `gaussians` with `framing_camera` to a PNG at `path`; returns the uint8 image."""
    import imageio.v3 as iio

    from ..render import render

    out = render(gaussians, framing_camera(gaussians, width), background=background)
    image = out.rgb_uint8()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(path, image)
    return image


def _show(args: argparse.Namespace) -> int:
    from .api import asset_gaussians
    from .cache import ConversionCache

    index = _index(args)
    try:
        record = index.get(args.id)
    except KeyError as exc:
        raise ValueError(exc.args[0]) from None
    info = record.to_dict()
    if args.render:
        if record.kind == "sky":
            import imageio.v3 as iio

            from .sky import load_sky

            iio.imwrite(args.render, (load_sky(record.path).image * 255 + 0.5).astype(np.uint8))
        else:
            cache = ConversionCache(Path(args.cache_dir) / "converted") if args.cache_dir else True
            g = asset_gaussians(record, budget=args.budget, size_m=args.size, cache=cache)
            render_asset(g, args.render, args.width)
            lo, hi = g.means.min(axis=0), g.means.max(axis=0)
            info["converted"] = {"gaussians": len(g), "extents_m": [round(float(x), 4) for x in hi - lo]}
        info["render"] = str(args.render)
    print(json.dumps(info, indent=2, ensure_ascii=False))
    return 0
