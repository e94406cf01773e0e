"""No-reference quality: BRISQUE (packaged model) and our NIQE rank clean renders above degraded
copies; the report command writes the paper's table, marking missing models unavailable."""

import json

import cv2
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.cli import main
from morphosim_gym.metrics.brisque_score import brisque
from morphosim_gym.metrics.niqe import niqe, pristine_model

FISH = "The fish swims through the crystal-clear waters from right to left"


def _degraded(img: np.ndarray) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(0)
    return {"blurred": cv2.GaussianBlur(img, (0, 0), 1.5),
            "noised": np.clip(img + rng.normal(0.0, 15.0, img.shape), 0, 255).astype(np.uint8)}


@pytest.fixture(scope="module")
def fish_views():
    """The paper's first scene at full detail, from the generation view and a 30-degree novel view."""
    scene = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=4.0)).generate(FISH, seed=0)
    cam = scene.camera.resized(384, 384)
    return [ms.render(scene, c, 1.0).rgb_uint8() for c in (cam, cam.orbit(30.0, scene.centre()))]


@pytest.mark.parametrize("metric", [brisque, niqe], ids=["brisque", "niqe"])
def test_clean_render_ranks_above_blurred_and_noised(fish_views, metric):
    for img in fish_views:
        clean = metric(img)
        for name, bad in _degraded(img).items():
            assert clean < metric(bad), (name, clean, metric(bad))


def test_niqe_on_a_natural_photograph_and_its_model():
    import skimage.data

    mu, cov = pristine_model()
    assert mu.shape == (36,) and cov.shape == (36, 36) and np.allclose(cov, cov.T)
    photo = skimage.data.astronaut()
    score = niqe(photo)
    # BasicSR 1.4.2's calculate_niqe (MATLAB-faithful; Y channel, no crop) gives 3.065 on this image and
    # 4.115 on skimage's coffee; ours differs only in the half-scale resize
    assert abs(score - 3.065) < 0.1 and abs(niqe(skimage.data.coffee()) - 4.115) < 0.1
    assert niqe(cv2.GaussianBlur(photo, (0, 0), 2.0)) > score + 2.0
    with pytest.raises(ValueError, match="96x96"):
        niqe(photo[:64, :64])


def _tiny_clip(path) -> None:
    """A randomly initialised CLIP with a letter-level tokenizer, saved like a downloaded model."""
    import torch
    from transformers import CLIPConfig, CLIPModel, CLIPTokenizer

    vocab = {"<|startoftext|>": 0, "<|endoftext|>": 1}
    for c in "abcdefghijklmnopqrstuvwxyz":
        vocab[c], vocab[c + "</w>"] = len(vocab), len(vocab) + 1
    (path / "vocab.json").write_text(json.dumps(vocab))
    (path / "merges.txt").write_text("#version: 0.2\n")
    torch.manual_seed(0)
    cfg = CLIPConfig(text_config=dict(vocab_size=len(vocab), hidden_size=16, intermediate_size=32, num_hidden_layers=1,
                                      num_attention_heads=2, max_position_embeddings=64, bos_token_id=0, eos_token_id=1,
                                      pad_token_id=1),
                     vision_config=dict(hidden_size=16, intermediate_size=32, num_hidden_layers=1,
                                        num_attention_heads=2, image_size=32, patch_size=8), projection_dim=8)
    CLIPModel(cfg).save_pretrained(str(path))
    CLIPTokenizer(str(path / "vocab.json"), str(path / "merges.txt")).save_pretrained(str(path))


def test_quality_report_command(tmp_path):
    prompts = tmp_path / "prompts.txt"
    prompts.write_text("# two scenes\na red ball moves from left to right\n\nThe bus is moving from right to left\n")
    clip_dir = tmp_path / "clip"
    clip_dir.mkdir()
    _tiny_clip(clip_dir)
    out = tmp_path / "quality.md"
    assert main(["quality", str(prompts), "--out", str(out), "--size", "128", "--times", "1", "--yaws=-30,30",
                 "--detail", "0.5", "--clip-model", str(clip_dir)]) == 0
    text = out.read_text()
    header = "| View | BRISQUE ↓ | NIQE ↓ | CLIP Similarity ↑ | QAlign Quality ↑ | QAlign Aesthetic ↑ |"
    assert header in text and "***Overall average***" in text and "***Scene: The bus is moving" in text
    rows = [line for line in text.splitlines() if line.startswith("| generation view")]
    assert len(rows) == 3                                   # overall + two scenes
    cells = rows[0].split("|")[2:-1]
    assert all(float(c) == float(c) for c in cells[:3])     # BRISQUE, NIQE, CLIP are numbers
    assert cells[3].strip() == cells[4].strip() == "unavailable"
    data = json.loads(out.with_suffix(".json").read_text())
    assert len(data["images"]) == 2 * 3 and {"brisque", "niqe", "clip"} <= set(data["images"][0])
    assert -1.0 <= data["images"][0]["clip"] <= 1.0
    assert "qalign_quality" in data["unavailable"] and "clip" not in data["unavailable"]
