"""Mesh -> Gaussians: colours at known UVs, normals, z-up, size, determinism, bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from morphosim_gym.assets import AssetError, AssetWarning, ConversionParams, FolderSource, asset_gaussians
from morphosim_gym.assets.texture import sample_texture
from morphosim_gym.scene.rotations import quat_rotate

from .conftest import TEXELS, WALL_RGB, write_quad


def _quad_record(folder):
    (record,) = FolderSource(folder).records()
    return record


def _convert(folder, **kw):
    kw.setdefault("budget", 4000)
    return asset_gaussians(_quad_record(folder), cache=False, **kw)


def test_texture_lookup_at_texel_centres():
    tex = TEXELS.astype(np.float32) / 255
    uv = np.array([[0.25, 0.75], [0.75, 0.75], [0.25, 0.25], [0.75, 0.25], [1.25, 0.25]])
    got = sample_texture(tex, uv)
    np.testing.assert_allclose(got, [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [0, 0, 1]], atol=1e-6)
    mid = sample_texture(tex, np.array([[0.5, 0.25]]))[0]          # half-way between blue and white
    np.testing.assert_allclose(mid, [0.5, 0.5, 1.0], atol=1e-6)


def test_quad_is_z_up_sized_and_based(quad_dir):
    g = _convert(quad_dir)
    assert len(g) == 4000
    lo, hi = g.means.min(axis=0), g.means.max(axis=0)
    np.testing.assert_allclose(hi - lo, [2, 1, 1], atol=0.02)        # y-up file: its height is z here
    np.testing.assert_allclose([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]], [0, 0, 0], atol=0.02)
    assert lo[2] >= -1e-6


def test_normals_colours_and_flatness(quad_dir):
    g = _convert(quad_dir)
    normals = quat_rotate(g.quats, np.tile([0.0, 0.0, 1.0], (len(g), 1)))
    floor = g.means[:, 2] < 1e-6
    wall = ~floor
    assert 1800 < floor.sum() < 2200                                  # areas 2 and 2: the budget splits by area
    np.testing.assert_allclose(normals[floor], np.tile([0, 0, 1], (floor.sum(), 1)), atol=1e-5)
    np.testing.assert_allclose(normals[wall], np.tile([0, -1, 0], (wall.sum(), 1)), atol=1e-5)  # front faces -y
    np.testing.assert_allclose(g.colors[wall], np.tile(WALL_RGB, (wall.sum(), 1)), atol=1e-6)
    # floor: u = (x + 1) / 2, v = y + 0.5; the quadrant centres are pure texel colours
    u, v = (g.means[:, 0] + 1) / 2, g.means[:, 1] + 0.5
    for (cu, cv), rgb in {(0.25, 0.75): (1, 0, 0), (0.75, 0.75): (0, 1, 0), (0.25, 0.25): (0, 0, 1),
                          (0.75, 0.25): (1, 1, 1)}.items():
        near = floor & (np.abs(u - cu) < 0.04) & (np.abs(v - cv) < 0.04)
        assert near.sum() >= 3
        np.testing.assert_allclose(g.colors[near].mean(axis=0), rgb, atol=0.2)
    thin, wide = g.scales[:, 2], g.scales[:, 0]
    assert np.all(thin < 0.2 * wide) and np.allclose(g.scales[:, 0], g.scales[:, 1])
    assert np.all((g.opacities > 0) & (g.opacities <= 1))


def test_size_and_seed(quad_dir):
    g = _convert(quad_dir, size_m=4.0)
    np.testing.assert_allclose(np.ptp(g.means, axis=0), [4, 2, 2], atol=0.05)
    g = _convert(quad_dir, size_m=(1.0, 1.0, 0.5))
    np.testing.assert_allclose(np.ptp(g.means, axis=0), [1, 1, 0.5], atol=0.02)
    a, b, c = _convert(quad_dir, seed=3), _convert(quad_dir, seed=3), _convert(quad_dir, seed=4)
    assert np.array_equal(a.means, b.means) and np.array_equal(a.colors, b.colors)
    assert not np.array_equal(a.means, c.means)
    with pytest.raises(ValueError, match="budget"):
        ConversionParams(budget=0)


def test_missing_and_unreadable_texture_fall_back_to_material_colour(tmp_path):
    for case, texture in (("missing", None), ("broken", b"this is not a png")):
        folder = tmp_path / case
        write_quad(folder, texture=texture if texture else b"")
        if case == "missing":
            (folder / "quad.png").unlink()
        with pytest.warns(AssetWarning, match="quad.png"):
            g = _convert(folder)
        floor = g.means[:, 2] < 1e-6
        np.testing.assert_allclose(g.colors[floor], np.full((floor.sum(), 3), 0.8), atol=1e-6)


def test_broken_missing_and_oversized_files(tmp_path):
    folder = tmp_path / "bad"
    folder.mkdir()
    (folder / "empty.obj").write_text("# no geometry\n")
    (folder / "junk.glb").write_bytes(b"\x00garbage" * 10)
    records = {r.name: r for r in FolderSource(folder).records()}
    for name in ("empty", "junk"):
        with pytest.raises(AssetError, match=name):
            asset_gaussians(records[name], budget=100, cache=False)
    (folder / "empty.obj").unlink()
    with pytest.raises(AssetError, match="Missing asset file.*empty.obj"):
        asset_gaussians(records["empty"], budget=100, cache=False)
    quad = write_quad(tmp_path / "big")
    with pytest.raises(AssetError, match="limit"):
        asset_gaussians(_quad_record(quad.parent), budget=100, cache=False, max_bytes=10)


def test_huge_mesh_is_bounded_by_the_budget(tmp_path):
    n = 120                                    # a 120x120 grid: 28,800 triangles for 500 Gaussians
    xs = np.linspace(0, 1, n + 1)
    verts = [f"v {x} 0 {z}" for z in xs for x in xs]
    faces = []
    for i in range(n):
        for j in range(n):
            a = i * (n + 1) + j + 1
            faces += [f"f {a} {a + n + 1} {a + 1}", f"f {a + 1} {a + n + 1} {a + n + 2}"]
    folder = tmp_path / "grid"
    folder.mkdir()
    (folder / "grid.obj").write_text("\n".join(verts + faces) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", AssetWarning)
        g = asset_gaussians(FolderSource(folder).records()[0], budget=500, cache=False)
    assert len(g) == 500
    np.testing.assert_allclose(np.ptp(g.means, axis=0), [1, 1, 0], atol=0.01)


@pytest.mark.parametrize("suffix", ["glb", "ply"])
def test_glb_and_ply_meshes_keep_their_colours(tmp_path, suffix):
    import trimesh

    box = trimesh.creation.box(extents=(0.4, 0.2, 0.1))        # in a y-up file: 0.2 tall, 0.1 deep
    box.visual.vertex_colors = np.tile([255, 0, 0, 255], (len(box.vertices), 1))
    folder = tmp_path / suffix
    folder.mkdir()
    box.export(folder / f"box.{suffix}")
    (record,) = FolderSource(folder).records()
    assert record.kind == "mesh"
    g = asset_gaussians(record, budget=500, cache=False)
    np.testing.assert_allclose(np.ptp(g.means, axis=0), [0.4, 0.1, 0.2], atol=0.01)
    np.testing.assert_allclose(g.colors, np.tile([1, 0, 0], (500, 1)), atol=0.01)
