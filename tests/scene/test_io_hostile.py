"""Hostile and damaged scene / clip files: bounded memory, checksummed headers, one error type naming
the file, and a seeded fuzz of bit flips, truncations and duplicated runs (identical load or clean error)."""

import hashlib
import json
import struct
import tracemalloc

import numpy as np
import pytest

from morphosim_gym.cli import main
from morphosim_gym.scene import GeneratedClip, SceneFileError, load_clip, load_scene, save_clip, save_scene
from morphosim_gym.scene.container import FORMAT_VERSION, MAGIC
from tests.conftest import make_tiny_scene
from tests.scene.test_io import _assert_same_scene


def _pad(b: bytes) -> bytes:
    return b + b"\0" * ((-len(b)) % 64)


def _craft_v2(path, kind, metadata, blobs, arrays, data: bytes):
    """A version-2 file with valid checksums around whatever table it is given (as an attacker can)."""
    header = {"kind": kind, "metadata": metadata, "blobs": blobs, "arrays": arrays, "data_nbytes": len(data),
              "data_sha256": hashlib.sha256(data).hexdigest()}
    h = json.dumps(header).encode()
    prefix = MAGIC + struct.pack("<IQ", 2, len(h)) + h
    path.write_bytes(_pad(prefix + hashlib.sha256(prefix).digest()) + data)
    return path


def _craft_v1(path, kind, metadata, arrays: dict):
    """A file as format version 1 wrote it (no header checksum, one byte range per array, deduplicated)."""
    data, table, seen = bytearray(), [], {}
    for name, a in arrays.items():
        raw = np.ascontiguousarray(a).tobytes()
        if raw not in seen:
            data.extend(b"\0" * ((-len(data)) % 64))
            seen[raw] = len(data)
            data.extend(raw)
        table.append({"name": name, "dtype": a.dtype.str, "shape": list(a.shape), "offset": seen[raw],
                      "nbytes": len(raw)})
    header = {"kind": kind, "metadata": metadata, "arrays": table, "data_nbytes": len(data),
              "data_sha256": hashlib.sha256(bytes(data)).hexdigest()}
    h = json.dumps(header).encode()
    path.write_bytes(_pad(MAGIC + struct.pack("<IQ", 1, len(h)) + h) + bytes(data))
    return path


def _scene_v1(scene, path):
    chain = [scene]
    while chain[0].parent is not None:
        chain.insert(0, chain[0].parent)
    arrays = {f"{i}/{k}": v for i, s in enumerate(chain) for k, v in s.arrays().items()}
    return _craft_v1(path, "scene", {"scenes": [s.metadata() for s in chain]}, arrays)


def test_format_version_is_2():
    assert FORMAT_VERSION == 2


def test_version_1_files_still_load(tmp_path):
    s = make_tiny_scene(n_per_object=30)
    edited = s.derive("grey", gaussians=s.gaussians.replace(colors=np.full_like(s.gaussians.colors, 0.5)))
    back = load_scene(_scene_v1(edited, tmp_path / "old.msim"))
    _assert_same_scene(back, edited)
    _assert_same_scene(back.undo(), s)


def test_repeated_blob_table_is_loaded_once_not_per_entry(tmp_path):
    """200 table entries naming one 1 MB blob: the old reader copied it 200 times (200 MB)."""
    blob = np.zeros(1 << 20, np.uint8)
    for write in ("v1", "v2"):
        path = tmp_path / f"bomb_{write}.msim"
        if write == "v1":
            _craft_v1(path, "scene", {"scenes": []}, {f"x{i}": blob for i in range(200)})
        else:
            _craft_v2(path, "scene", {"scenes": []}, [{"offset": 0, "nbytes": blob.nbytes}],
                      [{"name": f"x{i}", "dtype": "|u1", "shape": [blob.nbytes], "blob": 0} for i in range(200)],
                      blob.tobytes())
        tracemalloc.start()
        with pytest.raises(SceneFileError, match=str(path.name)):
            load_scene(path)                                    # no scenes: a clean error, after the arrays
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < 8 * blob.nbytes, (write, peak)


