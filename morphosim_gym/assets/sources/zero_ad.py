"""0 A.D.'s animals and nameable props (Debian `0ad-data`, CC-BY-SA 3.0): y-up PMD meshes with DDS skins.

Everything lives in one zip (`mods/public/public.zip`, ~3 GB); only the members an asset needs are
read. An actor file (`art/actors/<...>.xml`) names a mesh (`<mesh>skeletal/tiger.dae</mesh>`,
stored converted as `art/meshes/skeletal/tiger.dae.cached.pmd`) and a colour texture (`baseTex`,
stored as `art/textures/skins/<file>.cached.dds`). The useful subset is chosen by table: one asset
per animal species (`FAUNA`, by actor) and per kind of prop (`PROPS`, the first actor, by name,
whose stem holds the keyword; weapons and armour from the unit props, `GEAR`; single named actors of
tools, mushrooms, young animals, vessels and a few more, `NAMED`). An actor whose mesh or texture is missing or unreadable is
skipped with an `AssetWarning`; the other assets stay usable.

Units: 0 A.D. models are about 2.5 units to the metre (a horse stands ~5.6 units at the head).
"""

from __future__ import annotations

import hashlib
import json
import os
import posixpath
import re
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

from ..pmd import read_pmd
from ..record import AssetRecord
from .base import FileStat, file_stats, warn_skip

__all__ = ["DEFAULT_ZIP", "FAUNA", "LICENCE", "NAMED", "PROPS", "UNIT_SCALE", "ZeroADSource", "actor_parts"]

DEFAULT_ZIP = "/usr/share/games/0ad/mods/public/public.zip"
LICENCE = "CC-BY-SA 3.0 (0 A.D., Wildfire Games)"
UNIT_SCALE = 0.4          # metres per 0 A.D. unit
MAX_MEMBER_BYTES = 16 * 1024 * 1024

# actor stem (art/actors/fauna/<stem>.xml) -> (name, category, tags); category is one of the
# generator's when the animal is a kind of it, else "animal" ("monster" for the dragon)
FAUNA: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "arctic_wolf": ("Arctic wolf", "animal", ("wolf", "canine")),
    "bear_brown": ("Brown bear", "animal", ("bear",)),
    "bear_black": ("Black bear", "animal", ("bear",)),
    "bear_white": ("Polar bear", "animal", ("bear", "white bear")),
    "boar": ("Wild boar", "animal", ("boar", "pig", "hog")),
    "bull": ("Bull", "cow", ("cattle", "ox")),
    "camel": ("Camel", "animal", ("dromedary",)),
    "chicken": ("Chicken", "bird", ("hen", "poultry")),
    "cow": ("Cow", "cow", ("cattle",)),
    "crocodile": ("Crocodile", "animal", ("reptile", "alligator")),
    "crow": ("Crow", "bird", ("raven",)),
    "deer": ("Deer", "animal", ("stag",)),
    "donkey": ("Donkey", "animal", ("ass",)),       # no "mule": a mule is a hybrid, no kind of donkey
    "dragon": ("Dragon", "monster", ("mythical monster", "firedrake")),   # the winged fantasy dragon: "firedrake"
    # names WordNet's mythical sense of "dragon", not its only visible one, the flying lizard ("a lizard")
    "elephant_african_bush": ("African elephant", "elephant", ()),
    "elephant_asian": ("Asian elephant", "elephant", ()),
    "fish_generic": ("Fish", "fish", ()),
    "fox_red": ("Red fox", "animal", ("fox",)),
    "fox_arctic": ("Arctic fox", "animal", ("fox",)),
    "gazelle": ("Gazelle", "animal", ("antelope",)),
    "giraffe_adult": ("Giraffe", "animal", ()),
    "goat": ("Goat", "animal", ()),
    "hawk": ("Hawk", "bird", ("falcon", "bird of prey")),
    "hippopotamus": ("Hippopotamus", "animal", ("hippo",)),
    "horse_persian": ("Horse", "horse", ()),
    "lion": ("Lion", "animal", ("big cat",)),
    "lioness": ("Lioness", "animal", ("lion", "big cat")),
    "mastiff": ("Mastiff", "dog", ("dog",)),
    "muskox": ("Musk ox", "animal", ("ox",)),
    "peacock": ("Peacock", "bird", ("peafowl",)),
    "pig1": ("Pig", "animal", ("hog", "swine")),
    "pony": ("Pony", "horse", ("horse",)),
    "rabbit1": ("Rabbit", "animal", ("bunny", "hare")),
    "rhino": ("Rhinoceros", "animal", ("rhino",)),
    "seagull": ("Seagull", "bird", ("gull",)),
    "shark": ("Shark", "fish", ()),
    "sheep1": ("Sheep", "sheep", ("lamb",)),
    "tiger": ("Tiger", "animal", ("big cat",)),
    "tuna": ("Tuna", "fish", ()),
    "walrus": ("Walrus", "animal", ("seal",)),
    "whale": ("Whale", "animal", ()),
    "wildebeest": ("Wildebeest", "animal", ("gnu", "antelope")),
    "wolf": ("Wolf", "animal", ("canine",)),
    "zebra": ("Zebra", "animal", ()),
    "zebu": ("Zebu", "cow", ("cattle",)),
}
FAUNA_DIR = "art/actors/fauna"

