"""Tiny randomly initialised CogVideoX components for tests and offline demos.

Nothing here downloads anything: every model is built from a config with random weights (so the
"videos" are noise-like), and the tokenizer is a word-level tokenizer built from a small local
vocabulary with T5's conventions (``</s>`` appended, ``<pad>`` = id 0). Use it to exercise the
diffusion backend's plumbing and guidance on a CPU; never for image quality.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import torch

__all__ = ["TINY_VOCAB", "make_tiny_pipeline", "make_tiny_scheduler", "make_tiny_t5_tokenizer",
           "make_tiny_text_encoder", "make_tiny_tokenizer", "make_tiny_transformer", "make_tiny_vae"]

TINY_VOCAB: tuple[str, ...] = (
    "a", "an", "the", "red", "blue", "green", "yellow", "black", "white", "small", "big", "ball", "bus", "car",
    "boat", "fish", "dog", "cat", "bird", "cube", "motorcycle", "is", "moves", "rolls", "bounces", "flies", "swims",
    "glides", "from", "to", "left", "right", "up", "down", "across", "over", "through", "on", "in", "road", "water",
    "sky", "grass", "table", "street", "quickly", "slowly", "and",
)

TEXT_DIM = 16
MAX_TEXT_LEN = 16


def make_tiny_transformer(seed: int = 0, num_layers: int = 2, sample_size: int = 16, sample_frames: int = 9,
                          patch_size_t: int | None = None) -> Any:
    """A ~35k-parameter `CogVideoXTransformer3DModel` (2 heads x 16, text dim 16, 16 text tokens, patch 2)."""
    from diffusers import CogVideoXTransformer3DModel

    torch.manual_seed(seed)
    return CogVideoXTransformer3DModel(
        num_attention_heads=2, attention_head_dim=16, in_channels=4, out_channels=4, time_embed_dim=8,
        text_embed_dim=TEXT_DIM, num_layers=num_layers, sample_width=sample_size, sample_height=sample_size,
        sample_frames=sample_frames, patch_size=2, patch_size_t=patch_size_t, max_text_seq_length=MAX_TEXT_LEN,
        use_rotary_positional_embeddings=True).eval()


def make_tiny_vae(seed: int = 0) -> Any:
    """A tiny `AutoencoderKLCogVideoX` (4 latent channels, spatial /8, temporal /4)."""
    from diffusers import AutoencoderKLCogVideoX

    torch.manual_seed(seed)
    return AutoencoderKLCogVideoX(block_out_channels=(8, 8, 8, 8), latent_channels=4, layers_per_block=1,
                                  norm_num_groups=2).eval()


def make_tiny_scheduler() -> Any:
    """`CogVideoXDDIMScheduler` with CogVideoX-2b's settings (v-prediction, zero-SNR, trailing)."""
    from diffusers import CogVideoXDDIMScheduler

    return CogVideoXDDIMScheduler(beta_schedule="scaled_linear", prediction_type="v_prediction",
                                  rescale_betas_zero_snr=True, timestep_spacing="trailing", clip_sample=False,
                                  set_alpha_to_one=True, snr_shift_scale=3.0)


def make_tiny_tokenizer(vocab: Sequence[str] = TINY_VOCAB) -> Any:
    """A fast word-level tokenizer (lower-cased, whitespace/punctuation split, ``</s>`` appended)
    wrapped as `transformers.PreTrainedTokenizerFast`, built from a local vocabulary."""
    from tokenizers import Tokenizer, normalizers, pre_tokenizers, processors
    from tokenizers.models import WordLevel
    from transformers import PreTrainedTokenizerFast

    words = ["<pad>", "</s>", "<unk>"] + [w for w in vocab if w not in ("<pad>", "</s>", "<unk>")]
    tok = Tokenizer(WordLevel({w: i for i, w in enumerate(words)}, unk_token="<unk>"))
    tok.normalizer = normalizers.Lowercase()
    tok.pre_tokenizer = pre_tokenizers.Sequence([pre_tokenizers.WhitespaceSplit(), pre_tokenizers.Punctuation()])
    tok.post_processor = processors.TemplateProcessing(single="$A </s>", special_tokens=[("</s>", 1)])
    return PreTrainedTokenizerFast(tokenizer_object=tok, pad_token="<pad>", eos_token="</s>", unk_token="<unk>",
                                   model_max_length=MAX_TEXT_LEN)


def make_tiny_t5_tokenizer(directory: str, vocab_size: int = 40) -> Any:
    """A `T5Tokenizer` from a SentencePiece model trained here on a few sentences, saved in the layout
    of a real CogVideoX ``tokenizer/`` folder (``spiece.model`` + ``tokenizer_config.json``) and
    loaded back with `AutoTokenizer`. Needs the sentencepiece and protobuf packages (as real
    CogVideoX tokenizers do with transformers 5)."""
    import json
    import os

    import sentencepiece as spm
    from transformers import AutoTokenizer

    os.makedirs(directory, exist_ok=True)
    corpus = os.path.join(directory, "corpus.txt")
    with open(corpus, "w") as f:
        f.write("\n".join(["a red ball rolls from right to left", "the bus moves quickly to the right",
                           "a small boat glides on the water", "a black motorcycle is gliding from right to left",
                           "the fish swims through the water"] * 20))
    spm.SentencePieceTrainer.train(input=corpus, model_prefix=os.path.join(directory, "spiece"),
                                   vocab_size=vocab_size, model_type="unigram", pad_id=0, eos_id=1, unk_id=2,
                                   bos_id=-1, character_coverage=1.0, minloglevel=2)
    os.remove(corpus)
    os.remove(os.path.join(directory, "spiece.vocab"))
    with open(os.path.join(directory, "tokenizer_config.json"), "w") as f:
        json.dump({"tokenizer_class": "T5Tokenizer", "model_max_length": 226, "extra_ids": 0, "eos_token": "</s>",
                   "pad_token": "<pad>", "unk_token": "<unk>"}, f)
    return AutoTokenizer.from_pretrained(directory)


def make_tiny_text_encoder(vocab_size: int, seed: int = 0) -> Any:
    """A tiny random `T5EncoderModel` (d_model 16, 1 layer) matching the tiny transformer's text dim."""
    from transformers import T5Config, T5EncoderModel

    torch.manual_seed(seed)
    cfg = T5Config(vocab_size=vocab_size, d_model=TEXT_DIM, d_kv=8, d_ff=32, num_layers=1, num_heads=2,
                   decoder_start_token_id=0, pad_token_id=0, eos_token_id=1)
    return T5EncoderModel(cfg).eval()


def make_tiny_pipeline(seed: int = 0, text_encoder: bool = True) -> Any:
    """A complete tiny `CogVideoXPipeline` (tokenizer and T5 text encoder optional)."""
    from diffusers import CogVideoXPipeline

    tok = make_tiny_tokenizer() if text_encoder else None
    enc = make_tiny_text_encoder(len(tok), seed) if text_encoder else None
    return CogVideoXPipeline(tokenizer=tok, text_encoder=enc, vae=make_tiny_vae(seed),
                             transformer=make_tiny_transformer(seed), scheduler=make_tiny_scheduler())