def test_shared_arrays_are_read_only_views(tmp_path):
    s = make_tiny_scene(n_per_object=20)
    back = load_scene(save_scene(s.derive("noop"), tmp_path / "s.msim"))
    assert np.shares_memory(back.gaussians.means, back.undo().gaussians.means)
    with pytest.raises(ValueError, match="read-only"):
        back.gaussians.means[0, 0] = 1.0
    clip = load_clip(save_clip(_tiny_clip(), tmp_path / "c.mclip"))
    clip.frames[0, 0, 0] = 1                                   # an array stored once stays writable


@pytest.mark.parametrize("blobs, arrays, problem", [
    ([{"offset": 0, "nbytes": 64}, {"offset": 0, "nbytes": 64}], [], "listed twice"),
    ([{"offset": 0, "nbytes": 64}, {"offset": 32, "nbytes": 64}], [], "overlaps"),
    ([{"offset": 0, "nbytes": 1 << 40}], [], "past the data"),
    ([{"offset": 0, "nbytes": 128}], [{"name": "a", "dtype": "<f4", "shape": [1 << 20, 1 << 20], "blob": 0}],
     "for a blob of 128 bytes"),
    ([{"offset": 0, "nbytes": 128}], [{"name": "a", "dtype": "|O", "shape": [16], "blob": 0}], "dtype"),
    ([{"offset": 0, "nbytes": 128}], [{"name": "a", "dtype": "<f8", "shape": [-16], "blob": 0}], "shape"),
    ([{"offset": 0, "nbytes": 128}], [{"name": "a", "dtype": "<f8", "shape": [16], "blob": 7}], "names blob 7"),
    ([{"offset": 0, "nbytes": 64}, {"offset": 64, "nbytes": 64}],
     [{"name": "a", "dtype": "|u1", "shape": [64], "blob": 0}, {"name": "a", "dtype": "|u1", "shape": [64], "blob": 1}],
     "listed twice"),
    ([{"offset": "0", "nbytes": 64}], [], "blob 0 has offset"),
])
def test_crafted_tables_are_refused(tmp_path, blobs, arrays, problem):
    path = _craft_v2(tmp_path / "c.msim", "scene", {"scenes": []}, blobs, arrays, bytes(128))
    with pytest.raises(SceneFileError, match=problem) as info:
        load_scene(path)
    assert str(info.value).startswith(str(path))


def test_crafted_content_errors_name_the_file(tmp_path):
    s = make_tiny_scene(n_per_object=20)
    good = tmp_path / "g.msim"
    save_scene(s, good)
    meta = s.metadata()
    for i, bad in enumerate([{"scenes": [{**meta, "fps": "fast"}]}, {"scenes": [{**meta, "objects": 3}]},
                             {"scenes": [{**meta, "cameras": [[]]}]}, {"scenes": "x"}, {"scenes": [None]}]):
        path = _scene_v1(s, tmp_path / f"b{i}.msim")
        raw = path.read_bytes()
        hlen = struct.unpack_from("<Q", raw, 16)[0]
        header = json.loads(raw[24:24 + hlen])
        header["metadata"] = bad
        h = json.dumps(header).encode()
        data = raw[len(_pad(raw[:24 + hlen])):]
        path.write_bytes(_pad(MAGIC + struct.pack("<IQ", 1, len(h)) + h) + data)
        with pytest.raises(SceneFileError) as info:
            load_scene(path)
        assert str(info.value).startswith(str(path)), info.value


def test_renamed_header_key_is_a_clean_error(tmp_path):
    """A v1 header with a key renamed (no checksum to catch it): the old reader raised a raw KeyError."""
    path = _scene_v1(make_tiny_scene(n_per_object=20), tmp_path / "r.msim")
    raw = path.read_bytes().replace(b'"data_nbytes"', b'"data_nbytez"')
    path.write_bytes(raw)
    with pytest.raises(SceneFileError, match="truncated or padded"):
        load_scene(path)