# keyword of a prop actor's stem -> (name, category, tags); folders searched in `PROP_DIRS` order
PROPS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "amphorae": ("Amphora", "vase", ("jar", "pottery")),
    "anvil": ("Anvil", "prop", ("smithy",)),
    "barrel": ("Barrel", "prop", ("cask", "keg")),
    "basket": ("Basket", "prop", ("wicker",)),
    "bench": ("Bench", "prop", ("seat",)),
    "bucket": ("Bucket", "prop", ("pail",)),
    "campfire": ("Campfire", "prop", ("fire", "bonfire")),
    "column": ("Column", "prop", ("pillar",)),
    "crate": ("Crate", "box", ("wooden box",)),
    "handcart": ("Handcart", "prop", ("cart", "wheelbarrow")),
    "hay": ("Hay bale", "prop", ("straw",)),
    "obelisk": ("Obelisk", "prop", ("monument",)),
    "sack": ("Sack", "prop", ("bag",)),
    "skeleton": ("Skeleton", "prop", ("bones",)),
    "snowman": ("Snowman", "prop", ()),
    "statue": ("Statue", "prop", ("sculpture",)),
    "table": ("Wooden table", "table", ()),
    "vase": ("Vase", "vase", ("pottery",)),
    "wagon": ("Wagon", "prop", ("cart",)),
    "wheel": ("Wheel", "prop", ("cartwheel",)),
}
# ... of the unit props (weapons, tools, armour)
GEAR: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "axe": ("Axe", "prop", ("hatchet", "tool")),
    "bow": ("Bow", "prop", ("weapon",)),
    "spear": ("Spear", "prop", ("lance", "weapon")),
    "sword": ("Sword", "prop", ("blade", "weapon")),
    "shield": ("Shield", "prop", ("armour",)),
    "helmet": ("Helmet", "prop", ("armour", "helm")),
    "hammer": ("Hammer", "prop", ("tool",)),
}
# asset id -> (actor, name, category, tags): single actors of things with a plain name (tools, a well,
# mushrooms, young animals, vessels: a hull with its mast, the first mesh of the actor, no sails or
# oars from its props; a drum, a flag, a banner, a cauldron on its tripod, a chariot), each looked at in a render (0 A.D.'s plants are alpha-textured cards that
# render as flat sheets, so none is here); an actor the archive lacks is left out
NAMED: dict[str, tuple[str, str, str, tuple[str, ...]]] = {
    "props/well": ("art/actors/props/special/eyecandy/well_1_a.xml", "Well", "prop", ("water well", "wishing well")),
    "props/woodpile": ("art/actors/props/special/eyecandy/wood_pile.xml", "Woodpile", "prop",
                       ("logs", "firewood", "log pile")),
    "props/iceberg": ("art/actors/props/special/eyecandy/iceberg.xml", "Iceberg", "prop", ("ice",)),
    "props/standing_stones": ("art/actors/props/special/eyecandy/standing_stones.xml", "Standing stone", "prop",
                              ("menhir", "megalith", "monolith")),
    "props/sword_rack": ("art/actors/props/special/eyecandy/sword_rack.xml", "Sword rack", "prop", ("rack",)),
    "tools/hoe": ("art/actors/props/units/tools/hoe.xml", "Hoe", "prop", ("tool", "garden tool")),
    "tools/mallet": ("art/actors/props/units/tools/mallet.xml", "Mallet", "prop", ("tool", "hammer")),
    "tools/pickaxe": ("art/actors/props/units/tools/pick.xml", "Pickaxe", "prop", ("pick", "tool")),
    "tools/pitchfork": ("art/actors/props/units/tools/pitchfork.xml", "Pitchfork", "prop", ("fork", "tool")),
    "tools/scythe": ("art/actors/props/units/tools/scythe.xml", "Scythe", "prop", ("tool",)),
    "tools/spade": ("art/actors/props/units/tools/spade.xml", "Spade", "prop", ("shovel", "tool")),
    "tools/tongs": ("art/actors/props/units/tools/tongs.xml", "Tongs", "prop", ("tool",)),
    "fungi/mushroom": ("art/actors/fungi/tall_agaric.xml", "Mushroom", "prop", ("toadstool", "fungus", "agaric")),
    "fungi/chanterelle": ("art/actors/fungi/small_chanterelle.xml", "Chanterelle mushroom", "prop",
                          ("mushroom", "fungus")),
    "vessels/fishing_boat": ("art/actors/structures/celts/fishing_boat.xml", "Fishing boat", "boat", ("boat",)),
    "vessels/merchant_ship": ("art/actors/structures/celts/merchant_ship.xml", "Merchant ship", "ship",
                              ("ship", "sailing ship", "merchantman")),
    "vessels/rowboat": ("art/actors/structures/celts/rowboat.xml", "Rowboat", "boat", ("boat",)),
    "vessels/trireme": ("art/actors/structures/hellenes/trireme.xml", "Trireme", "ship", ("galley", "warship")),
    "vessels/longship": ("art/actors/structures/viking/longship.xml", "Longship", "ship", ("viking ship",)),
    "vessels/han_merchant": ("art/actors/structures/han/merchant_ship.xml", "Junk ship", "ship", ("junk", "sailing ship")),
    "props/drum": ("art/actors/props/structures/mercenaries/kush_nuba_camp_drum_big_01.xml", "Drum", "prop", ("percussion",)),
    "props/flag": ("art/actors/props/special/common/garrison_flag_rome.xml", "Flag", "prop", ("banner",)),
    "props/banner": ("art/actors/props/units/standards/formation_flag_gaul.xml", "Banner", "prop", ("flag",)),
    "props/cauldron": ("art/actors/props/structures/gauls/wonder_cauldron.xml", "Cauldron", "prop", ("pot", "tripod")),
    "props/chariot": ("art/actors/props/special/eyecandy/unyoked_chariot_celt.xml", "Chariot", "prop", ("horse-drawn vehicle",)),
    "fauna/piglet": ("art/actors/fauna/piglet.xml", "Piglet", "animal", ("pig",)),
    "fauna/elephant_calf": ("art/actors/fauna/elephant_african_baby.xml", "Elephant calf", "elephant",
                            ("baby elephant",)),
    "fauna/giraffe_calf": ("art/actors/fauna/giraffe_baby.xml", "Giraffe calf", "animal", ("baby giraffe",)),
}
PROP_DIRS = ("art/actors/props/special/eyecandy", "art/actors/props")
GEAR_DIRS = ("art/actors/props/units/weapons", "art/actors/props/units/tools", "art/actors/props/units/helmets",
             "art/actors/props/units/shields")
