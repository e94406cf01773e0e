"""The converted-asset cache: hits, content keys, atomic writes, damaged entries."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.assets import AssetWarning, ConversionCache, ConversionParams, FolderSource, api, asset_gaussians
from morphosim_gym.assets.files import AssetFiles

from .conftest import write_quad


def _entries(root):
    return sorted(p for p in root.rglob("*") if p.is_file())


def test_second_call_is_a_hit_and_keys_follow_content(quad_dir, tmp_path, monkeypatch):
    cache = ConversionCache(tmp_path / "conv")
    record = FolderSource(quad_dir).records()[0]
    first = asset_gaussians(record, budget=300, cache=cache)
    (entry,) = _entries(tmp_path / "conv")
    assert entry.suffix == ".npz"

    def no_convert(*a, **k):
        raise AssertionError("a cached asset must not be converted again")

    monkeypatch.setitem(api._CONVERTERS, "mesh", no_convert)
    again = asset_gaussians(record, budget=300, cache=cache)
    assert np.array_equal(first.means, again.means) and np.array_equal(first.colors, again.colors)
    monkeypatch.undo()
    files = AssetFiles(record)
    key = api.conversion_key(record, ConversionParams(budget=300), files)
    assert key != api.conversion_key(record, ConversionParams(budget=301), files)
    write_quad(quad_dir, texture=(quad_dir / "quad.png").read_bytes() + b"\0")   # a texture's bytes change
    assert key != api.conversion_key(record, ConversionParams(budget=300), AssetFiles(record))


def test_damaged_entry_is_rebuilt_with_a_warning(quad_dir, tmp_path):
    cache = ConversionCache(tmp_path / "conv")
    record = FolderSource(quad_dir).records()[0]
    good = asset_gaussians(record, budget=300, cache=cache)
    (entry,) = _entries(tmp_path / "conv")
    for damage in (lambda b: b[: len(b) // 2], lambda b: b[:-200] + bytes(200)):
        entry.write_bytes(damage(entry.read_bytes()))
        with pytest.warns(AssetWarning, match="Damaged asset cache entry"):
            rebuilt = asset_gaussians(record, budget=300, cache=cache)
        assert np.array_equal(rebuilt.means, good.means)
        assert cache.get(entry.stem) is not None


def test_failed_write_leaves_no_entry(tmp_path, monkeypatch):
    cache = ConversionCache(tmp_path / "conv")
    g = asset_gaussians(FolderSource(write_quad(tmp_path / "q").parent).records()[0], budget=50, cache=False)

    def fail(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", fail)
    with pytest.raises(OSError, match="disk full"):
        cache.put("ab" * 32, g)
    assert _entries(tmp_path / "conv") == []                    # neither the entry nor its temporary file
    assert cache.get("ab" * 32) is None


def test_failed_conversion_writes_nothing(tmp_path):
    folder = tmp_path / "bad"
    folder.mkdir()
    (folder / "bad.obj").write_text("v 0 0 0\nf 1 1 1\n")      # one degenerate triangle
    cache = ConversionCache(tmp_path / "conv")
    with pytest.raises(ValueError, match="bad.obj"):
        asset_gaussians(FolderSource(folder).records()[0], budget=50, cache=cache)
    assert _entries(tmp_path / "conv") == []


def test_unwritable_cache_only_costs_the_caching(quad_dir, tmp_path):
    (tmp_path / "file").write_text("a file where the cache folder should be")
    cache = ConversionCache(tmp_path / "file" / "conv")
    with pytest.warns(AssetWarning, match="Could not cache"):
        g = asset_gaussians(FolderSource(quad_dir).records()[0], budget=50, cache=cache)
    assert len(g) == 50


def test_truncated_entry_is_rebuilt_with_a_damaged_cache_entry_warning(quad_dir, tmp_path):
    from morphosim_gym.assets.cache import DamagedAssetCacheWarning
    from morphosim_gym.scene.diskcache import DamagedCacheEntryWarning

    cache = ConversionCache(tmp_path / "conv")
    record = FolderSource(quad_dir).records()[0]
    good = asset_gaussians(record, budget=300, cache=cache)
    (entry,) = _entries(tmp_path / "conv")
    entry.write_bytes(entry.read_bytes()[:100])                        # a writer killed mid-file
    with pytest.warns(DamagedCacheEntryWarning, match=str(entry.name)) as caught:
        rebuilt = asset_gaussians(record, budget=300, cache=cache)
    assert any(isinstance(w.message, DamagedAssetCacheWarning) for w in caught)
    assert np.array_equal(rebuilt.means, good.means) and np.array_equal(rebuilt.colors, good.colors)
    assert _entries(tmp_path / "conv") == [entry] and cache.get(entry.stem) is not None
