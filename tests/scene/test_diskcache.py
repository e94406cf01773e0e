"""The clip / scene cache: damaged entries are discarded and rebuilt with a warning, temporaries of
killed writers are swept, and the key follows the generator's version."""

import os
import subprocess
import sys
import time
import warnings

import pytest

import morphosim_gym as ms
from morphosim_gym import pipeline
from morphosim_gym.generate.version import GENERATOR_VERSION
from morphosim_gym.scene import diskcache
from morphosim_gym.scene.atomic import STALE_TEMP_SECONDS, sweep_stale_temps
from morphosim_gym.scene.diskcache import DamagedCacheEntryWarning

PROMPT = "a red ball moves from left to right"
GEN = {"num_frames": 2, "width": 32, "height": 32}


def _sim(tmp_path, **kw):
    return ms.MorphoSim(cache=True, cache_dir=str(tmp_path), generation=dict(GEN), **kw)


def _only(tmp_path, kind):
    files = sorted((tmp_path / kind).glob("*.m*"))
    assert len(files) == 1, files
    return files[0]


def test_truncated_clip_entry_is_rebuilt_with_a_warning(tmp_path):
    sim = _sim(tmp_path)
    first = sim.generate_clip(PROMPT, seed=1)
    entry = _only(tmp_path, "clip")
    entry.write_bytes(entry.read_bytes()[:-100])
    with pytest.warns(DamagedCacheEntryWarning, match=entry.name):
        again = sim.generate_clip(PROMPT, seed=1)
    assert again.content_hash() == first.content_hash()
    with warnings.catch_warnings():
        warnings.simplefilter("error")                     # repaired: the next read is clean
        assert sim.generate_clip(PROMPT, seed=1).content_hash() == first.content_hash()


def test_scene_entry_with_a_renamed_header_key_is_rebuilt(tmp_path):
    sim = _sim(tmp_path, reconstruction="oracle")
    first = sim.generate(PROMPT, seed=2)
    entry = _only(tmp_path, "scene")
    entry.write_bytes(entry.read_bytes().replace(b'"data_nbytes"', b'"data_nbytez"'))
    with pytest.warns(DamagedCacheEntryWarning, match="checksum of the header"):
        assert sim.generate(PROMPT, seed=2).content_hash() == first.content_hash()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert sim.generate(PROMPT, seed=2).content_hash() == first.content_hash()


def test_cache_key_follows_the_generator_version(tmp_path, monkeypatch):
    sim = _sim(tmp_path)
    before = sim._cache_path("clip", PROMPT, 0)
    monkeypatch.setattr(pipeline, "GENERATOR_VERSION", GENERATOR_VERSION + 1)
    assert sim._cache_path("clip", PROMPT, 0) != before


_KILLED_WRITER = """
import os, signal, sys
import numpy as np
from morphosim_gym.scene import atomic
atomic.os.replace = lambda *a: os.kill(os.getpid(), signal.SIGKILL)   # die between write and rename
atomic.atomic_write(sys.argv[1], [np.zeros(1 << 20, np.uint8).tobytes()])
"""


def _age(path, seconds):
    t = time.time() - seconds
    os.utime(path, (t, t))


def test_temporaries_of_killed_writers_are_swept(tmp_path):
    target = tmp_path / "scene" / "x.msim"
    for _ in range(3):
        proc = subprocess.run([sys.executable, "-c", _KILLED_WRITER, str(target)], capture_output=True, check=False)
        assert proc.returncode == -9, proc.stderr
    left = sorted((tmp_path / "scene").glob(".x.msim.*.tmp"))
    assert len(left) == 3 and not target.exists()
    live = tmp_path / "scene" / f".y.msim.{left[0].name.split('.')[3]}.{os.getpid()}.abcd1234.tmp"
    live.write_bytes(b"being written")
    other = tmp_path / "scene" / ".keep"
    other.write_bytes(b"")
    for p in left + [live, other]:
        _age(p, 10)
    assert sorted(sweep_stale_temps(tmp_path / "scene")) == left     # dead writers only
    assert live.exists() and other.exists()
    _age(live, STALE_TEMP_SECONDS + 60)                              # a writer that never finishes
    assert sweep_stale_temps(tmp_path / "scene") == [live]


def test_cache_writes_sweep_their_directory(tmp_path, monkeypatch):
    monkeypatch.setattr(diskcache, "_last_sweep", {})
    (tmp_path / "clip").mkdir(parents=True)
    stale = tmp_path / "clip" / ".old.mclip.k3j2h1g0.tmp"               # a temp of the old naming
    stale.write_bytes(b"x" * 1000)
    _age(stale, STALE_TEMP_SECONDS + 60)
    _sim(tmp_path).generate_clip(PROMPT, seed=5)
    assert not stale.exists()


def test_damaged_reconstruction_entry_is_fitted_again(tmp_path, monkeypatch):
    from morphosim_gym.reconstruct import pipeline as rp
    from tests.conftest import make_tiny_scene

    fits = []
    monkeypatch.setattr(rp, "_fit_scene", lambda clip, cfg: fits.append(1) or make_tiny_scene(n_per_object=10))
    clip = _sim(tmp_path).generate_clip(PROMPT, seed=1)
    cfg = rp.ReconstructionConfig(cache_dir=str(tmp_path / "reconstruct"), progress=False)
    first = rp.reconstruct(clip, cfg)
    entry = rp.cache_path(clip, cfg)
    entry.write_bytes(entry.read_bytes()[:200])
    with pytest.warns(DamagedCacheEntryWarning, match="truncated"):
        assert rp.reconstruct(clip, cfg).content_hash() == first.content_hash()
    assert rp.reconstruct(clip, cfg).content_hash() == first.content_hash() and len(fits) == 2
