"""Scene and clip files round-trip bit-exactly; bad files give clear errors; .ply export."""

import numpy as np
import pytest

from morphosim_gym.scene import (FeatureDecoder, GeneratedClip, SceneFileError, export_ply, load_clip, load_scene,
                                 read_ply, save_clip, save_scene)
from tests.conftest import make_tiny_scene


def _assert_same_scene(a, b):
    assert a.arrays().keys() == b.arrays().keys()
    for k, v in a.arrays().items():
        w = b.arrays()[k]
        assert v.dtype == w.dtype and v.shape == w.shape and v.tobytes() == w.tobytes(), k
    assert a.metadata() == b.metadata()
    assert a.content_hash() == b.content_hash()


def test_scene_roundtrip_bit_exact_with_history(tmp_path):
    s = make_tiny_scene(features=8)
    dec = FeatureDecoder("semantic", [np.random.default_rng(0).normal(size=(8, 16)), np.ones((16, 4))],
                         [np.zeros(16), np.zeros(4)], normalize=True)
    s = s.derive(decoders={"semantic": dec})
    colors = s.gaussians.colors.copy()
    colors[:10] = 0.25
    edited = s.derive("make it grey", gaussians=s.gaussians.replace(colors=colors))
    path = save_scene(edited, tmp_path / "scene.msim")
    back = load_scene(path)
    _assert_same_scene(edited, back)
    _assert_same_scene(edited.undo(), back.undo())
    np.testing.assert_array_equal(back.at(1.3).means, edited.at(1.3).means)
    np.testing.assert_array_equal(back.decoders["semantic"](back.gaussians.features),
                                  edited.decoders["semantic"](edited.gaussians.features))


def test_identical_arrays_stored_once(tmp_path):
    s = make_tiny_scene()
    one = save_scene(s, tmp_path / "a.msim").stat().st_size
    twice = save_scene(s.derive("noop"), tmp_path / "b.msim").stat().st_size
    assert twice < one * 1.1


def test_truncated_and_corrupted_files(tmp_path):
    path = save_scene(make_tiny_scene(), tmp_path / "s.msim")
    raw = path.read_bytes()
    (tmp_path / "trunc.msim").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(SceneFileError, match="truncated"):
        load_scene(tmp_path / "trunc.msim")
    flipped = bytearray(raw)
    flipped[-100] ^= 0xFF
    (tmp_path / "bad.msim").write_bytes(bytes(flipped))
    with pytest.raises(SceneFileError, match="corrupted"):
        load_scene(tmp_path / "bad.msim")
    (tmp_path / "junk.msim").write_bytes(b"hello world" * 10)
    with pytest.raises(SceneFileError, match="not a MorphoSim file"):
        load_scene(tmp_path / "junk.msim")
    with pytest.raises(SceneFileError, match="no such file"):
        load_scene(tmp_path / "missing.msim")
    with pytest.raises(SceneFileError, match="expected a 'clip'"):
        load_clip(path)
    assert issubclass(SceneFileError, ValueError)


def test_newer_version_is_refused(tmp_path):
    import struct

    path = save_scene(make_tiny_scene(), tmp_path / "s.msim")
    raw = bytearray(path.read_bytes())
    struct.pack_into("<I", raw, 12, 99)
    path.write_bytes(bytes(raw))
    with pytest.raises(SceneFileError, match="version 99"):
        load_scene(path)


def test_clip_roundtrip(tmp_path):
    s = make_tiny_scene()
    t = 3
    rng = np.random.default_rng(0)
    clip = GeneratedClip(frames=rng.integers(0, 255, (t, 64, 64, 3), dtype=np.uint8), cameras=[s.camera] * t,
                         fps=4.0, depth=rng.uniform(1, 5, (t, 64, 64)).astype(np.float32),
                         masks=rng.integers(-1, 3, (t, 64, 64)).astype(np.int32), labels={0: "ground", 1: "ball", 2: "cube"},
                         tracks=rng.uniform(0, 64, (5, t, 2)).astype(np.float32), prompt="p", ground_truth=s,
                         info={"seed": 3})
    back = load_clip(save_clip(clip, tmp_path / "c.mclip"))
    assert back.content_hash() == clip.content_hash()
    assert back.labels == clip.labels and back.info == {"seed": 3} and back.prompt == "p"
    _assert_same_scene(back.ground_truth, s)


def test_clip_validation_names_problem():
    s = make_tiny_scene()
    frames = np.zeros((2, 64, 64, 3), np.uint8)
    with pytest.raises(ValueError, match="cameras"):
        GeneratedClip(frames=frames, cameras=[s.camera], fps=8)
    with pytest.raises(ValueError, match="finite depth"):
        GeneratedClip(frames=frames, cameras=[s.camera] * 2, fps=8, depth=np.full((2, 64, 64), np.nan))
    with pytest.raises(ValueError, match="label"):
        GeneratedClip(frames=frames, cameras=[s.camera] * 2, fps=8, masks=np.ones((2, 64, 64), np.int32))
    with pytest.raises(ValueError, match="at least one frame"):
        GeneratedClip(frames=np.zeros((0, 64, 64, 3), np.uint8), cameras=[], fps=8)


def test_ply_export_layout_and_roundtrip(tmp_path):
    s = make_tiny_scene()
    path = export_ply(s, tmp_path / "f.ply", t=1.0)
    header = path.read_bytes().split(b"end_header\n")[0].decode()
    for prop in ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "f_rest_44", "opacity", "scale_0", "scale_2", "rot_0",
                 "rot_3"]:
        assert f"property float {prop}\n" in header
    g = read_ply(path)
    ref = s.at(1.0)
    np.testing.assert_allclose(g.means, ref.means, atol=1e-6)
    np.testing.assert_allclose(g.colors, ref.colors, atol=1e-5)
    np.testing.assert_allclose(g.opacities, ref.opacities, atol=1e-5)
    np.testing.assert_allclose(g.scales, ref.scales, rtol=1e-5)
    q = ref.quats / np.linalg.norm(ref.quats, axis=1, keepdims=True)
    np.testing.assert_allclose(g.quats, q, atol=1e-6)
    raw = path.read_bytes()
    (tmp_path / "t.ply").write_bytes(raw[:-50])
    with pytest.raises(SceneFileError, match="truncated"):
        read_ply(tmp_path / "t.ply")
