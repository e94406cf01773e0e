"""Real assets for generated objects: which asset a category gets, and its Gaussians as a cloud.

Mode (`GenerationConfig.assets`):

* "auto" (default): real assets where an installed source has one, else the procedural builder
  (with a one-line notice, once per process, when no source is installed);
* "off": always the procedural builders (bit-identical to the generator before real assets);
* "require": like "auto", but no installed source is an error.

`$MORPHOSIM_ASSET_SOURCES` narrows the system sources to a comma list of names (e.g.
"sweethome3d"); set to "" it disables them all, which makes "auto" procedural everywhere.

Open categories are "asset:<asset id>" (from open-vocabulary grounding): that asset, at its
real-world size.
"""

from __future__ import annotations

import functools
import logging
import os
import re

import numpy as np

from ..assets import AssetError, AssetIndex, AssetRecord, asset_gaussians, default_sources
from ..language.hypernyms import head_word, kind_category, ranked_senses, synonym_sibling
from ..language.vocabulary import CATEGORIES
from ..scene.parts import SurfaceCloud
from ..scene.rotations import matrix_to_quat, quat_multiply

__all__ = ["ASSET_MODES", "ASSET_PREFIX", "EXCLUDED_WORDS", "SETTING_SKIES", "asset_candidates", "asset_cloud", "asset_index", "pick_asset", "setting_sky",
           "uses_assets"]

ASSET_MODES = ("auto", "off", "require")
ASSET_PREFIX = "asset:"
ENV_SOURCES = "MORPHOSIM_ASSET_SOURCES"
INSTALL_HINT = "apt install sweethome3d-furniture 0ad-data flightgear-data-models blender-data"
_log = logging.getLogger(__name__)
_WORD = re.compile(r"[a-z0-9]+")

# words (of an asset's name or tags) that keep it out of a category's picks: a ceiling or
# pendant lamp hangs above the frame, so "a lamp" on the ground would show nothing.
EXCLUDED_WORDS: dict[str, frozenset[str]] = {
    "lamp": frozenset({"ceiling", "pendant", "hanging", "chandelier"}),
}


def env_sources() -> tuple[str, ...] | None:
    raw = os.environ.get(ENV_SOURCES)
    return None if raw is None else tuple(n.strip() for n in raw.split(",") if n.strip())


@functools.lru_cache(maxsize=8)
def _index_for(sources: tuple[str, ...] | None) -> AssetIndex:
    return AssetIndex.load(default_sources(system=None if sources is None else list(sources)))


def asset_index() -> AssetIndex:
    """The index of the system sources `$MORPHOSIM_ASSET_SOURCES` allows (cached per process)."""
    return _index_for(env_sources())


@functools.lru_cache(maxsize=1)
def _notice_once() -> None:
    _log.warning("No real asset source is installed: objects use the procedural builders "
                 "(real furniture, vehicles, animals and skies: %s)", INSTALL_HINT)


def uses_assets(mode: str) -> bool:
    """Whether objects should come from real assets under `mode` (notice / error when none are installed)."""
    if mode not in ASSET_MODES:
        raise ValueError(f"Expected assets in {ASSET_MODES}, found {mode!r}")
    if mode == "off":
        return False
    if env_sources() == ():
        if mode == "require":
            raise AssetError(f"assets='require' but ${ENV_SOURCES} is empty (no source allowed)")
        return False
    if not any(r.kind in ("mesh", "splat") for r in asset_index()):
        if mode == "require":
            raise AssetError(f"assets='require' but no asset source is installed ({INSTALL_HINT})")
        _notice_once()
        return False
    return True


def _words(text: str) -> set[str]:
    words = set(_WORD.findall(text.lower()))
    return words | {w[:-1] for w in words if len(w) > 3 and w.endswith("s")}


def _other_compound(name: str, category: str) -> bool:
    """A name WordNet knows as a compound that is not a kind of the category ("Hot dog" is food)."""
    words = _WORD.findall(name.lower())
    return len(words) > 1 and bool(ranked_senses(" ".join(words))) and \
        kind_category(" ".join(words), [category]) is None


