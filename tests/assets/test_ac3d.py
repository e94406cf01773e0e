"""The AC3D reader on small files written here: nested transforms, textures (modulated by the
material, alpha as opacity), dropped line surfaces, CRLF, skipped objects, and broken input."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from morphosim_gym.assets import AssetError, AssetRecord, AssetWarning, ConversionCache, asset_gaussians
from morphosim_gym.assets.ac3d import find_texture, read_ac3d, texture_names
from morphosim_gym.assets.files import AssetFiles
from morphosim_gym.assets.mesh import load_mesh_parts

MATERIALS = ('MATERIAL "white" rgb 1 1 1  amb 0.2 0.2 0.2  emis 0 0 0  spec 0 0 0  shi 10  trans 0\n'
             'MATERIAL "half" rgb 0.5 1 0.25  amb 0.2 0.2 0.2  emis 0 0 0  spec 0 0 0  shi 10  trans 0.25\n')

# a group turned a quarter about z (row-major: x -> y, y -> -x) and moved, holding a poly moved
# along its own x: p_file = R_group @ (p + loc_poly) + loc_group
NESTED = MATERIALS + """OBJECT world
kids 1
OBJECT group
name "turned"
rot 0 -1 0 1 0 0 0 0 1
loc 10 0 0
kids 1
OBJECT poly
name "square"
loc 1 0 0
numvert 4
0 0 0
1 0 0
1 1 0
0 1 0
numsurf 2
SURF 0x20
mat 0
refs 4
0 0 0
1 1 0
2 1 1
3 0 1
SURF 0x01
mat 0
refs 3
0 0 0
1 1 0
2 1 1
kids 0
"""


def _ac(body: str) -> str:
    return "AC3Db\n" + body


def _square_corners(model) -> np.ndarray:
    [part] = model.parts
    return np.unique(part.triangles.reshape(-1, 3).round(9), axis=0)


def test_nested_transforms_place_a_kid_by_its_parents():
    model = read_ac3d(_ac(NESTED), "nested.ac")
    # local square (0..1, 0..1, 0) + (1, 0, 0), turned x -> y, then + (10, 0, 0)
    expected = np.array([[9, 1, 0], [9, 2, 0], [10, 1, 0], [10, 2, 0]], dtype=float)
    assert np.allclose(_square_corners(model), expected)
    assert model.objects == 3 and model.n_triangles == 2


def test_a_line_surface_is_dropped_and_a_polygon_fanned():
    """The closed line (SURF 0x01) has three refs: drawn as a polygon it would add a triangle."""
    model = read_ac3d(_ac(NESTED), "nested.ac")
    assert model.lines_dropped == 1
    [part] = model.parts
    assert part.triangles.shape == (2, 3, 3) and part.uvs is None     # no texture: no UVs


@pytest.mark.parametrize("end", ["\r\n", "\r"])
def test_crlf_and_cr_read_as_lf(end):
    lf = read_ac3d(_ac(NESTED), "a.ac")
    other = read_ac3d(_ac(NESTED).replace("\n", end).encode("latin-1"), "a.ac")
    assert np.array_equal(lf.parts[0].triangles, other.parts[0].triangles) and other.lines_dropped == 1


def test_skipped_objects_and_their_kids_give_no_geometry():
    model = read_ac3d(_ac(NESTED), "a.ac", skip=("^TURNED$",))     # case-insensitive
    assert model.parts == [] and model.skipped == ["turned"] and model.bounds() is None


def test_data_blocks_spanning_lines_and_missing_trailing_kids_are_read():
    body = NESTED.replace('name "square"\n', 'name "square"\ndata 11\nline one\nxy\n')
    body = body.replace("OBJECT world\nkids 1", "OBJECT world\nkids 3")        # promises 2 kids it lacks
    model = read_ac3d(_ac(body), "a.ac")
    assert model.n_triangles == 2 and model.missing_kids == 2


def test_triangle_strips_are_unrolled_with_alternating_winding():
    body = NESTED.replace("SURF 0x20\nmat 0\nrefs 4\n0 0 0\n1 1 0\n2 1 1\n3 0 1",
                          "SURF 0x24\nmat 0\nrefs 4\n0 0 0\n1 1 0\n3 0 1\n2 1 1")
    [part] = read_ac3d(_ac(body), "a.ac").parts
    normals = np.cross(part.triangles[:, 1] - part.triangles[:, 0], part.triangles[:, 2] - part.triangles[:, 0])
    assert len(part.triangles) == 2 and np.allclose(normals[0] / np.linalg.norm(normals[0]),
                                                    normals[1] / np.linalg.norm(normals[1]))


@pytest.mark.parametrize("old, new, message", [
    ("0 0 0\n1 0 0\n1 1 0", "0 0 0\n1 x 0\n1 1 0", r"broken\.ac, line 16: expected 3 numbers"),
    ("refs 4\n0 0 0\n1 1 0\n2 1 1\n3 0 1", "refs 4\n0 0 0\n1 1 0\n2 1 1\n7 0 1", "line 20: SURF refers to vertex 7"),
    ("SURF 0x20", "SURF 0xZZ", "line 20: expected SURF flags"),
    ("numsurf 2", "numsurf two", "line 19: expected a count after 'numsurf'"),
    ("kids 0\n", "", "line 32: the file ends where 'kids' of the OBJECT square"),
    ("OBJECT world", "OBJECT", "line 4: expected OBJECT <type>"),
])
def test_broken_files_name_the_file_and_line(old, new, message):
    text = _ac(NESTED)
    assert old in text
    with pytest.raises(ValueError, match=message):
        read_ac3d(text.replace(old, new, 1), "broken.ac")


def test_not_an_ac3d_file_is_refused():
    with pytest.raises(ValueError, match=r"x\.ac, line 1: expected an AC3D header"):
        read_ac3d(b"# an OBJ\nv 0 0 0\n", "x.ac")


# ----------------------------------------------------------------- textures, through the asset layer
TEXTURED = MATERIALS + """OBJECT world
kids 1
OBJECT poly
name "quad"
texture "Textures/quad.png"
texrep 2 1
texoff 0 0
numvert 4
0 0 0
1 0 0
1 1 0
0 1 0
numsurf 1
SURF 0x20
mat 1
refs 4
0 0 0
1 0.5 0
2 0.5 1
3 0 1
kids 0
"""
LEFT, RIGHT = (200, 100, 40), (40, 200, 200)


def _write_textured(folder, alpha_right: int = 255, texture: bool = True):
    """quad.ac whose square is textured by Textures/quad.png: left 4 texel columns LEFT, right 4 RIGHT.
    texrep 2 with u in 0..0.5 makes u run 0..1 over the square: its left half LEFT, right half RIGHT."""
    (folder / "Textures").mkdir(parents=True, exist_ok=True)
    rgba = np.zeros((2, 8, 4), dtype=np.uint8)
    rgba[:, :4] = (*LEFT, 255)
    rgba[:, 4:] = (*RIGHT, alpha_right)
    if texture:
        Image.fromarray(rgba).save(folder / "Textures" / "quad.png")
    path = folder / "quad.ac"
    path.write_text(_ac(TEXTURED))
    return path


def _record(path, **kw) -> AssetRecord:
    return AssetRecord(id="test/quad", name="quad", category="object", source="test", licence="test", kind="mesh",
                       path=str(path), up_axis="z", **kw)


def test_texture_lookup_and_names(tmp_path):
    path = _write_textured(tmp_path)
    assert texture_names(path.read_bytes()) == ["Textures/quad.png"]
    assert find_texture(tmp_path, "Textures/quad.png") == tmp_path / "Textures" / "quad.png"
    assert find_texture(tmp_path, "QUAD.PNG") == tmp_path / "Textures" / "quad.png"     # base name, any case
    assert find_texture(tmp_path, "other.png") is None


def test_a_texture_is_modulated_by_its_material_and_tiled_by_texrep(tmp_path):
    path = _write_textured(tmp_path)
    [part] = read_ac3d(path.read_bytes(), str(path)).parts
    assert np.allclose(part.uvs[:, :, 0].max(), 1.0)              # texrep 2 over u = 0..0.5
    g = asset_gaussians(_record(path), budget=2000, cache=False)
    x = g.means[:, 0]                                             # object frame: the square centred on x
    left, right = (x > -0.4) & (x < -0.1), (x > 0.1) & (x < 0.4)
    material = np.array([0.5, 1.0, 0.25])
    assert np.allclose(g.colors[left].mean(0), np.array(LEFT) / 255 * material, atol=0.03)
    assert np.allclose(g.colors[right].mean(0), np.array(RIGHT) / 255 * material, atol=0.03)
    assert np.allclose(g.opacities.max(), 0.75 * 0.95, atol=1e-6)     # trans 0.25 of material "half"


def test_texture_alpha_becomes_opacity(tmp_path):
    path = _write_textured(tmp_path, alpha_right=0)
    g = asset_gaussians(_record(path), budget=2000, cache=False)
    x = g.means[:, 0]
    left, right = (x > -0.4) & (x < -0.1), (x > 0.1) & (x < 0.4)
    assert g.opacities[left].min() > 0.7 and g.opacities[right].max() < 0.06   # clear texels: the 0.05 floor


def test_a_missing_texture_warns_and_uses_the_material_colour(tmp_path):
    path = _write_textured(tmp_path, texture=False)
    with pytest.warns(AssetWarning, match=r"Textures/quad\.png.*quad\.ac"):
        parts = load_mesh_parts(_record(path))
    assert parts[0].texture is None and np.allclose(parts[0].color, (0.5, 1.0, 0.25))


def test_texture_bytes_and_skipped_objects_are_part_of_the_cache_key(tmp_path):
    from morphosim_gym.assets import conversion_key
    from morphosim_gym.assets.convert import ConversionParams

    path = _write_textured(tmp_path)
    params = ConversionParams(budget=10)
    record = _record(path)
    before = conversion_key(record, params, AssetFiles(record))
    _write_textured(tmp_path, alpha_right=10)
    assert conversion_key(record, params, AssetFiles(record)) != before
    skipping = _record(path, extra={"skip": ["^quad$"]})
    assert conversion_key(skipping, params, AssetFiles(skipping)) != conversion_key(record, params, AssetFiles(record))


def test_broken_file_at_conversion_is_an_asset_error_naming_it(tmp_path):
    path = tmp_path / "broken.ac"
    path.write_text(_ac(NESTED).replace("1 1 0\n0 1 0", "1 1\n0 1 0", 1))
    with pytest.raises(AssetError, match=r"broken\.ac, line 17: expected 3 numbers"):
        asset_gaussians(_record(path), budget=10, cache=ConversionCache(tmp_path / "conv"))


def test_a_folder_of_ac3d_files_is_a_source(tmp_path):
    from morphosim_gym.assets import FolderSource

    _write_textured(tmp_path / "models")
    [rec] = FolderSource(tmp_path / "models").records()
    assert rec.path.endswith("quad.ac") and len(asset_gaussians(rec, budget=50, cache=False)) == 50
