"""The "lamp" category never picks a ceiling or pendant lamp (it would hang out of frame)."""

import pytest

from morphosim_gym.assets import AssetRecord
from morphosim_gym.generate import real_assets
from morphosim_gym.generate.real_assets import asset_candidates


def _lamp(aid: str, name: str, tags: tuple[str, ...] = ()) -> AssetRecord:
    return AssetRecord(id=f"fake/{aid}", name=name, category="Lights", source="fake", licence="CC0", kind="mesh",
                       path="/nonexistent.obj", tags=tags)


@pytest.fixture
def fake_index(monkeypatch):
    records = [_lamp("desk", "Desk lamp"), _lamp("table", "Lamp"), _lamp("ceiling", "Ceiling lamp"),
               _lamp("saloon", "Pendant lamp", ("hanging", "pendant", "ceiling")),
               _lamp("chandelier", "Chandelier lamp"), _lamp("tagged", "Lamp", ("hanging",))]
    monkeypatch.setattr(real_assets, "_index_for", lambda sources: records)
    real_assets._candidates.cache_clear()
    yield records
    real_assets._candidates.cache_clear()


def test_lamp_excludes_hanging_and_ceiling_lamps_by_name_and_tags(fake_index):
    assert [r.id for r in asset_candidates("lamp")] == ["fake/desk", "fake/table"]


def test_installed_lamps_are_all_standing(monkeypatch):
    monkeypatch.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
    lamps = asset_candidates("lamp")
    if not lamps:
        pytest.skip("needs the Sweet Home 3D furniture (apt install sweethome3d-furniture)")
    for r in lamps:
        words = set(" ".join((r.name, *r.tags)).lower().split())
        assert not words & {"ceiling", "pendant", "hanging", "chandelier"}, r.id