@functools.lru_cache(maxsize=256)
def _candidates(category: str, sources: tuple[str, ...] | None) -> tuple[AssetRecord, ...]:
    index = _index_for(sources)
    want = _words(category.replace("_", " "))
    entry = CATEGORIES.get(category)
    # a synonym WordNet calls a sibling of the category ("stool" of chair, "ship" of boat) names no asset of it
    synonyms = {w.lower() for w in (entry.synonyms if entry is not None else ())
                if " " not in w and not synonym_sibling(w.lower())}

    excluded = EXCLUDED_WORDS.get(category, frozenset())

    def matches(r: AssetRecord) -> bool:
        words = _WORD.findall(r.name.lower())
        head = words[-1] if words else ""
        if excluded & _words(" ".join((r.name, *r.tags))):
            return False
        # the category's words in the name count only with its last word as the name's head noun:
        # "Dog house" is a house, not a dog
        named = bool(want and want <= _words(r.name)) and head_word(r.name) in _words(category.split("_")[-1])
        return r.category == category or ((named or head in synonyms) and not _other_compound(r.name, category))

    hits = [r for r in index if r.kind in ("mesh", "splat") and matches(r)]
    return tuple(sorted(hits, key=lambda r: r.id))


def asset_candidates(category: str) -> tuple[AssetRecord, ...]:
    """Every mesh or splat asset matching a category: same category, or the name holds the words of
    its name with its last word as the name's head noun ("Dog house" is not a dog), or its last word is one of its vocabulary synonyms ("person": "Sitting boy"), by id;
    never one whose name or tags hold a word of the category's `EXCLUDED_WORDS` (ceiling lamps)."""
    if category.startswith(ASSET_PREFIX):
        aid = category[len(ASSET_PREFIX):]
        index = asset_index()
        return (index.get(aid),) if aid in index else ()
    return _candidates(category, env_sources())


def pick_asset(category: str, seed: int, k: int) -> AssetRecord | None:
    """The asset object `k` of a scene with this seed gets (None: no asset matches)."""
    cands = asset_candidates(category)
    if not cands:
        return None
    return cands[int(np.random.default_rng([seed, 3, k]).integers(len(cands)))]


# a quarter turn about z: the front of a y-up model (-y in the asset layer's object frame) to +x
FRONT_TO_X = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def asset_cloud(record: AssetRecord, budget: int, longest_m: float | None, seed: int,
                front_to_x: bool = False) -> SurfaceCloud:
    """The asset as a one-node surface cloud in its object frame (base on z = 0), longest side
    `longest_m` metres (None: its real-world size); with `front_to_x` a y-up model's front turns
    from -y (towards the camera) to +x, the forward of the procedural builders."""
    g = asset_gaussians(record, budget=budget, size_m=longest_m, seed=seed)
    n = len(g.means)
    means, quats = np.asarray(g.means, dtype=np.float64), np.asarray(g.quats, dtype=np.float64)
    if front_to_x and record.up_axis != "z":
        means = means @ FRONT_TO_X.T
        quats = quat_multiply(np.broadcast_to(matrix_to_quat(FRONT_TO_X), quats.shape), quats)
    return SurfaceCloud(means=means, quats=quats,
                        scales=np.asarray(g.scales, dtype=np.float64),
                        opacities=np.asarray(g.opacities, dtype=np.float64),
                        colors=np.asarray(g.colors, dtype=np.float64), nodes=np.zeros(n, dtype=np.int64),
                        node_names=["body"])


# outdoor settings -> the sky panoramas they may get (Blender's studio lights, by stem)
SETTING_SKIES: dict[str, tuple[str, ...]] = {
    "ground": ("courtyard", "city", "forest", "sunrise", "sunset"),
    "grass": ("forest", "courtyard", "sunrise", "sunset"),
    "road": ("city", "courtyard", "sunset"),
    "snow": ("sunrise", "courtyard"),
    "sand": ("sunset", "sunrise"),
    "water": ("sunset", "sunrise", "courtyard"),
    "sky": ("sunrise", "sunset", "courtyard"),
}
SKY_SIZE = (128, 256)   # rows, columns of the stored equirectangular sky


@functools.lru_cache(maxsize=16)
def _sky_image(path: str) -> np.ndarray:
    import cv2

    from ..assets import load_sky
    img = load_sky(path).image
    return cv2.resize(img, (SKY_SIZE[1], SKY_SIZE[0]), interpolation=cv2.INTER_AREA).clip(0, 1).astype(np.float32)


def setting_sky(setting: str, seed: int) -> np.ndarray | None:
    """An equirectangular sky [128, 256, 3] for an outdoor setting, picked by seed (None: indoor,
    or no panorama installed)."""
    names = SETTING_SKIES.get(setting)
    if not names:
        return None
    skies = sorted((r for r in asset_index() if r.kind == "sky" and r.name.lower() in names), key=lambda r: r.id)
    if not skies:
        return None
    record = skies[int(np.random.default_rng([seed, 4]).integers(len(skies)))]
    try:
        return _sky_image(record.path)
    except AssetError:
        return None
