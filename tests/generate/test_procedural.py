"""The procedural generator: determinism, ground truth, clip contract, plan checks, bad input, CLIs."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.generate.compose import compose_scene
from morphosim_gym.generate.evaluate import check_clip, evaluate, speed_ratios

SMALL = ms.GenerationConfig(width=64, height=64, num_frames=13)
PROMPT = "A small, vibrant red rubber ball is bouncing from right to left"


@pytest.fixture(scope="module")
def sim():
    return ms.MorphoSim(generation=SMALL, reconstruction="oracle")


def test_same_prompt_and_seed_give_a_bit_identical_clip(sim):
    a, b = sim.generate_clip(PROMPT, seed=3), sim.generate_clip(PROMPT, seed=3)
    assert a.content_hash() == b.content_hash()
    assert a.ground_truth.content_hash() == b.ground_truth.content_hash()
    assert sim.generate_clip(PROMPT, seed=4).content_hash() != a.content_hash()


def test_frames_are_renders_of_the_ground_truth(sim):
    clip = sim.generate_clip("a red cube moves to the plate while the camera circles the table", seed=0)
    gt = clip.ground_truth
    for i in (0, 6, 12):
        out = ms.render(gt, clip.cameras[i], t=i / clip.fps)
        np.testing.assert_array_equal(out.rgb_uint8(), clip.frames[i])
        np.testing.assert_array_equal(out.instance, clip.masks[i])
    # the camera circles the table: the cameras move
    assert not np.allclose(clip.cameras[0].position, clip.cameras[-1].position)


def test_clip_contract_and_priors(sim):
    clip = sim.generate_clip("The bus is moving from right to left", seed=0)
    T, H, W = SMALL.num_frames, SMALL.height, SMALL.width
    assert clip.frames.shape == (T, H, W, 3) and clip.frames.dtype == np.uint8
    assert len(clip.cameras) == T and clip.fps == SMALL.fps
    assert clip.depth.shape == (T, H, W) and np.all(clip.depth >= 0)
    assert set(np.unique(clip.masks)) <= {-1} | set(clip.labels)
    assert clip.labels == clip.ground_truth.id_to_name
    assert clip.tracks.shape[1:] == (T, 2) and clip.track_visible.any()
    assert [o.name for o in clip.ground_truth.objects] == ["road", "bus"]
    boxes = np.asarray(clip.info["trajectories"]["bus"]["boxes"])
    assert boxes.shape == (T, 4)


@pytest.mark.parametrize("prompt,expect", [
    ("The fish swims through the crystal-clear waters from right to left", ["water", "fish", "seaweed"]),
    ("A serene boat glides gracefully through tranquil waters from left to right", ["water", "boat"]),
    ("A sleek black motorcycle is gliding effortlessly from right to left", ["road", "motorcycle"]),
    ("two sheep walk across the field from left to right", ["grass", "sheep 1", "sheep 2"]),
])
def test_paper_prompts_pass_their_checks(sim, prompt, expect):
    clip = sim.generate_clip(prompt, seed=0)
    assert clip.ground_truth.object_names == expect
    results = check_clip(ms.parse(prompt), clip)
    assert results and all(r.passed for r in results), [r.__dict__ for r in results if not r.passed]


def test_quickly_travels_farther_than_slowly(sim):
    ratios = speed_ratios(sim, subjects=("car", "ball", "dog"))
    assert min(ratios.values()) >= 1.5, ratios


@pytest.mark.slow
def test_generate_corpus_meets_the_bars():
    corpus = Path(__file__).parents[1] / "language" / "corpus.jsonl"
    texts = sorted({json.loads(line)["text"] for line in corpus.read_text().splitlines()
                    if line.strip() and not line.startswith("#")})
    report = evaluate(texts, ms.MorphoSim(generation=ms.GenerationConfig(width=48, height=48, num_frames=9)))
    assert report["errors"] == []
    for key in ("color", "direction", "depth", "landmark", "speed"):
        assert report[key]["rate"] >= 0.95, (key, report[key], report["failures"][:5])
    assert report["objects"]["rate"] >= 0.95


def test_bad_plans_and_prompts(sim):
    with pytest.raises(ms.CommandError):
        sim.generate_clip("make the bus blue")                       # an edit, not a scene
    with pytest.raises(ms.CommandError):
        sim.generate_clip("ten thousand balls roll to the left")     # impossible count
    with pytest.raises(ValueError, match="seed"):
        sim.generate_clip(PROMPT, seed=-1)
    plan = ms.parse("a dog runs to the left")
    crowded = ms.Plan.from_dict({**plan.to_dict(), "objects": [{**plan.objects[0].to_dict(), "count": 20}]})
    with pytest.raises(ValueError, match="at most 12"):
        compose_scene(crowded, 0, SMALL)
    with pytest.raises(ms.CommandError, match="end"):
        ms.Plan.from_dict({**plan.to_dict(), "motions": [{**plan.motions[0].to_dict(), "end": "giraffe"}]})


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "morphosim_gym.cli", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300)


def test_generate_and_render_commands(tmp_path):
    out = tmp_path / "bus"
    r = _cli("generate", "The bus is moving from right to left", "--out", str(out), "--size", "48", "--frames", "9",
             cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    for name in ("clip.mp4", "scene.msim", "clip.mclip", "summary.json"):
        assert (out / name).stat().st_size > 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["setting"] == "road" and [o["name"] for o in summary["objects"]] == ["road", "bus"]
    r = _cli("render", str(out / "scene.msim"), "--orbit", "--out", str(tmp_path / "orbit.gif"), "--frames", "6",
             cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "orbit.gif").stat().st_size > 0


def test_generate_command_writes_nothing_on_bad_input(tmp_path):
    r = _cli("generate", "make the bus blue", "--out", str(tmp_path / "nope"), cwd=tmp_path)
    assert r.returncode == 2 and "edit command" in r.stderr
    assert not (tmp_path / "nope").exists()