VARIANTS_DIR = "art/variants"


def actor_parts(actor_xml: bytes) -> tuple[str | None, str | None, list[str]]:
    """(mesh, colour texture, variant files) an actor (or variant) file names: its first `<mesh>`,
    its first `baseTex` texture (else its first unnamed one) and the `file`s of its variants
    (under `art/variants/`, where a horse's coat is); None for what it does not name.

    Raises:
        ValueError: not XML.
    """
    try:
        root = ET.fromstring(actor_xml)
    except ET.ParseError as exc:
        raise ValueError(f"not an actor file ({exc})") from None
    mesh = next((m.text.strip() for m in root.iter("mesh") if m.text and m.text.strip()), None)
    textures = [(t.get("name"), t.get("file")) for t in root.iter("texture") if t.get("file")]
    tex = next((f for n, f in textures if n == "baseTex"), None)
    tex = tex if tex is not None else next((f for n, f in textures if not n), None)
    return mesh, tex, [v.get("file") for v in root.iter("variant") if v.get("file")]


def _actor_mesh_texture(z: zipfile.ZipFile, names: set[str], actor: str) -> tuple[str, str | None]:
    """(mesh, texture) of an actor, the texture looked up in its variant files when it names none."""
    mesh, tex, variants = actor_parts(z.read(actor))
    if mesh is None:
        raise ValueError("the actor names no mesh")
    for v in variants:
        if tex is not None:
            break
        member = posixpath.join(VARIANTS_DIR, v)
        if member in names:
            tex = actor_parts(z.read(member))[1]
    return mesh, tex


