"""3DGS `.ply` files: round trip with the scene layer's writer, bad files, splats as assets and settings."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.assets import AssetError, FolderSource, asset_gaussians, read_splat_ply, splat_setting
from morphosim_gym.assets.splat_ply import REQUIRED_FIELDS
from morphosim_gym.scene import Gaussians
from morphosim_gym.scene.io import export_ply


def _gaussians(n=50, seed=0):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return Gaussians(means=rng.uniform(-1, 1, (n, 3)), quats=q, scales=rng.uniform(0.01, 0.1, (n, 3)),
                     opacities=rng.uniform(0.1, 0.9, n), colors=rng.uniform(0.05, 0.95, (n, 3)))


@pytest.mark.parametrize("sh_rest", [False, True])
def test_round_trip(tmp_path, sh_rest):
    g = _gaussians()
    path = export_ply(g, tmp_path / "s.ply", sh_rest=sh_rest)
    back = read_splat_ply(path)
    for name in ("means", "scales", "opacities", "colors"):
        np.testing.assert_allclose(getattr(back, name), getattr(g, name), rtol=1e-5, atol=1e-6)
    dots = np.abs(np.sum(back.quats * g.quats, axis=1))     # the same rotation up to sign
    np.testing.assert_allclose(dots, 1.0, atol=1e-6)


def test_ascii_file(tmp_path):
    header = "ply\nformat ascii 1.0\nelement vertex 1\n" + "".join(f"property float {f}\n" for f in REQUIRED_FIELDS) + \
        "end_header\n"
    (tmp_path / "a.ply").write_text(header + "1 2 3 0 0 0 0 -2 -2 -2 1 0 0 0\n")
    g = read_splat_ply(tmp_path / "a.ply")
    np.testing.assert_allclose(g.means, [[1, 2, 3]])
    np.testing.assert_allclose(g.colors, [[0.5, 0.5, 0.5]])
    np.testing.assert_allclose(g.opacities, [0.5])
    np.testing.assert_allclose(g.scales, np.exp(-2) * np.ones((1, 3)), rtol=1e-6)


def test_missing_field_and_truncated_body_name_the_file(tmp_path):
    path = export_ply(_gaussians(), tmp_path / "s.ply", sh_rest=False)
    data = path.read_bytes()
    (tmp_path / "noop.ply").write_bytes(data.replace(b"property float opacity\n", b"property float opacitx\n"))
    with pytest.raises(AssetError, match=r"noop\.ply.*'opacity'"):
        read_splat_ply(tmp_path / "noop.ply")
    (tmp_path / "short.ply").write_bytes(data[:-40])
    with pytest.raises(AssetError, match=r"short\.ply is truncated"):
        read_splat_ply(tmp_path / "short.ply")
    (tmp_path / "text.ply").write_bytes(b"hello")
    with pytest.raises(AssetError, match="text.ply"):
        read_splat_ply(tmp_path / "text.ply")


def test_splat_as_asset_and_setting(tmp_path):
    g = _gaussians(200)
    folder = tmp_path / "splats"
    folder.mkdir()
    export_ply(g, folder / "blob.ply")
    (record,) = FolderSource(folder, up_axis="z").records()
    assert record.kind == "splat"
    obj = asset_gaussians(record, budget=120, size_m=1.0, cache=False)
    assert len(obj) == 120
    ext = np.ptp(obj.means, axis=0)
    assert abs(ext.max() - 1.0) < 1e-5 and abs(obj.means[:, 2].min()) < 1e-6
    setting = splat_setting(folder / "blob.ply", up_axis="y")
    assert len(setting) == 200
    np.testing.assert_allclose(setting.means, g.means[:, [0, 2, 1]] * [1, -1, 1], atol=1e-6)   # y-up -> z-up
