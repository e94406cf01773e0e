"""Sizes that would exhaust memory are refused up front with the estimate: clip generation, renders,
benchmark episode counts, and object counts in commands ("a billion balls")."""

import pytest

import morphosim_gym as ms
from morphosim_gym.bench.suite import SuiteError, load_suite
from morphosim_gym.cli import main
from morphosim_gym.errors import CommandError
from morphosim_gym.generate.compose import GenerationConfig
from morphosim_gym.limits import MAX_EPISODES, MAX_RENDER_SIDE, check_clip_size, format_bytes
from morphosim_gym.scene import Camera
from tests.conftest import make_tiny_scene


def test_huge_generation_states_the_estimate():
    with pytest.raises(ValueError, match=r"1000 frames of 4096x4096 would need ~172 GiB \(frames ~46.9 GiB, "
                                         r"depth ~62.5 GiB, masks ~62.5 GiB\); the limit is ~4 GiB"):
        GenerationConfig(num_frames=1000, width=4096, height=4096)
    with pytest.raises(ValueError, match="would need"):
        ms.MorphoSim(generation={"num_frames": 200, "width": 2048, "height": 2048})


def test_real_generation_sizes_are_allowed():
    GenerationConfig()
    GenerationConfig(num_frames=49, width=2048, height=2048)
    GenerationConfig(num_frames=1000, width=512, height=512)
    check_clip_size(49, 1024, 1024)


def test_huge_render_is_refused_before_allocating():
    s = make_tiny_scene(n_per_object=5)
    big = Camera.look_at((0, -4, 2), (0, 0.5, 0.3), 16384, 16384, 60)
    with pytest.raises(ValueError, match=rf"at most {MAX_RENDER_SIDE} pixels a side, found 16384x16384 "
                                         r"\(its outputs alone would need ~6 GiB\)"):
        ms.render(s, big)
    many = [s.camera.resized(4096, 4096)] * 16
    with pytest.raises(ValueError, match=r"16 cameras of 4096x4096 .* would need ~6 GiB"):
        ms.render(s, many)
    assert ms.render(s, s.camera.resized(32, 32)).rgb.shape == (32, 32, 3)


def test_huge_episode_counts_are_refused(tmp_path, capsys):
    suite = load_suite("smoke")
    with pytest.raises(SuiteError, match=rf"\[1, {MAX_EPISODES}\].*found 100000000: \d+ planned episodes .* "
                                         r"would need ~\d+(\.\d+)? GiB"):
        suite.with_episodes(10**8)
    assert suite.with_episodes(MAX_EPISODES).episodes == MAX_EPISODES
    path = tmp_path / "s.yaml"
    path.write_text("name: s\nenv: MorphoSim/Track-v0\nperturbations: []\nepisodes: 1000000000\n")
    with pytest.raises(SuiteError, match="planned episodes"):
        load_suite(path)
    code = main(["bench", "smoke", "--episodes", str(10**8), "--out", str(tmp_path / "out"), "--no-progress"])
    assert code != 0 and "planned episodes" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("text", ["a billion balls bounce", "two billion balls bounce", "a trillion cubes",
                                  "countless balls bounce", "1e9 balls bounce", "a zillion mugs",
                                  "10^9 balls bounce", "10 ** 12 cubes"])
def test_unbounded_counts_are_command_errors(text):
    with pytest.raises(CommandError, match="count must be"):
        ms.parse(text)


def test_ordinary_counts_still_parse():
    assert [o.count for o in ms.parse("three balls bounce").objects] == [3]
    assert [o.count for o in ms.parse("twenty balls bounce").objects] == [20]
    assert [o.count for o in ms.parse("balls bounce").objects] == [3]
    assert [o.count for o in ms.parse("2^3 balls bounce").objects] == [8]     # a power is its value


def test_format_bytes():
    assert format_bytes(47 << 30) == "~47 GiB" and format_bytes(512 << 20) == "~512 MiB"
    assert format_bytes(10) == "10 bytes"
