"""The diffusion backend behind the ClipGenerator protocol, end to end from `MorphoSim`, the envs and the
CLI, on tiny random CogVideoX weights saved to a local folder (the frames are noise; the wiring is real):
the guidance boxes are the trajectory planner's, guidance lowers the energy E, no download happens."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("diffusers")

import morphosim_gym as ms  # noqa: E402
from morphosim_gym.generate.compose import compose_scene  # noqa: E402
from morphosim_gym.generate.diffusion import DiffusionConfig, GuidanceConfig  # noqa: E402
from morphosim_gym.generate.diffusion.planned import (  # noqa: E402
    PlannedDiffusionGenerator,
    motion_word,
    planning_config,
    scene_text,
)
from morphosim_gym.generate.diffusion.testing import make_tiny_pipeline  # noqa: E402

PROMPT = "a red ball rolls from right to left"
GEN = ms.GenerationConfig(detail=0.3, assets="off")


pytestmark = pytest.mark.usefixtures("torch_one_thread")


@pytest.fixture(scope="module")
def weights(tmp_path_factory):
    path = tmp_path_factory.mktemp("tiny_cogvideox")
    make_tiny_pipeline(seed=0).save_pretrained(str(path))
    return path


def _diffusion(weights, **guidance):
    g = dict(strength=0.25, guidance_steps=3, inner_iters=2)
    g.update(guidance)
    return DiffusionConfig(weights_path=weights, device="cpu", num_inference_steps=6, height=64, width=64,
                           num_frames=9, guidance=GuidanceConfig(**g))


def _sim(weights, **kw):
    return ms.MorphoSim(ms.SimConfig(generator="diffusion", diffusion=_diffusion(weights, **kw.pop("guidance", {})),
                                     generation=GEN, **kw))


def test_guidance_boxes_are_the_planners(weights):
    sim = _sim(weights)
    gen = sim.generator
    assert isinstance(gen, PlannedDiffusionGenerator) and gen.name == "diffusion"
    clip = sim.generate_clip(PROMPT, seed=1)
    # the procedural planner with the same plan, seed and settings at the model's clip size
    planned = compose_scene(ms.parse(PROMPT), 1, planning_config(GEN, gen.config), PROMPT)
    boxes = np.clip(planned.trajectories["ball"].boxes_normalized(), 0, 1)
    (target,) = clip.info["targets"]              # what the backend steered with
    assert target["words"] == ["ball"] and target["label"] == "ball"
    np.testing.assert_allclose(target["boxes"], boxes, atol=1e-12)
    assert boxes[0, 0] > boxes[-1, 0]            # right to left
    # the clip is seen by the planner's camera, fixed
    assert all(c == planned.cameras[0] for c in clip.cameras) and len(clip.cameras) == 9
    assert clip.info["trajectories"]["ball"]["boxes"] == planned.trajectories["ball"].to_dict()["boxes"]
    # a different seed plans a different path, and the guidance follows it
    other = sim.generate_clip(PROMPT, seed=2)
    assert not np.allclose(other.info["targets"][0]["boxes"], target["boxes"])


def test_diffusion_clip_end_to_end_from_morphosim(weights):
    sim = _sim(weights)
    clip = sim.generate_clip(PROMPT, seed=0)
    assert isinstance(clip, ms.GeneratedClip) and clip.ground_truth is None
    assert clip.frames.shape == (9, 64, 64, 3) and clip.frames.dtype == np.uint8 and clip.fps == 8.0
    assert clip.labels == {0: "ball"} and clip.masks.shape == (9, 64, 64) and clip.depth.shape == (9, 64, 64)
    assert clip.prompt == PROMPT and clip.info["backend"] == "diffusion" and clip.info["unguided"] == []
    assert clip.info["weights_path"] == str(weights)
    json.dumps(clip.info)
    assert sim.generate_clip(PROMPT, seed=0).content_hash() == clip.content_hash()      # deterministic


def test_guidance_through_the_wiring_lowers_the_energy(weights):
    guided = _sim(weights).generate_clip(PROMPT, seed=0).info["guidance"]
    plain = _sim(weights, guidance={"enabled": False}).generate_clip(PROMPT, seed=0).info["guidance"]
    e_guided, e_plain = np.mean(guided["energy"]), np.mean(plain["energy"])
    assert e_guided < e_plain, (e_plain, e_guided)


def test_prompt_text_and_motion_words():
    plan = ms.parse("a red ball rolls from right to left; then make the ball blue")
    assert scene_text(plan, plan.text) == "a red ball rolls from right to left"
    assert motion_word("two red balls roll to the left", "ball") == "balls"
    assert motion_word("a red ball", "cube") is None


def test_compound_prompts_and_camera_motion_are_planned_in_one_fixed_view(weights):
    sim = _sim(weights)
    clip = sim.generate_clip("two red balls roll from right to left while the camera orbits", seed=0)
    (target,) = clip.info["targets"]          # two instances, one noun: one target, the union of their boxes
    assert target["words"] == ["balls"] and clip.info["camera_motion"] == "orbit"
    assert len({c.world_to_camera.tobytes() for c in clip.cameras}) == 1


def test_diffusion_needs_fit_and_local_weights(weights, tmp_path):
    with pytest.raises(ValueError, match="reconstruction='fit'"):
        _sim(weights, reconstruction="oracle")
    with pytest.raises(ms.BackendUnavailableError, match="weights_path"):
        ms.MorphoSim(generator="diffusion")
    with pytest.raises(ms.BackendUnavailableError, match="does not exist"):
        ms.MorphoSim(generator="diffusion", diffusion=DiffusionConfig(weights_path=tmp_path / "none"))
    assert not (tmp_path / "none").exists()
    assert ms.SimConfig(diffusion={"num_frames": 9}).diffusion == DiffusionConfig(num_frames=9)   # a YAML mapping
    with pytest.raises(ValueError, match="unknown \\['steps'\\]"):
        ms.SimConfig(diffusion={"steps": 4})


def test_clip_cache_key_holds_the_diffusion_settings(weights, tmp_path):
    a = _sim(weights, cache=True, cache_dir=str(tmp_path))
    b = ms.MorphoSim(replace(a.config, diffusion=replace(_diffusion(weights), num_inference_steps=5)))
    assert a._cache_path("clip", PROMPT, 0) != b._cache_path("clip", PROMPT, 0)
    clip = a.generate_clip(PROMPT, seed=0)
    assert a._cache_path("clip", PROMPT, 0).exists()
    assert a.generate_clip(PROMPT, seed=0).content_hash() == clip.content_hash()


def test_generate_command_with_the_diffusion_generator(weights, tmp_path):
    config = tmp_path / "diffusion.yaml"
    config.write_text("device: cpu\nguidance:\n  strength: 0.25\n  guidance_steps: 2\n  inner_iters: 1\n")
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "morphosim_gym.cli", "generate", PROMPT, "--out", str(out),
                        "--generator", "diffusion", "--weights", str(weights), "--diffusion-config", str(config),
                        "--size", "64", "--frames", "9", "--steps", "3"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL,
                       env={**__import__("os").environ, "OMP_NUM_THREADS": "1"})
    assert r.returncode == 0, r.stderr[-2000:]
    for name in ("clip.mp4", "clip.mclip", "summary.json"):
        assert (out / name).stat().st_size > 0
    assert not (out / "scene.msim").exists() and "--reconstruct" in r.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["generator"] == "diffusion" and summary["objects"] == [{"id": 0, "name": "ball"}]
    assert len(summary["guidance_energy"]) == 3 and summary["trajectories"]["ball"]["boxes"]
    clip = ms.load_clip(out / "clip.mclip")
    assert clip.frames.shape == (9, 64, 64, 3) and clip.info["settings"]["num_inference_steps"] == 3
    bad = subprocess.run([sys.executable, "-m", "morphosim_gym.cli", "generate", PROMPT, "--out", str(tmp_path / "x"),
                          "--generator", "dalle"], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         stdin=subprocess.DEVNULL)
    assert bad.returncode == 2 and "'procedural', 'diffusion', or 'module:factory'" in bad.stderr
    assert not (tmp_path / "x").exists()


def test_track_env_on_a_diffusion_world(weights):
    """gym.make -> reset -> step on a world fitted to a diffusion clip (a short fit: seconds on tiny clips)."""
    import gymnasium as gym

    from morphosim_gym.reconstruct import ReconstructionConfig
    from morphosim_gym.reconstruct.features import FeatureConfig
    from morphosim_gym.reconstruct.fit import FitConfig

    fast = ReconstructionConfig(fit=FitConfig(iterations=60, progress=False),
                                features=FeatureConfig(iterations=30, progress=False), complete=False,
                                progress=False, cache=False)
    sim = ms.SimConfig(generator="diffusion", diffusion=_diffusion(weights), generation=GEN, reconstruction="fit",
                       reconstruction_config=fast)
    env = gym.make("MorphoSim/Track-v0", sim=sim, prompt=PROMPT, scene_seed=0, width=16, height=16)
    try:
        obs, info = env.reset(seed=0)
        assert info["target"] == "ball" and env.unwrapped.scene.provenance.generator == "diffusion"
        obs, reward, _, _, info = env.step(env.action_space.sample())
        assert obs["rgb"].shape == (16, 16, 3) and np.isfinite(reward)
    finally:
        env.close()