def test_info_prints_the_error_without_traceback(tmp_path, capsys):
    path = _scene_v1(make_tiny_scene(n_per_object=20), tmp_path / "r.msim")
    path.write_bytes(path.read_bytes().replace(b'"arrays"', b'"arrayz"'))
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "Traceback" not in err
    clip = _tiny_clip()
    good = save_clip(clip, tmp_path / "c.mclip")
    assert main(["info", str(good)]) == 0
    assert '"kind": "clip"' in capsys.readouterr().out


# ---------------------------------------------------------------------- fuzz
def _tiny_clip() -> GeneratedClip:
    s = make_tiny_scene(n_per_object=8, frames=3)
    rng = np.random.default_rng(1)
    t = 3
    return GeneratedClip(frames=rng.integers(0, 255, (t, 16, 16, 3), dtype=np.uint8),
                         cameras=[s.camera.resized(16, 16)] * t,
                         fps=4.0, depth=rng.uniform(1, 5, (t, 16, 16)).astype(np.float32),
                         masks=rng.integers(-1, 3, (t, 16, 16)).astype(np.int32),
                         labels={0: "ground", 1: "ball", 2: "cube"}, prompt="a ball", ground_truth=s,
                         info={"seed": 3})


def _same_clip(a: GeneratedClip, b: GeneratedClip) -> bool:
    return (a.content_hash() == b.content_hash() and a.prompt == b.prompt and a.info == b.info
            and a.ground_truth.content_hash() == b.ground_truth.content_hash()
            and a.ground_truth.metadata() == b.ground_truth.metadata())


def _same_scene(a, b) -> bool:
    while a is not None and b is not None:
        if a.content_hash() != b.content_hash() or a.metadata() != b.metadata():
            return False
        a, b = a.parent, b.parent
    return a is None and b is None


def _mutations(raw: bytes, rng: np.random.Generator, header_end: int, count: int):
    """Bit flips (half of them inside the header, where a flip used to change a value silently),
    truncations, and a duplicated run of bytes inserted somewhere."""
    for i in range(count):
        kind = i % 4
        b = bytearray(raw)
        if kind in (0, 1):
            pos = int(rng.integers(0, header_end if kind == 0 else len(raw)))
            b[pos] ^= 1 << int(rng.integers(0, 8))
        elif kind == 2:
            b = b[: int(rng.integers(0, len(raw)))]
        else:
            start = int(rng.integers(0, len(raw)))
            n = int(rng.integers(1, 65))
            b[start:start] = raw[start:start + n]
        yield bytes(b)


@pytest.mark.parametrize("what", ["scene", "clip"])
def test_fuzz_damage_is_identical_or_clean_error(tmp_path, what):
    if what == "scene":
        s = make_tiny_scene(n_per_object=8, frames=3)
        obj = s.derive("grey", gaussians=s.gaussians.replace(colors=np.full_like(s.gaussians.colors, 0.5)))
        path, load, same = save_scene(obj, tmp_path / "x.msim"), load_scene, _same_scene
    else:
        obj = _tiny_clip()
        path, load, same = save_clip(obj, tmp_path / "x.mclip"), load_clip, _same_clip
    raw = path.read_bytes()
    header_end = 24 + struct.unpack_from("<Q", raw, 16)[0]
    rng = np.random.default_rng(22)
    damaged = tmp_path / f"d{path.suffix}"
    outcomes = {"identical": 0, "error": 0}
    for b in _mutations(raw, rng, header_end, 300):
        damaged.write_bytes(b)
        try:
            back = load(damaged)
        except SceneFileError as exc:
            assert str(exc).startswith(str(damaged)), exc
            outcomes["error"] += 1
            continue
        assert same(back, obj), "a damaged file loaded with changed content"
        outcomes["identical"] += 1
    assert outcomes["error"] > 250, outcomes
