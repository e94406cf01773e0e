"""FlightGear's models (Debian `flightgear-data-models`): a tiny Models folder written here, the source
absent, and the real package (skipped when it is not installed): every curated model at its size,
upright and facing the camera, with its licence; nouns that ground to them."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import morphosim_gym.assets.sources.flightgear as fg
from morphosim_gym.assets import AssetIndex, ConversionCache, asset_gaussians, default_sources
from morphosim_gym.assets.sources import FlightGearSource

REAL = FlightGearSource.discover()
needs_real = pytest.mark.skipif(REAL is None, reason="Debian flightgear-data-models is not installed "
                                                     f"({fg.DEFAULT_ROOT})")

# a "boat" in the file's frame (y-up, front to -x as FlightGear's vehicles): a 10 x 2 x 3 box hull, a
# pointed bow reaching x = -7, and a 100 m wake plane at the waterline that must not count
BOAT = """AC3Db
MATERIAL "hull" rgb 0.8 0.2 0.2  amb 0.2 0.2 0.2  emis 0 0 0  spec 0 0 0  shi 10  trans 0
OBJECT world
kids 3
OBJECT poly
name "hull"
numvert 8
-5 0 -1
5 0 -1
5 0 1
-5 0 1
-5 3 -1
5 3 -1
5 3 1
-5 3 1
numsurf 6
SURF 0x20
mat 0
refs 4
0 0 0
1 0 0
2 0 0
3 0 0
SURF 0x20
mat 0
refs 4
4 0 0
5 0 0
6 0 0
7 0 0
SURF 0x20
mat 0
refs 4
0 0 0
1 0 0
5 0 0
4 0 0
SURF 0x20
mat 0
refs 4
3 0 0
2 0 0
6 0 0
7 0 0
SURF 0x20
mat 0
refs 4
0 0 0
3 0 0
7 0 0
4 0 0
SURF 0x20
mat 0
refs 4
1 0 0
2 0 0
6 0 0
5 0 0
kids 0
OBJECT poly
name "bow"
numvert 3
-5 0 -1
-5 0 1
-7 1.5 0
numsurf 1
SURF 0x20
mat 0
refs 3
0 0 0
1 0 0
2 0 0
kids 0
OBJECT poly
name "Wake"
numvert 4
-50 0 -20
50 0 -20
50 0 20
-50 0 20
numsurf 1
SURF 0x20
mat 0
refs 4
0 0 0
1 0 0
2 0 0
3 0 0
kids 0
"""


def _models(tmp_path, readme: bool = True):
    """A Models folder holding Maritime/Civilian/Boat.ac (listed in readme.savage when `readme`)."""
    folder = tmp_path / "Models" / "Maritime" / "Civilian"
    folder.mkdir(parents=True)
    (folder / "Boat.ac").write_text(BOAT)
    if readme:
        (folder / "readme.savage").write_text("The following models were converted...\n\nBoat.ac Other.ac\n")
    return tmp_path / "Models"


@pytest.fixture
def boat_table(monkeypatch):
    table = {"ships/boat": fg._m("Maritime/Civilian/Boat.ac", "Boat", "boat", "dinghy", 24.0),
             "ships/absent": fg._m("Maritime/Civilian/Absent.ac", "Absent", "boat", "", 5.0)}
    monkeypatch.setattr(fg, "MODELS", table)
    return table


def test_absent_package_is_skipped_cleanly(tmp_path, monkeypatch):
    monkeypatch.setattr(fg, "DEFAULT_ROOT", str(tmp_path / "no-flightgear"))
    assert FlightGearSource.discover() is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert default_sources(system=["flightgear"], use_env=False) == []
        assert FlightGearSource(tmp_path / "no-flightgear").records() == []
        assert len(AssetIndex.build([FlightGearSource(tmp_path / "no-flightgear")], cache_dir=tmp_path / "c")) == 0


def test_a_model_is_sized_turned_and_licensed_by_its_row(tmp_path, boat_table):
    [rec] = FlightGearSource(_models(tmp_path)).records()              # the absent file is left out silently
    assert (rec.id, rec.name, rec.category, rec.up_axis, rec.tags) == ("flightgear/ships/boat", "Boat", "boat", "y",
                                                                       ("dinghy",))
    assert rec.licence == fg.SAVAGE_LICENCE and rec.extra["skip"] == ["wake", "shadow"]
    # 12 m long (bow included, wake left out) scaled to 24: 2 x 3 x 12 file units -> x 4, y 24, z 6
    assert rec.extra["native_longest_m"] == pytest.approx(12.0)
    assert np.allclose(rec.size_m, (4.0, 24.0, 6.0))
    g = asset_gaussians(rec, budget=3000, cache=ConversionCache(tmp_path / "conv"))
    assert np.allclose(np.ptp(g.means, axis=0), (4.0, 24.0, 6.0), atol=0.3)
    bow = g.means[g.means[:, 1] < -10]                                  # the front is at -y, towards the camera
    assert len(bow) > 0 and np.ptp(bow[:, 0]) < 2.0                     # ... and it is the pointed end


def test_the_licence_is_gpl_unless_savage_lists_the_file(tmp_path, boat_table):
    [rec] = FlightGearSource(_models(tmp_path, readme=False)).records()
    assert rec.licence == fg.LICENCE and "GPL-2.0-or-later" in rec.licence


def test_yaw_turns_the_front_to_plus_z():
    assert np.allclose(fg.yaw_rotation(90) @ [-1, 0, 0], [0, 0, 1])
    assert np.allclose(fg.yaw_rotation(180) @ [0, 0, -1], [0, 0, 1])


def test_an_edited_table_rereads_the_folder(tmp_path, boat_table, monkeypatch):
    root = _models(tmp_path)
    assert [r.name for r in AssetIndex.build([FlightGearSource(root)], cache_dir=tmp_path / "c")] == ["Boat"]
    monkeypatch.setattr(fg, "MODELS", {"ships/boat": fg._m("Maritime/Civilian/Boat.ac", "Dinghy", "boat", "", 6.0)})
    assert [r.name for r in AssetIndex.build([FlightGearSource(root)], cache_dir=tmp_path / "c")] == ["Dinghy"]


# ------------------------------------------------------------------------------- the real package
# things that travel: their length runs front to back along y, longer than their width (wings and rotors aside)
LENGTHWISE = {"boat", "ship", "train", "rail car", "bus", "truck", "car", "aircraft tug", "crane", "missile", "bomb"}
TALL = {"tower", "rocket", "buoy", "silo", "skyscraper", "beacon", "parachutist"}


@pytest.fixture(scope="module")
def real_index(tmp_path_factory):
    return AssetIndex.build([REAL], cache_dir=tmp_path_factory.mktemp("fg-index"))


@needs_real
def test_every_curated_model_is_there_at_its_size(real_index):
    assert {r.id.split("/", 1)[1] for r in real_index} == set(fg.MODELS)
    for r in real_index:
        model = fg.MODELS[r.id.split("/", 1)[1]]
        native = r.extra["native_longest_m"]
        # the file's own size (its unit, stray planes left out) is the real thing's, within 12%
        assert model.longest_m / 1.12 < native < model.longest_m * 1.12, (r.id, native, model.longest_m)
        assert max(r.size_m) == pytest.approx(model.longest_m, rel=1e-6)
        assert r.kind == "mesh" and r.up_axis == "y" and r.path.endswith(".ac") and r.licence


@needs_real
def test_upright_and_lengthwise(real_index):
    for r in real_index:
        x, y, z = r.size_m
        if r.category in LENGTHWISE:
            assert y > x, (r.id, r.size_m)                      # front to back along y (masts may be taller)
        if r.category in TALL:
            assert z == max(x, y, z), (r.id, r.size_m)          # standing up


@needs_real
@pytest.mark.parametrize("rid", ["ships/container_ship", "ships/tanker", "ships/cruise_ship", "ships/freighter",
                                 "ships/ferry", "ships/large_ferry", "ships/large_trawler", "ships/frigate",
                                 "ships/cruiser", "ships/sailboat", "aircraft/f15", "aircraft/missile"])
def test_fronts_face_the_camera(real_index, rid, tmp_path):
    """A ship's bow, a jet's nose, a missile's seeker are narrower than their sterns and tails: the
    narrow end is at -y, where the asset layer puts a y-up model's front (the camera's side)."""
    g = asset_gaussians(real_index.get(f"flightgear/{rid}"), budget=6000, cache=ConversionCache(tmp_path / "c"))
    y = g.means[:, 1]
    lo, hi = y.min(), y.max()
    front = g.means[y < lo + 0.02 * (hi - lo)]          # the last 2% of the length at each end
    back = g.means[y > hi - 0.02 * (hi - lo)]
    assert np.ptp(front[:, 0]) < 0.6 * np.ptp(back[:, 0]), rid


@needs_real
def test_licences_per_asset(real_index, capsys):
    from morphosim_gym.cli import main

    licences = {r.id: r.licence for r in real_index}
    assert licences["flightgear/ships/container_ship"] == fg.SAVAGE_LICENCE         # listed in readme.savage
    assert licences["flightgear/sea/red_buoy"] == fg.SAVAGE_LICENCE
    assert licences["flightgear/aircraft/h60"] == fg.LICENCE
    assert set(licences.values()) == {fg.LICENCE, fg.SAVAGE_LICENCE}
    assert main(["assets", "show", "flightgear/ships/sailboat", "--sources", "flightgear"]) == 0
    assert json.loads(capsys.readouterr().out)["licence"] == fg.SAVAGE_LICENCE


# ------------------------------------------------------------------------------- nouns to assets
@pytest.fixture
def grounding(monkeypatch):
    from morphosim_gym.language import embeddings, wordnet

    if REAL is None or not wordnet.available() or not embeddings.is_available():
        pytest.skip("needs flightgear-data-models, WordNet (wordnet-base) and the MiniLM model")
    monkeypatch.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
    monkeypatch.delenv("MORPHOSIM_GROUNDING", raising=False)
    import morphosim_gym.generate.compose  # noqa: F401  (registers the real assets as open-vocabulary candidates)


def _scene_asset(text: str, seed: int = 0) -> str | None:
    from morphosim_gym.generate.compose import compose_scene
    from morphosim_gym.language import parse

    scene = compose_scene(parse(text), seed).scene
    return scene.objects[1].asset


@pytest.mark.parametrize("text, asset", [
    ("a helicopter", "flightgear/aircraft/"),
    ("a sailboat", "flightgear/ships/sailboat"),
    ("a container ship", "flightgear/ships/container_ship"),
    ("an aircraft carrier", "flightgear/ships/carrier"),        # a compound naming another thing than "aircraft"
])
def test_open_nouns_ground_to_flightgear_assets(grounding, text, asset):
    from morphosim_gym.generate.real_assets import asset_index
    from morphosim_gym.language import parse

    [obj] = parse(text).objects
    assert obj.category.startswith(f"asset:{asset}"), obj
    assert asset_index().get(obj.category[len("asset:"):]).source == "flightgear"
    assert _scene_asset(text).startswith(asset)


@pytest.mark.parametrize("text, category, asset", [
    ("an airplane", "airplane", "flightgear/aircraft/"),
    ("a double-decker bus", "bus", "flightgear/vehicles/double_decker"),
])
def test_category_nouns_get_flightgear_assets(grounding, text, category, asset):
    from morphosim_gym.generate.real_assets import asset_candidates, pick_asset
    from morphosim_gym.language import parse

    [obj] = parse(text).objects
    assert obj.category == category
    assert any(r.id.startswith(asset) for r in asset_candidates(category))
    seed = next(s for s in range(50) if pick_asset(category, s, 0).id.startswith(asset))
    assert _scene_asset(text, seed).startswith(asset)
