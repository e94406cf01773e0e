"""MorphoSim's on-disk cache of oracle scenes: what the benchmark workers share."""

import pytest

import morphosim_gym as ms
from morphosim_gym.scene.diskcache import DamagedCacheEntryWarning

PROMPT = "a red ball moves from left to right next to a blue cube"


def test_oracle_scenes_are_cached_on_disk_bit_exact(tmp_path):
    cached = ms.MorphoSim(reconstruction="oracle", cache=True, cache_dir=str(tmp_path))
    first = cached.generate(PROMPT, seed=3)
    files = list((tmp_path / "scene").glob("*.msim"))
    assert len(files) == 1
    again = ms.MorphoSim(reconstruction="oracle", cache=True, cache_dir=str(tmp_path)).generate(PROMPT, seed=3)
    plain = ms.MorphoSim(reconstruction="oracle").generate(PROMPT, seed=3)
    assert again.content_hash() == first.content_hash() == plain.content_hash()
    cached.generate(PROMPT, seed=4)
    assert len(list((tmp_path / "scene").glob("*.msim"))) == 2
    files[0].write_bytes(b"damaged")                         # a damaged entry is regenerated, not fatal
    with pytest.warns(DamagedCacheEntryWarning, match=files[0].name):
        assert cached.generate(PROMPT, seed=3).content_hash() == first.content_hash()
