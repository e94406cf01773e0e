"""The asset index: real installed sources (skipped when absent), caching, broken input, search."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from morphosim_gym.assets import AssetIndex, AssetRecord, AssetWarning, FolderSource
from morphosim_gym.assets.sources import RobosuiteSource, StudioLightsSource, SweetHome3DSource
from morphosim_gym.assets.sources.sweethome3d import parse_properties

from .conftest import write_quad

SH3D = SweetHome3DSource.discover()
ROBOSUITE = RobosuiteSource.discover()
SKIES = StudioLightsSource.discover()


@pytest.mark.skipif(SH3D is None, reason="Debian sweethome3d-furniture is not installed "
                                         "(/usr/share/sweethome3d/furniture/*.sh3f)")
def test_sweethome3d_catalogues(tmp_path):
    index = AssetIndex.build([SH3D], cache_dir=tmp_path)
    assert len(index) > 100
    for r in index:
        assert r.kind == "mesh" and r.up_axis == "y" and r.unit_scale == 0.01
        assert r.size_m is not None and min(r.size_m) > 0 and r.licence and r.member.endswith(".obj")
    horses = [r for r, _ in index.search("horse", k=5)]
    assert any(r.category == "Characters" for r in horses)


@pytest.mark.skipif(ROBOSUITE is None, reason="robosuite's files are not installed (pip robosuite)")
def test_robosuite_objects(tmp_path):
    index = AssetIndex.build([ROBOSUITE], cache_dir=tmp_path)
    names = {r.name for r in index}
    assert {"bread", "can", "milk"} <= names
    for r in index:
        assert r.up_axis == "z" and r.unit_scale == 1.0 and max(r.size_m) < 0.5   # metres, tabletop objects


@pytest.mark.skipif(SKIES is None, reason="Debian blender-data's studio-light worlds are not installed")
def test_sky_panoramas_are_listed(tmp_path):
    index = AssetIndex.build([SKIES], cache_dir=tmp_path)
    assert len(index.kind("sky")) == len(index) >= 1


def test_index_is_cached_and_rebuilt_when_files_change(quad_dir, tmp_path, monkeypatch):
    src = FolderSource(quad_dir)
    first = AssetIndex.build([src], cache_dir=tmp_path / "c")
    assert [r.name for r in first] == ["quad"]
    assert json.loads((tmp_path / "c" / "index.json").read_text())["version"] == 1

    def boom(self):
        raise AssertionError("records() should not be called for an unchanged source")

    monkeypatch.setattr(FolderSource, "records", boom)
    again = AssetIndex.build([src], cache_dir=tmp_path / "c")
    assert [r.to_dict() for r in again] == [r.to_dict() for r in first]
    monkeypatch.undo()
    write_quad(quad_dir / "toys")                       # a new file in a sub-folder: its category is "toys"
    grown = AssetIndex.build([src], cache_dir=tmp_path / "c")
    assert sorted(r.category for r in grown) == ["object", "toys"]


def test_damaged_index_cache_is_rebuilt(quad_dir, tmp_path):
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "index.json").write_text('{"version": 1, "sources": {"fol')
    with pytest.warns(AssetWarning, match="index.json"):
        index = AssetIndex.build([FolderSource(quad_dir)], cache_dir=tmp_path / "c")
    assert len(index) == 1
    assert json.loads((tmp_path / "c" / "index.json").read_text())["version"] == 1
    assert not [p for p in (tmp_path / "c").iterdir() if p.suffix == ".tmp"]


def test_broken_catalogue_and_entries_are_skipped_with_a_warning(tmp_path):
    folder = tmp_path / "sh3f"
    folder.mkdir()
    (folder / "Broken.sh3f").write_bytes(b"not a zip")
    props = ("name=Test\nlicense=CC0\n"
             "name#1=Good chair\ncategory#1=Living room\nmodel#1=/good/chair.obj\nwidth#1=50\ndepth#1=40\nheight#1=90\n"
             "tags#1=Seat, Wood\n"
             "name#2=Lost lamp\ncategory#2=Lights\nmodel#2=/lost/lamp.obj\nwidth#2=10\ndepth#2=10\nheight#2=30\n"
             "name#3=Flat\ncategory#3=Misc\nmodel#3=/good/chair.obj\nwidth#3=0\ndepth#3=1\nheight#3=1\n")
    with zipfile.ZipFile(folder / "Good.sh3f", "w") as z:
        z.writestr("PluginFurnitureCatalog.properties", props)
        z.writestr("good/chair.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.warns(AssetWarning) as caught:
        index = AssetIndex.build([SweetHome3DSource(folder)], cache_dir=tmp_path / "c")
    messages = " ".join(str(w.message) for w in caught)
    assert "Broken.sh3f" in messages and "lost/lamp.obj" in messages and "entry #3" in messages
    (chair,) = index.records
    assert chair.name == "Good chair" and chair.size_m == (0.5, 0.4, 0.9) and chair.tags == ("seat", "wood")
    assert chair.licence == "CC0" and chair.id == "sweethome3d/good/chair"


def test_properties_parser():
    text = "# comment\nname#1=Bill 10\\u20ac\nkey\\:x = a \\\n   b\n! other\n"
    assert parse_properties(text) == {"name#1": "Bill 10\u20ac", "key:x": "a b"}


def _record(i, name, category, tags=()):
    return AssetRecord(id=f"t/x/{i}", name=name, category=category, source="t", licence="", kind="mesh",
                       path="/none", tags=tags)


def test_search_words_then_embeddings():
    index = AssetIndex([_record(0, "Rocking horse", "Bedroom", ("toy",)), _record(1, "Horse", "Characters"),
                        _record(2, "Armchair", "Living room", ("seat",)), _record(3, "Sofa", "Living room")])
    assert [r.name for r, _ in index.search("horse")] == ["Horse", "Rocking horse"]
    assert [r.name for r, _ in index.search("seat")] == ["Armchair"]
    assert index.search("giraffe") == []

    vocab = ["horse", "seat", "sofa", "armchair", "toy", "couch"]

    def embed(texts):   # bag of words, with "couch" made a synonym of "sofa"
        out = np.array([[float(w in t.lower().replace("couch", "sofa")) for w in vocab] for t in texts]) + 1e-3
        return out / np.linalg.norm(out, axis=1, keepdims=True)

    hits = index.search("couch", k=2, embed=embed)
    assert hits[0][0].name == "Sofa" and len(hits) == 2
    by_vector = index.search(embed(["sofa"])[0], k=1, embed=embed)
    assert by_vector[0][0].name == "Sofa"
    with pytest.raises(KeyError, match="did you mean"):
        index.get("t/x")


def test_folder_settings_file(quad_dir):
    (quad_dir / "morphosim_assets.json").write_text('{"up_axis": "z", "unit_scale": 0.01, "licence": "CC0"}')
    (record,) = FolderSource(quad_dir).records()
    assert (record.up_axis, record.unit_scale, record.licence) == ("z", 0.01, "CC0")
    assert FolderSource(quad_dir, up_axis="y").records()[0].up_axis == "y"     # arguments win
    (quad_dir / "morphosim_assets.json").write_text('{"up": "z"}')
    with pytest.raises(ValueError, match=r"Unknown key 'up' in .*morphosim_assets.json"):
        FolderSource(quad_dir)
