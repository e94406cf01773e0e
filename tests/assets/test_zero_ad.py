"""0 A.D.'s PMD meshes and actors: a tiny archive written here (no 0ad needed), bad input, and the
real `0ad-data` package (skipped when it is not installed)."""

from __future__ import annotations

import io
import struct
import zipfile

import numpy as np
import pytest
from PIL import Image

from morphosim_gym.assets import AssetError, AssetIndex, AssetWarning, ConversionCache, asset_gaussians
from morphosim_gym.assets.pmd import read_pmd, write_pmd
from morphosim_gym.assets.sources import ZeroADSource

REAL = ZeroADSource.discover()

# a unit square (file frame y-up: the square stands in the x-y plane), UV (0,0) bottom-left
SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
SQUARE_UV = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
SQUARE_FACES = np.array([[0, 1, 2], [0, 2, 3]])
RED = (230, 20, 20)

ACTOR = """<?xml version="1.0" encoding="utf-8"?>
<actor version="1"><group><variant name="Mesh"><mesh>skeletal/tiger.dae</mesh></variant></group>
<group><variant name="coat"><textures><texture file="skeletal/tiger.png" name="baseTex"/></textures></variant></group>
</actor>"""


def _png(rgb) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(np.full((4, 4, 3), rgb, dtype=np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def _archive(path, members: dict[str, bytes]) -> str:
    with zipfile.ZipFile(path, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    return str(path)


def _tiger_members(pmd: bytes | None = None) -> dict[str, bytes]:
    return {"art/actors/fauna/tiger.xml": ACTOR.encode(),
            "art/meshes/skeletal/tiger.dae.cached.pmd": pmd or write_pmd(SQUARE, SQUARE_FACES, SQUARE_UV),
            "art/textures/skins/skeletal/tiger.png": _png(RED)}


def test_pmd_round_trip():
    for version in (2, 3, 4):
        m = read_pmd(write_pmd(SQUARE, SQUARE_FACES, SQUARE_UV, version=version))
        assert np.allclose(m.positions, SQUARE) and np.allclose(m.uvs, SQUARE_UV)
        assert m.faces.tolist() == SQUARE_FACES.tolist() and m.n_bones == 0


@pytest.mark.parametrize("data, message", [
    (b"NOPE" + b"\0" * 20, "PSMD"),
    (b"PSMD" + struct.pack("<I", 9) + b"\0" * 8, "version"),
    (write_pmd(SQUARE, SQUARE_FACES)[:60], "truncated"),
    (write_pmd(SQUARE, [[0, 1, 7]]), "vertex 7"),
])
def test_bad_pmd_is_a_clear_error(data, message):
    with pytest.raises(ValueError, match=message):
        read_pmd(data)


def test_tiny_archive_converts_with_its_texture(tmp_path):
    src = ZeroADSource(_archive(tmp_path / "public.zip", _tiger_members()))
    [rec] = src.records()
    assert (rec.id, rec.name, rec.up_axis, rec.unit_scale) == ("zero_ad/fauna/tiger", "Tiger", "y", 0.4)
    assert "CC-BY-SA" in rec.licence and rec.extra["texture"] == "art/textures/skins/skeletal/tiger.png"
    assert np.allclose(rec.size_m, (0.4, 1e-3, 0.4), atol=1e-6)    # a flat square: its depth floored at 1 mm
    cache = ConversionCache(tmp_path / "conv")
    g = asset_gaussians(rec, budget=200, cache=cache)
    assert np.allclose(g.colors, np.array(RED) / 255, atol=0.02)
    assert np.allclose(g.means[:, 2].max(), 0.4, atol=0.01)          # y-up -> z-up, 0.4 m per unit
    again = asset_gaussians(rec, budget=200, cache=cache)
    assert np.array_equal(g.means, again.means)


def test_texture_change_changes_the_cache_key(tmp_path):
    from morphosim_gym.assets import conversion_key
    from morphosim_gym.assets.convert import ConversionParams
    from morphosim_gym.assets.files import AssetFiles

    keys = []
    for colour in (RED, (10, 200, 10)):
        members = _tiger_members()
        members["art/textures/skins/skeletal/tiger.png"] = _png(colour)
        [rec] = ZeroADSource(_archive(tmp_path / f"p{colour[1]}.zip", members)).records()
        keys.append(conversion_key(rec, ConversionParams(budget=10), AssetFiles(rec)))
    assert keys[0] != keys[1]


def test_broken_actors_are_skipped_with_a_warning(tmp_path):
    members = _tiger_members()
    members["art/actors/fauna/wolf.xml"] = b"<actor><group><variant><mesh>skeletal/wolf.dae</mesh>"   # not XML
    members["art/actors/fauna/zebra.xml"] = ACTOR.replace("tiger.dae", "zebra.dae").encode()          # no mesh file
    members["art/actors/fauna/lion.xml"] = ACTOR.replace("tiger.dae", "lion.dae").encode()
    members["art/meshes/skeletal/lion.dae.cached.pmd"] = b"PSMD" + struct.pack("<III", 4, 0, 99)     # truncated
    with pytest.warns(AssetWarning) as caught:
        records = ZeroADSource(_archive(tmp_path / "public.zip", members)).records()
    assert [r.name for r in records] == ["Tiger"]
    text = " ".join(str(w.message) for w in caught)
    assert "wolf.xml" in text and "zebra.xml" in text and "lion.xml" in text


def test_unreadable_texture_warns_and_uses_the_default_colour(tmp_path):
    members = _tiger_members()
    members["art/textures/skins/skeletal/tiger.png"] = b"not an image"
    [rec] = ZeroADSource(_archive(tmp_path / "public.zip", members)).records()
    with pytest.warns(AssetWarning, match="tiger.png"):
        g = asset_gaussians(rec, budget=50, cache=False)
    assert len(g.means) == 50


def test_missing_archive_is_skipped_with_a_warning(tmp_path):
    (tmp_path / "public.zip").write_bytes(b"not a zip")
    with pytest.warns(AssetWarning, match="public.zip"):
        assert ZeroADSource(tmp_path / "public.zip").records() == []


def test_corrupt_mesh_at_conversion_names_the_file(tmp_path):
    [rec] = ZeroADSource(_archive(tmp_path / "public.zip", _tiger_members())).records()
    _archive(tmp_path / "public.zip", {**_tiger_members(), "art/meshes/skeletal/tiger.dae.cached.pmd": b"PSMDxx"})
    with pytest.raises(AssetError, match="tiger.dae.cached.pmd"):
        asset_gaussians(rec, budget=50, cache=False)


@pytest.mark.skipif(REAL is None, reason="Debian 0ad-data is not installed (/usr/share/games/0ad/mods/public)")
def test_real_0ad_animals_and_props(tmp_path):
    index = AssetIndex.build([REAL], cache_dir=tmp_path)
    names = {r.name for r in index}
    assert {"Tiger", "Whale", "Giraffe", "Polar bear", "Horse", "Barrel", "Sword"} <= names
    for r in index:
        assert r.kind == "mesh" and r.up_axis == "y" and r.member.endswith(".pmd") and r.extra["texture"]
        assert 0.01 < max(r.size_m) < (25 if r.category == "ship" else 12)      # a trireme: 18 m at game scale
    tiger = next(r for r in index if r.name == "Tiger")
    g = asset_gaussians(tiger, budget=2000, cache=ConversionCache(tmp_path / "conv"))
    assert 1.8 < float(np.ptp(g.means[:, 1])) < 3.0            # about 2.4 m nose to tail, along y
    assert float(np.std(g.colors)) > 0.05                      # textured, not one flat colour


def test_an_edited_selection_table_rereads_the_archive(tmp_path, monkeypatch):
    """The archive is unchanged, but a table of what to take from it grew: the cached index is stale."""
    import morphosim_gym.assets.sources.zero_ad as zero_ad

    members = _tiger_members()
    members["art/actors/fungi/tall_agaric.xml"] = ACTOR.encode()
    src = ZeroADSource(_archive(tmp_path / "public.zip", members))
    monkeypatch.setattr(zero_ad, "NAMED", {})
    assert [r.name for r in AssetIndex.build([src], cache_dir=tmp_path / "c")] == ["Tiger"]
    monkeypatch.setattr(zero_ad, "NAMED", {"fungi/mushroom": ("art/actors/fungi/tall_agaric.xml", "Mushroom", "prop",
                                                              ("toadstool",))})
    index = AssetIndex.build([src], cache_dir=tmp_path / "c")
    assert sorted(r.name for r in index) == ["Mushroom", "Tiger"]
    assert next(r for r in index if r.name == "Mushroom").tags == ("fungi", "toadstool")


@pytest.mark.skipif(REAL is None, reason="Debian 0ad-data is not installed (/usr/share/games/0ad/mods/public)")
def test_real_0ad_named_things(tmp_path):
    names = {r.name for r in AssetIndex.build([REAL], cache_dir=tmp_path)}
    assert {"Well", "Mushroom", "Hoe", "Pickaxe", "Pitchfork", "Piglet", "Fishing boat", "Merchant ship", "Rowboat",
            "Drum", "Flag", "Banner", "Cauldron", "Chariot"} <= names
