"""Diffusion backend: trajectory attention processors, the frame-wise box energy, guided sampling
and the clip contract, on tiny randomly initialised CogVideoX models built from configs (CPU)."""

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("diffusers")

from morphosim_gym.errors import BackendUnavailableError  # noqa: E402
from morphosim_gym.generate.diffusion import (  # noqa: E402
    AttentionStore,
    DefaultPriorEstimators,
    DiffusionClipBackend,
    DiffusionConfig,
    GuidanceConfig,
    GuidanceTarget,
    boxes_to_latent_frames,
    cogvideox_rotary_embeddings,
    frame_energy,
    guided_sample,
    in_box_fraction,
    install_trajectory_processors,
    latent_frame_groups,
    rasterize_boxes,
    token_indices_for_words,
    tokens_to_latent_grid,
    trajectory_loss,
)
from morphosim_gym.generate.diffusion.testing import (  # noqa: E402
    make_tiny_pipeline,
    make_tiny_scheduler,
    make_tiny_tokenizer,
    make_tiny_transformer,
)
from morphosim_gym.scene import Camera, GeneratedClip  # noqa: E402

T_LAT, H_LAT, W_LAT, P = 3, 16, 16, 2  # tiny latents: 3 latent frames (9 video frames), 16 x 16, patch 2


pytestmark = pytest.mark.usefixtures("torch_one_thread")


@pytest.fixture(scope="module")
def tiny():
    g = torch.Generator().manual_seed(0)
    return dict(transformer=make_tiny_transformer(seed=0), scheduler=make_tiny_scheduler(),
                noise=torch.randn(1, T_LAT, 4, H_LAT, W_LAT, generator=g),
                embeds=torch.randn(1, 16, 16, generator=g), negative=torch.randn(1, 16, 16, generator=g))


def _forward(tr, lat, emb, t=500):
    rope = cogvideox_rotary_embeddings(tr, lat.shape[1], lat.shape[3], lat.shape[4], "cpu")
    with torch.no_grad():
        return tr(hidden_states=lat, encoder_hidden_states=emb, timestep=torch.tensor([t]), image_rotary_emb=rope,
                  return_dict=False)[0]