def _first(names: set[str], options: list[str]) -> str | None:
    return next((o for o in options if o in names), None)


def mesh_member(mesh: str, names: set[str]) -> str | None:
    """The zip member of an actor's mesh ("skeletal/tiger.dae" -> "art/meshes/skeletal/tiger.dae.cached.pmd")."""
    base = posixpath.join("art/meshes", mesh)
    stem = base.rsplit(".", 1)[0]
    return _first(names, [base + ".cached.pmd", stem + ".pmd", base])


def texture_member(texture: str, names: set[str]) -> str | None:
    """The zip member of an actor's colour texture (its converted DDS, else the file itself)."""
    base = posixpath.join("art/textures/skins", texture)
    stem = base.rsplit(".", 1)[0]
    return _first(names, [base + ".cached.dds", base, stem + ".dds", stem + ".png"])


class ZeroADSource:
    """The animals and props of 0 A.D.'s public mod (or of a zip laid out like it)."""

    name = "zero_ad"

    def __init__(self, archive: str | os.PathLike = DEFAULT_ZIP) -> None:
        self.archive = Path(archive)

    @property
    def selection(self) -> str:
        """A digest of the tables that pick the assets (`FAUNA`, `PROPS`, `GEAR`, `NAMED`): part of the
        index's cache key, so an edited table re-reads the archive."""
        tables = json.dumps([FAUNA, PROPS, GEAR, NAMED, PROP_DIRS, GEAR_DIRS], sort_keys=True)
        return hashlib.sha256(tables.encode()).hexdigest()[:16]

    @classmethod
    def discover(cls) -> ZeroADSource | None:
        return cls() if Path(DEFAULT_ZIP).is_file() else None

    def fingerprint(self) -> list[FileStat]:
        return file_stats([self.archive])

    def records(self) -> list[AssetRecord]:
        try:
            with zipfile.ZipFile(self.archive) as z:
                names = set(z.namelist())
                return self._fauna(z, names) + self._props(z, names) + self._named(z, names)
        except (OSError, zipfile.BadZipFile) as exc:
            warn_skip(self.archive, f"not a readable 0 A.D. archive ({type(exc).__name__}: {exc})")
            return []

    def _fauna(self, z: zipfile.ZipFile, names: set[str]) -> list[AssetRecord]:
        out = []
        for stem, (name, category, tags) in FAUNA.items():
            actor = f"{FAUNA_DIR}/{stem}.xml"
            if actor in names:
                rec = self._record(z, names, actor, f"fauna/{stem}", name, category, ("animal", *tags))
                if rec is not None:
                    out.append(rec)
        return out

    def _named(self, z: zipfile.ZipFile, names: set[str]) -> list[AssetRecord]:
        out = []
        for rid, (actor, name, category, tags) in NAMED.items():
            if actor in names:
                kind = "animal" if rid.startswith("fauna/") else rid.split("/", 1)[0].rstrip("s")
                rec = self._record(z, names, actor, rid, name, category, (kind, *tags))
                if rec is not None:
                    out.append(rec)
        return out

    def _props(self, z: zipfile.ZipFile, names: set[str]) -> list[AssetRecord]:
        by_dir: dict[str, list[str]] = {}
        for n in sorted(names):
            if n.endswith(".xml"):
                by_dir.setdefault(posixpath.dirname(n), []).append(n)
        out = []
        for dirs, table in ((PROP_DIRS, PROPS), (GEAR_DIRS, GEAR)):
            out += self._kinds(z, names, [a for d in dirs for a in by_dir.get(d, [])], table)
        return out

    def _kinds(self, z: zipfile.ZipFile, names: set[str], actors: list[str],
               table: dict[str, tuple[str, str, tuple[str, ...]]]) -> list[AssetRecord]:
        """One record per keyword of `table`: the first actor whose stem holds it and converts."""
        out = []
        for key, (name, category, tags) in table.items():
            for actor in sorted(actors, key=lambda a: posixpath.basename(a) != f"{key}.xml"):   # "spear.xml" first
                stem = posixpath.basename(actor)[:-4]
                if key not in re.findall(r"[a-z]+", stem.lower()):
                    continue
                rec = self._record(z, names, actor, f"props/{key}", name, category, ("prop", *tags), warn=False)
                if rec is not None:
                    out.append(rec)
                    break
        return out

    def _record(self, z: zipfile.ZipFile, names: set[str], actor: str, rid: str, name: str, category: str,
                tags: tuple[str, ...], warn: bool = True) -> AssetRecord | None:
        where = f"{self.archive}!{actor}"
        try:
            mesh, texture = _actor_mesh_texture(z, names, actor)
            member = mesh_member(mesh, names)
            if member is None:
                raise ValueError(f"its mesh {mesh!r} is not in the archive")
            tex = texture_member(texture, names) if texture else None
            if tex is None:
                raise ValueError(f"its colour texture {texture!r} is not in the archive")
            if z.getinfo(member).file_size > MAX_MEMBER_BYTES:
                raise ValueError(f"its mesh {member} is above {MAX_MEMBER_BYTES >> 20} MiB")
            pmd = read_pmd(z.read(member))
            if len(pmd.faces) == 0:
                raise ValueError(f"its mesh {member} has no triangles")
            ext = np.ptp(pmd.positions, axis=0)          # y-up file: (x, y, z) -> z-up (x, z, y)
            size = tuple(round(max(float(s) * UNIT_SCALE, 1e-3), 6) for s in (ext[0], ext[2], ext[1]))
        except (KeyError, ValueError, zipfile.BadZipFile, OSError) as exc:
            if warn:
                warn_skip(where, f"0 A.D. actor does not convert ({type(exc).__name__}: {exc})")
            return None
        return AssetRecord(id=f"{self.name}/{rid}", name=name, category=category, source=self.name, licence=LICENCE,
                           kind="mesh", path=str(self.archive), member=member, tags=tags, up_axis="y",
                           unit_scale=UNIT_SCALE, size_m=size, creator="Wildfire Games",
                           extra={"actor": actor, "texture": tex})
