"""`read_ply` is exact for valid PLY files of any layout, and names the file and the problem otherwise."""

import numpy as np
import pytest

from morphosim_gym.scene import SceneFileError, export_ply, read_ply
from tests.conftest import make_tiny_scene

_PROPS = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
          "rot_0", "rot_1", "rot_2", "rot_3"]


def _columns(n: int = 12, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    cols = rng.normal(size=(n, len(_PROPS))).astype(np.float32)
    cols[:, 7:10] = rng.uniform(-4, -2, (n, 3))
    return cols


def _write(path, cols, fmt="binary_little_endian", before=(), after=(), vertex_type="float"):
    """A PLY with `before` / `after` elements as (header lines, ascii rows, binary bytes)."""
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt, "")
    head = ["ply", f"format {fmt} 1.0", "comment test"]
    for h, _, _ in before:
        head += h
    head += [f"element vertex {len(cols)}"] + [f"property {vertex_type} {p}" for p in _PROPS]
    for h, _, _ in after:
        head += h
    head.append("end_header")
    out = ("\n".join(head) + "\n").encode()
    code = {"float": "f4", "double": "f8"}[vertex_type]
    if order:
        out += b"".join(b for _, _, b in before)
        out += cols.astype(order + code).tobytes()
        out += b"".join(b for _, _, b in after)
    else:
        rows = [r for _, rs, _ in before for r in rs]
        rows += [" ".join(repr(float(v)) for v in row) for row in cols.astype(code)]
        rows += [r for _, rs, _ in after for r in rs]
        out += ("\n".join(rows) + "\n").encode()
    path.write_bytes(out)
    return path


def _face_element(order: str):
    """Two faces with a list property (uchar count, int indices) and a scalar flag."""
    faces = [[0, 1, 2], [2, 3, 4, 5]]
    header = ["element face 2", "property list uchar int vertex_indices", "property uchar flag"]
    rows = [f"{len(f)} " + " ".join(map(str, f)) + " 7" for f in faces]
    raw = b""
    if order:
        for f in faces:
            raw += np.array([len(f)], "u1").tobytes() + np.array(f, order + "i4").tobytes() + b"\x07"
    return header, rows, raw


def _camera_element(order: str):
    header = ["element camera 1", "property double fx", "property double fy"]
    return header, ["500.0 510.0"], np.array([500.0, 510.0], (order or "<") + "f8").tobytes()


def _expected(cols: np.ndarray) -> dict:
    c = cols.astype(np.float64)
    return {"means": c[:, 0:3], "colors": np.clip(c[:, 3:6] * 0.28209479177387814 + 0.5, 0, 1),
            "opacities": 1 / (1 + np.exp(-c[:, 6])), "scales": np.exp(c[:, 7:10])}


@pytest.mark.parametrize("fmt", ["binary_little_endian", "binary_big_endian", "ascii"])
@pytest.mark.parametrize("layout", ["plain", "camera_before", "faces_before", "faces_after"])
def test_valid_layouts_read_exactly(tmp_path, fmt, layout):
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt, "")
    cols = _columns()
    before = {"camera_before": [_camera_element(order)], "faces_before": [_face_element(order)]}.get(layout, [])
    after = [_face_element(order)] if layout == "faces_after" else []
    g = read_ply(_write(tmp_path / "v.ply", cols, fmt, before, after))
    exp = _expected(cols)
    for k, v in exp.items():
        np.testing.assert_allclose(getattr(g, k), v, rtol=1e-6, atol=1e-6, err_msg=f"{fmt} {layout} {k}")


def test_double_properties(tmp_path):
    cols = _columns()
    g = read_ply(_write(tmp_path / "d.ply", cols, vertex_type="double"))
    np.testing.assert_allclose(g.means, cols[:, :3].astype(np.float64), rtol=1e-6)


def test_exported_ply_roundtrips(tmp_path):
    s = make_tiny_scene(n_per_object=20)
    g = read_ply(export_ply(s, tmp_path / "e.ply"))
    np.testing.assert_allclose(g.means, s.at(0.0).means, atol=1e-6)


def test_missing_field_names_file_and_field(tmp_path):
    path = _write(tmp_path / "m.ply", _columns())
    path.write_bytes(path.read_bytes().replace(b"property float opacity\n", b"property float opacitx\n"))
    with pytest.raises(SceneFileError, match=r"m\.ply: .*\['opacity'\]"):
        read_ply(path)


@pytest.mark.parametrize("damage, problem", [
    (lambda raw: raw[:-10], "truncated"),
    (lambda raw: raw.replace(b"format binary_little_endian", b"format binary_middle_endian"), "malformed header"),
    (lambda raw: raw.replace(b"property float x\n", b"property quad x\n"), "unknown property type"),
    (lambda raw: raw.replace(b"element vertex 12", b"element vertex 99999999999"), "truncated"),
    (lambda raw: raw.replace(b"end_header", b"end_headex"), "end_header"),
    (lambda raw: raw.replace(b"property float y\n", b"property float x\n"), "twice"),
    (lambda raw: b"hello", "not a PLY file"),
])
def test_damaged_files_are_clean_errors(tmp_path, damage, problem):
    path = _write(tmp_path / "good.ply", _columns())
    bad = tmp_path / "bad.ply"
    bad.write_bytes(damage(path.read_bytes()))
    with pytest.raises(SceneFileError, match=problem) as info:
        read_ply(bad)
    assert str(info.value).startswith(str(bad))


def test_truncated_element_before_vertex(tmp_path):
    cols = _columns(n=2)
    header, rows, raw = _face_element("<")
    header = ["element face 1000000"] + header[1:]
    path = _write(tmp_path / "t.ply", cols, before=[(header, rows, raw)])
    with pytest.raises(SceneFileError, match="truncated in element 'face'"):
        read_ply(path)