class ExplicitAttn:
    """Reference processor: softmax(Q K^T * scale) written out, keeping the full joint attention
    matrix (text tokens first, then video tokens)."""

    def __init__(self, sink):
        self.sink = sink

    def __call__(self, attn, hidden_states, encoder_hidden_states, attention_mask=None, image_rotary_emb=None):
        from diffusers.models.embeddings import apply_rotary_emb

        n_text = encoder_hidden_states.size(1)
        x = torch.cat([encoder_hidden_states, hidden_states], dim=1)
        b = x.shape[0]
        q, k, v = (f(x).view(b, -1, attn.heads, x.shape[-1] // attn.heads).transpose(1, 2)
                   for f in (attn.to_q, attn.to_k, attn.to_v))
        q, k = attn.norm_q(q), attn.norm_k(k)
        q = torch.cat([q[:, :, :n_text], apply_rotary_emb(q[:, :, n_text:], image_rotary_emb)], 2)
        k = torch.cat([k[:, :, :n_text], apply_rotary_emb(k[:, :, n_text:], image_rotary_emb)], 2)
        probs = torch.softmax(q @ k.transpose(-1, -2) * attn.scale, dim=-1)
        self.sink.append((probs, q, k))
        out = (probs @ v).transpose(1, 2).reshape(b, -1, attn.heads * v.shape[-1])
        out = attn.to_out[1](attn.to_out[0](out))
        return out[:, n_text:], out[:, :n_text]


# ------------------------------------------------------------------------------------------ processors
@pytest.mark.parametrize("recording", [False, True])
@pytest.mark.parametrize("normalization", ["text", "joint"])
def test_processors_match_default_attention(tiny, recording, normalization):
    tr = tiny["transformer"]
    ref = _forward(tr, tiny["noise"], tiny["embeds"])
    store = AttentionStore(token_indices=[2, 5], normalization=normalization, recording=recording, chunk_size=50)
    with install_trajectory_processors(tr, store) as names:
        out = _forward(tr, tiny["noise"], tiny["embeds"])
    assert names == ["transformer_blocks.0.attn1.processor", "transformer_blocks.1.attn1.processor"]
    assert type(tr.attn_processors[names[0]]).__name__ == "CogVideoXAttnProcessor2_0"  # restored
    # same fused SDPA as diffusers' processor; RoPE out of place instead of in place
    torch.testing.assert_close(out, ref, atol=1e-5, rtol=0)
    assert bool(store.maps) == recording


def test_recorded_attention_is_the_explicit_softmax(tiny):
    tr = tiny["transformer"]
    sink = []
    procs = dict(tr.attn_processors)
    tr.set_attn_processor({n: ExplicitAttn(sink) for n in procs})
    try:
        explicit_out = _forward(tr, tiny["noise"], tiny["embeds"])
    finally:
        tr.set_attn_processor(procs)
    # the explicit path matches the fused default (float32 round-off only)
    torch.testing.assert_close(explicit_out, _forward(tr, tiny["noise"], tiny["embeds"]), atol=1e-5, rtol=0)
    idx, n_text = [2, 5], 16
    for normalization in ("joint", "text"):
        store = AttentionStore(token_indices=idx, normalization=normalization, recording=True, chunk_size=64)
        with install_trajectory_processors(tr, store) as names:
            _forward(tr, tiny["noise"], tiny["embeds"])
        for name, (probs, q, k) in zip(names, sink, strict=True):
            if normalization == "joint":  # the model's own probabilities: video queries -> text keys idx
                want = probs[:, :, n_text:, idx].mean(1)
            else:  # softmax over the text keys only: the paper's sum_n A_{u,n} = 1
                s = q[:, :, n_text:] @ k[:, :, :n_text].transpose(-1, -2) * tr.transformer_blocks[0].attn1.scale
                want = torch.softmax(s, -1)[..., idx].mean(1)
            torch.testing.assert_close(store.maps[name], want, atol=1e-6, rtol=1e-5)


def test_recording_with_gradients_matches_no_grad(tiny):
    tr = tiny["transformer"]
    lat = tiny["noise"].clone().requires_grad_(True)
    maps = {}
    for grad in (False, True):
        store = AttentionStore(token_indices=[3], recording=True, chunk_size=40)
        with install_trajectory_processors(tr, store, layers=[-1]), torch.set_grad_enabled(grad):
            rope = cogvideox_rotary_embeddings(tr, T_LAT, H_LAT, W_LAT, "cpu")
            tr(hidden_states=lat, encoder_hidden_states=tiny["embeds"], timestep=torch.tensor([500]),
               image_rotary_emb=rope, return_dict=False)
        maps[grad] = store.mean_map()
    torch.testing.assert_close(maps[True].detach(), maps[False], atol=1e-6, rtol=0)
    (g,) = torch.autograd.grad(maps[True][0, :10, 0].sum(), lat)  # gradients reach the latents
    assert torch.isfinite(g).all() and g.abs().sum() > 0


# ------------------------------------------------------------------------------ energy and geometry
def test_energy_whole_frame_box_is_zero_and_all_outside_is_one():
    rng = np.random.default_rng(0)
    attn = torch.from_numpy(rng.random((2, T_LAT, H_LAT, W_LAT))).float()
    whole = torch.from_numpy(rasterize_boxes(np.tile([0, 0, 1, 1.0], (T_LAT, 1)), H_LAT, W_LAT))
    assert torch.all(whole == 1)
    assert float(trajectory_loss(attn, whole)) == pytest.approx(0.0, abs=1e-7)
    # all attention in the right half, box on the left half -> E_i = 1 for every frame
    right = attn.clone()
    right[..., : W_LAT // 2] = 0
    left_box = torch.from_numpy(rasterize_boxes(np.tile([0, 0, 0.5, 1.0], (T_LAT, 1)), H_LAT, W_LAT))
    torch.testing.assert_close(frame_energy(right, left_box), torch.ones(2, T_LAT))
    # uniform attention, box of area 1/4 -> fraction 1/4, E = (3/4)^2
    uniform = torch.ones(T_LAT, H_LAT, W_LAT)
    quarter = torch.from_numpy(rasterize_boxes(np.tile([0.25, 0.25, 0.75, 0.75], (T_LAT, 1)), H_LAT, W_LAT))
    torch.testing.assert_close(in_box_fraction(uniform, quarter), torch.full((T_LAT,), 0.25))
    assert float(trajectory_loss(uniform, quarter)) == pytest.approx(0.5625)
    assert float(trajectory_loss(uniform, quarter, "sum")) == pytest.approx(0.5625 * T_LAT)


def test_rasterize_boxes_soft_coverage():
    m = rasterize_boxes(np.array([[0.1, 0.0, 0.35, 0.5]]), 4, 4)  # x covers cells 0 (60%) and 1 (40%)
    np.testing.assert_allclose(m[0, :2, 0], 0.6, atol=1e-6)
    np.testing.assert_allclose(m[0, :2, 1], 0.4, atol=1e-6)
    assert m[0, 2:].sum() == 0 and m[0, :, 2:].sum() == 0
    assert m.sum() == pytest.approx(0.25 * 0.5 * 16)


def test_video_boxes_to_latent_frames():
    assert [list(g) for g in latent_frame_groups(9, 4)] == [[0], [1, 2, 3, 4], [5, 6, 7, 8]]
    assert len(latent_frame_groups(49, 4)) == 13
    boxes = np.stack([np.array([0.0, 0.0, 0.1, 0.1]) + 0.1 * i for i in range(9)])
    lat = boxes_to_latent_frames(boxes, 4)
    np.testing.assert_allclose(lat[:, 0], [0.0, 0.25, 0.65])  # frame 0; mean of 1..4; mean of 5..8
    with pytest.raises(ValueError, match="1 \\+ 4 k"):
        latent_frame_groups(10, 4)


@pytest.mark.parametrize("patch_size_t", [None, 2])
def test_token_order_matches_diffusers_patch_embedding(patch_size_t):
    """A latent cell perturbed before patchification changes exactly one video token; the reshape back
    to the latent grid puts that token over the cell (text tokens first, video tokens in (t, h, w) order)."""
    tr = make_tiny_transformer(seed=1, patch_size_t=patch_size_t)
    t_lat = 4 if patch_size_t else 3
    text = torch.zeros(1, 16, 16)
    base = torch.zeros(1, t_lat, 4, H_LAT, W_LAT)
    with torch.no_grad():
        e0 = tr.patch_embed(text, base)
        for t, y, x in [(0, 0, 0), (t_lat - 1, 5, 11), (1, 15, 2), (2, 9, 8)]:
            lat = base.clone()
            lat[0, t, :, y, x] = 1.0
            changed = (tr.patch_embed(text, lat) - e0).abs().sum(-1)[0] > 0  # [L_text + N_video]
            assert not changed[:16].any()  # text tokens come first and are untouched
            video = changed[16:].float()
            assert int(video.sum()) == 1
            grid = tokens_to_latent_grid(video[None, :, None], t_lat, H_LAT, W_LAT, P, patch_size_t)[0, 0]
            assert grid[t, y, x] == 1
            pt = patch_size_t or 1
            assert int(grid.sum()) == pt * P * P  # the token covers its p_t x p x p cells, nothing else
            k = int(video.argmax())
            assert k == (t // pt) * (H_LAT // P) * (W_LAT // P) + (y // P) * (W_LAT // P) + x // P


def test_synthetic_attention_lands_in_the_right_cell():
    n_tok = T_LAT * (H_LAT // P) * (W_LAT // P)
    maps = torch.zeros(1, n_tok, 2)
    t, h, w = 2, 3, 6  # token coordinates
    maps[0, t * 64 + h * 8 + w, 1] = 1.0
    grid = tokens_to_latent_grid(maps, T_LAT, H_LAT, W_LAT, P)  # [1, 2, T, H, W]
    assert grid.shape == (1, 2, T_LAT, H_LAT, W_LAT)
    assert grid[0, 0].sum() == 0
    nz = torch.nonzero(grid[0, 1])
    assert {tuple(r) for r in nz.tolist()} == {(t, h * P + a, w * P + b) for a in range(P) for b in range(P)}
    box = rasterize_boxes(np.tile([w * P / W_LAT, h * P / H_LAT, (w + 1) * P / W_LAT, (h + 1) * P / H_LAT],
                                  (T_LAT, 1)), H_LAT, W_LAT)
    fe = frame_energy(grid[0, 1], torch.from_numpy(box))
    assert float(fe[t]) == pytest.approx(0.0, abs=1e-7)


# ------------------------------------------------------------------------------------------ guidance
BOXES = [np.array([[0.0, 0.25, 0.5, 0.75], [0.25, 0.25, 0.75, 0.75], [0.5, 0.25, 1.0, 0.75]])]  # moves right


def _sample(tiny, cfg, **kw):
    return guided_sample(tiny["transformer"], tiny["scheduler"], tiny["noise"], tiny["embeds"], tiny["negative"],
                         [[3]], BOXES, cfg, num_inference_steps=8, guidance_scale=6.0, record=True, **kw)


def test_guidance_lowers_energy_and_moves_attention_into_boxes(tiny):
    x0, plain = _sample(tiny, GuidanceConfig(enabled=False))
    cfg = GuidanceConfig(strength=0.25, guidance_steps=4, inner_iters=3)
    x1, guided = _sample(tiny, cfg)
    e0, e1 = np.mean(plain.energy), np.mean(guided.energy)
    f0, f1 = np.mean(plain.in_box), np.mean(guided.in_box)
    # unguided: attention mass in the boxes is about their area (1/4); guided: clearly inside
    assert e1 < 0.5 * e0, (e0, e1)
    assert f1 > f0 + 0.3, (f0, f1)
    assert guided.energy[-1] < plain.energy[-1] - 0.2  # still true at the last step (guidance stops at 4)
    # within the guided steps the energy falls over the inner iterations
    g = guided.guidance
    assert len(g) == 4 * 3 and g[-1]["energy"] < g[0]["energy"]
    assert [d["step"] for d in g[::3]] == [0, 1, 2, 3]
    assert guided.attention.shape == (1, T_LAT, H_LAT, W_LAT) and guided.frame_energy.shape == (8, 1, T_LAT)
    assert torch.isfinite(x1).all() and not torch.equal(x0, x1)
    # same noise, same settings: bit-identical on the CPU
    x2, again = _sample(tiny, cfg)
    assert torch.equal(x1, x2) and again.energy == guided.energy


def test_guidance_with_gradient_checkpointing_enabled(tiny):
    tr = tiny["transformer"]
    tr.enable_gradient_checkpointing()
    try:
        _, with_ckpt = _sample(tiny, GuidanceConfig(strength=0.25, guidance_steps=2, inner_iters=1))
        assert tr.gradient_checkpointing  # restored
    finally:
        tr.disable_gradient_checkpointing()
    _, without = _sample(tiny, GuidanceConfig(strength=0.25, guidance_steps=2, inner_iters=1))
    assert with_ckpt.energy == without.energy


def test_guidance_options(tiny):
    # explicit step list, linear schedule, raw gradients, one hooked layer, joint normalisation, DPM scheduler
    from diffusers import CogVideoXDPMScheduler

    cfg = GuidanceConfig(strength=200.0, guidance_steps=(0, 2), inner_iters=1, strength_schedule="linear",
                         grad_normalization="none", layers=(-1,), attention_normalization="joint",
                         frame_reduction="sum")
    assert cfg.step_strengths(8) == {0: 200.0, 2: 100.0}
    dpm = CogVideoXDPMScheduler.from_config(tiny["scheduler"].config)
    x, tr_ = guided_sample(tiny["transformer"], dpm, tiny["noise"], tiny["embeds"], tiny["negative"], [[3]], BOXES,
                           cfg, num_inference_steps=8, record=True, generator=torch.Generator().manual_seed(0))
    assert [d["step"] for d in tr_.guidance] == [0, 2] and torch.isfinite(x).all()
    assert tr_.guidance[1]["strength"] == 100.0
    with pytest.raises(ValueError, match="guidance.inner_iters"):
        GuidanceConfig(inner_iters=0)
    with pytest.raises(ValueError, match="guidance.attention_normalization"):
        GuidanceConfig(attention_normalization="rows")


# ------------------------------------------------------------------------------------ targets, text
def test_guidance_target_validation():
    ok = GuidanceTarget(["red", "ball"], np.tile([0.1, 0.2, 0.3, 0.4], (9, 1)))
    assert ok.label == "red ball" and ok.words == ("red", "ball")
    for bad, match in [(dict(words=[], boxes=np.zeros((9, 4))), "words"),
                       (dict(words=["a"], boxes=np.zeros((9, 3))), "shape"),
                       (dict(words=["a"], boxes=np.tile([0.5, 0.1, 0.4, 0.3], (9, 1))), "x0 < x1"),
                       (dict(words=["a"], boxes=np.tile([0.1, 0.1, 1.4, 0.3], (9, 1))), r"\[0, 1\]"),
                       (dict(words=["a"], boxes=np.full((9, 4), np.nan)), "finite")]:
        with pytest.raises(ValueError, match=match):
            GuidanceTarget(**bad)


def test_words_to_token_indices():
    tok = make_tiny_tokenizer()
    prompt = "A red ball rolls from right to left"
    assert token_indices_for_words(tok, prompt, ["ball"], 16) == [2]
    assert token_indices_for_words(tok, prompt, ["Red", "ball"], 16) == [1, 2]
    with pytest.raises(ValueError, match="'bus'"):
        token_indices_for_words(tok, prompt, ["bus"], 16)
    with pytest.raises(ValueError, match="truncated"):
        token_indices_for_words(tok, prompt, ["left"], 4)


def test_words_to_token_indices_with_a_sentencepiece_t5_tokenizer(tmp_path):
    """The real CogVideoX tokenizer is T5's SentencePiece one: words split into several pieces, some
    preceded by a bare "▁" piece, which is not counted as a motion token."""
    pytest.importorskip("sentencepiece")
    pytest.importorskip("google.protobuf")
    from morphosim_gym.generate.diffusion.testing import make_tiny_t5_tokenizer

    tok = make_tiny_t5_tokenizer(str(tmp_path / "tokenizer"))
    assert type(tok).__name__ == "T5Tokenizer"
    prompt = "A sleek black motorcycle is gliding from right to left"
    ids = tok(prompt, padding="max_length", max_length=64, truncation=True)["input_ids"]
    pieces = tok.convert_ids_to_tokens(ids)
    idx = token_indices_for_words(tok, prompt, ["motorcycle"], 64)
    assert "".join(pieces[i] for i in idx) == "\u2581motorcycle"
    both = token_indices_for_words(tok, prompt, ["black", "motorcycle"], 64)
    assert "".join(pieces[i] for i in both) == "\u2581black\u2581motorcycle"
    is_idx = token_indices_for_words(tok, prompt, ["is"], 64)
    assert [pieces[i] for i in is_idx] == ["is"]  # the bare "\u2581" before it is left out


# ------------------------------------------------------------------------------------------- backend
def _config(path, **kw):
    return DiffusionConfig(weights_path=path, device="cpu", num_inference_steps=6, height=128, width=128,
                           num_frames=9, guidance=GuidanceConfig(strength=0.25, guidance_steps=3, inner_iters=2), **kw)


def _boxes_right_to_left(n=9):
    return np.linspace([0.55, 0.3, 0.95, 0.7], [0.05, 0.3, 0.45, 0.7], n)


@pytest.fixture(scope="module")
def tiny_weights(tmp_path_factory):
    path = tmp_path_factory.mktemp("tiny_cogvideox")
    make_tiny_pipeline(seed=0).save_pretrained(str(path))
    return path


def test_generate_end_to_end_from_local_weights(tiny_weights):
    backend = DiffusionClipBackend(_config(tiny_weights))
    prompt = "a red ball rolls from right to left"
    target = GuidanceTarget(["red", "ball"], _boxes_right_to_left())
    clip = backend.generate(prompt, [target], seed=3)
    assert isinstance(clip, GeneratedClip)
    assert clip.frames.shape == (9, 128, 128, 3) and clip.frames.dtype == np.uint8
    assert len(clip.cameras) == 9 and all(c == clip.cameras[0] for c in clip.cameras)
    assert clip.cameras[0].fov_y_deg == pytest.approx(60.0) and clip.fps == 8.0 and clip.ground_truth is None
    assert clip.prompt == prompt
    # priors
    assert clip.depth.shape == (9, 128, 128) and clip.depth.max() > 0 and clip.depth[:, 0].max() == 0  # sky: unknown
    assert clip.masks.shape == (9, 128, 128) and clip.labels == {0: "red ball"}
    assert (clip.masks[0] == 0).any() and (clip.masks == -1).any()
    _, xs = np.nonzero(clip.masks[-1] == 0)  # the last frame's mask lies inside the last box
    assert xs.min() >= np.floor(0.05 * 128) and xs.max() < np.ceil(0.45 * 128)
    assert clip.tracks.shape[1:] == (9, 2) and clip.track_visible.shape == clip.tracks.shape[:2]
    # tracks are seeded at anchor frames (the first, middle and last) and followed both ways: the
    # first frame's seeds come first, and every track is seen at least at its anchor
    seeded_first = np.flatnonzero(~clip.track_visible[:, 0])
    assert clip.track_visible[:, 0].any() and clip.track_visible.any(axis=1).all()
    assert seeded_first.size == 0 or clip.track_visible[:seeded_first[0], 0].all()
    # info: token indices found by the tokenizer, guidance measurements, JSON-friendly
    info = clip.info
    assert info["backend"] == "diffusion" and info["token_indices"] == [[1, 2]]
    assert len(info["guidance"]["energy"]) == 6 and len(info["guidance"]["guidance"]) == 3 * 2
    json.dumps(info)
    # determinism: same seed, same clip
    assert backend.generate(prompt, [target], seed=3).content_hash() == clip.content_hash()
    assert backend.generate(prompt, [target], seed=4).content_hash() != clip.content_hash()


def test_generate_with_prompt_embeds_and_explicit_tokens(tiny):
    pipe = make_tiny_pipeline(seed=0, text_encoder=False)
    backend = DiffusionClipBackend(_config(None), pipeline=pipe)
    camera = Camera.look_at((1, -3, 1.5), (0, 0, 0.3), 64, 64, 45)
    target = GuidanceTarget(["ball"], _boxes_right_to_left(), token_indices=[3])
    clip = backend.generate("a ball", [target], seed=0, camera=camera, prompt_embeds=tiny["embeds"],
                            negative_prompt_embeds=tiny["negative"])
    assert clip.frames.shape == (9, 128, 128, 3)
    assert clip.cameras[0] == camera.resized(128, 128)
    assert clip.info["token_indices"] == [[3]]
    plain = backend.generate("a ball", [], seed=0, prompt_embeds=tiny["embeds"])  # no targets: plain sampling
    assert plain.masks is None and plain.info["guidance"] is None and plain.tracks is not None
    with pytest.raises(ValueError, match="token_indices"):
        backend.generate("a ball", [GuidanceTarget(["ball"], _boxes_right_to_left())], seed=0,
                         prompt_embeds=tiny["embeds"])
    with pytest.raises(ValueError, match="prompt_embeds"):
        backend.generate("a ball", [target], seed=0)
    with pytest.raises(ValueError, match="9 boxes"):
        backend.generate("a ball", [GuidanceTarget(["ball"], np.tile([0, 0, 1, 1.0], (5, 1)), token_indices=[3])],
                         seed=0, prompt_embeds=tiny["embeds"])


def test_cogvideox15_style_transformer_pads_latent_frames(tiny):
    """CogVideoX 1.5 patches 2 latent frames per token: 3 latent frames are padded to 4 at the start (as the
    pipeline does), guided on the padded grid, and the padding is dropped before decoding."""
    pipe = make_tiny_pipeline(seed=0, text_encoder=False)
    pipe.transformer = make_tiny_transformer(seed=0, patch_size_t=2)
    backend = DiffusionClipBackend(_config(None), pipeline=pipe)
    target = GuidanceTarget(["ball"], _boxes_right_to_left(), token_indices=[3])
    clip = backend.generate("a ball", [target], seed=0, prompt_embeds=tiny["embeds"],
                            negative_prompt_embeds=tiny["negative"])
    assert clip.frames.shape == (9, 128, 128, 3) and clip.masks.shape == (9, 128, 128)
    g = clip.info["guidance"]["guidance"]
    assert g[-1]["energy"] < g[0]["energy"]


def test_generate_in_bfloat16(tiny):
    """The reduced-precision path (as used on CUDA) runs: model in bf16, latents, guidance gradients and the
    scheduler in float32. (CPU only here; a CUDA run with real weights is not tested.)"""
    backend = DiffusionClipBackend(_config(None, dtype="bfloat16"), pipeline=make_tiny_pipeline(seed=0))
    assert backend.dtype == torch.bfloat16
    clip = backend.generate("a red ball rolls", [GuidanceTarget(["ball"], _boxes_right_to_left())], seed=0)
    assert clip.frames.shape == (9, 128, 128, 3) and clip.info["dtype"] == "bfloat16"
    g = clip.info["guidance"]["guidance"]
    assert np.isfinite([d["energy"] for d in g]).all() and g[-1]["energy"] < g[0]["energy"]


def test_missing_weights_path_is_a_clear_error_and_writes_nothing(tmp_path):
    missing = tmp_path / "no" / "CogVideoX-2b"
    with pytest.raises(BackendUnavailableError, match=str(missing)):
        DiffusionClipBackend(_config(missing))
    with pytest.raises(BackendUnavailableError, match="weights_path"):
        DiffusionClipBackend(_config(None))
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(BackendUnavailableError, match="model_index.json"):
        DiffusionClipBackend(_config(empty))
    partial = tmp_path / "partial"
    partial.mkdir()
    (partial / "model_index.json").write_text(json.dumps({"_class_name": "CogVideoXPipeline"}))
    with pytest.raises(BackendUnavailableError, match="transformer"):
        DiffusionClipBackend(_config(partial))
    assert not missing.exists() and not missing.parent.exists()
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["empty", "model_index.json", "partial"]


def test_broken_weights_fail_on_load_naming_the_path(tmp_path, tiny_weights):
    import shutil

    broken = tmp_path / "broken"
    shutil.copytree(tiny_weights, broken)
    for f in (broken / "transformer").iterdir():
        if f.suffix == ".safetensors":
            f.write_bytes(b"not a safetensors file")
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    backend = DiffusionClipBackend(_config(broken))
    with pytest.raises(BackendUnavailableError, match=str(broken)):
        backend.generate("a red ball", [], seed=0)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before


def test_config_validation_names_the_key():
    with pytest.raises(ValueError, match="diffusion.num_frames"):
        DiffusionConfig(num_frames=0)
    with pytest.raises(ValueError, match="diffusion.dtype"):
        DiffusionConfig(dtype="float8")
    with pytest.raises(ValueError, match="unknown \\['strenght'\\]"):
        DiffusionConfig.from_dict({"guidance": {"strenght": 1.0}})
    cfg = DiffusionConfig.from_dict({"weights_path": "/m", "guidance": {"strength": 0.5, "guidance_steps": [0, 1]}})
    assert cfg.guidance.guidance_steps == (0, 1) and json.dumps(cfg.to_dict())


# -------------------------------------------------------------------------------------------- priors
def test_flow_tracks_follow_a_translating_pattern():
    rng = np.random.default_rng(0)
    base = (rng.random((40, 40)) * 255).astype(np.uint8)
    base = np.kron(base, np.ones((2, 2), np.uint8))  # 80 x 80 texture
    frames = np.stack([np.repeat(np.roll(base, 2 * i, axis=1)[..., None], 3, -1) for i in range(5)])
    tracks, vis = DefaultPriorEstimators(track_spacing=10).tracks(frames)
    inner = (tracks[:, 0, 0] > 15) & (tracks[:, 0, 0] < 55) & (tracks[:, 0, 1] > 10) & (tracks[:, 0, 1] < 70)
    assert vis[inner].all()
    np.testing.assert_allclose(tracks[inner, -1, 0] - tracks[inner, 0, 0], 8.0, atol=0.5)
    np.testing.assert_allclose(tracks[inner, -1, 1] - tracks[inner, 0, 1], 0.0, atol=0.5)


def test_ground_plane_depth():
    cam = Camera.look_at((0, -4, 2), (0, 0, 0), 64, 48, 60)
    depth = DefaultPriorEstimators().depth(np.zeros((2, 48, 64, 3), np.uint8), cam)
    assert depth.shape == (2, 48, 64)
    # the optical axis hits the ground at the look-at target: camera depth = |eye - target|
    centre = depth[0, 23:25, 31:33].mean()
    assert centre == pytest.approx(np.hypot(4, 2), rel=0.05)
    assert depth[0, 0].max() == 0 or depth[0, 0].min() > depth[0, -1].max()  # farther up the image, or unknown
