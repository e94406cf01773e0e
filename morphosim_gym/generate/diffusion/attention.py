"""Attention processors that expose the text-to-video attention of the motion tokens.

CogVideoX (and other MM-DiT video models) run *joint* attention: the text tokens and the video
patch tokens are concatenated (text FIRST, then video) and attend to each other in one softmax.
`TrajectoryAttnProcessor` is a drop-in replacement for diffusers' `CogVideoXAttnProcessor2_0`:
its output is the same fused scaled-dot-product attention, and when its `AttentionStore` is
recording it also computes, for every video query token u, the attention probability to the
recorded text key tokens n (the paper's A_{u,n}), averaged over heads.

Normalisation (``AttentionStore.normalization``):

- ``"text"`` (default, the paper's convention ``sum_n A_{u,n} = 1``): softmax of the video
  query's scores over the text keys only, i.e. the cross-attention part of the joint attention.
- ``"joint"``: the probability the model actually uses, softmax over all text + video keys.

Both are computed chunk by chunk over queries; when gradients are on, each chunk's
log-normaliser is checkpointed so only [B, heads, N_video] numbers stay alive per layer (not the
N x N attention matrix).

Token order (checked against diffusers 0.42.1 `CogVideoXPatchEmbed.forward`): video tokens come
in (t, h, w) order, t slowest, after patchification by (p_t, p, p) (p_t = 1 for CogVideoX 1.0),
so the video part of the sequence reshapes to [T_lat / p_t, H_lat / p, W_lat / p];
`tokens_to_latent_grid` does this and repeats every token over the p_t x p x p latent cells it
came from, restoring the latent grid "before patchification" as the paper describes.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import torch
import torch.nn.functional as F
from torch.utils.checkpoint import checkpoint

__all__ = [
    "AttentionStore",
    "TrajectoryAttnProcessor",
    "EarlyExit",
    "attention_layer_names",
    "install_trajectory_processors",
    "tokens_to_latent_grid",
]


# cap on the scores materialised at once when computing normalisers (64 Mi elements = 256 MiB in
# float32): with "joint" normalisation on CogVideoX-2b (30 heads, ~17.8k keys) that is ~125 queries
_MAX_CHUNK_ELEMENTS = 1 << 26


class EarlyExit(Exception):
    """Raised by the processor of the last recorded layer when ``AttentionStore.stop_after`` is
    set: the guidance forward only needs attention maps, not the noise prediction."""


@dataclass
class AttentionStore:
    """What to record and what was recorded.

    Attributes:
        token_indices: text-token indices n whose attention columns are kept (K of them).
        normalization: ``"text"`` or ``"joint"`` (see the module docstring).
        batch_rows: batch rows to keep (e.g. ``[1]`` for the conditional half of a CFG batch);
            None keeps all.
        chunk_size: at most this many video queries per chunk when computing normalisers (chunks
            are also capped at 64 Mi score elements).
        recording: the processors record only while this is True.
        stop_after: layer name after whose recording `EarlyExit` is raised (None: never).
        maps: layer name -> [B', N_video, K] float32 head-averaged attention of the last forward.
    """

    token_indices: Sequence[int] = ()
    normalization: str = "text"
    batch_rows: Sequence[int] | None = None
    chunk_size: int = 4096
    recording: bool = False
    stop_after: str | None = None
    maps: dict[str, torch.Tensor] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.normalization not in ("text", "joint"):
            raise ValueError(f"Expected normalization 'text' or 'joint', found {self.normalization!r}")
        if int(self.chunk_size) < 1:
            raise ValueError(f"Expected chunk_size >= 1, found {self.chunk_size}")

    def reset(self) -> None:
        """Forget the recorded maps."""
        self.maps = {}

    def mean_map(self) -> torch.Tensor:
        """[B', N_video, K] attention averaged over the recorded layers."""
        if not self.maps:
            raise RuntimeError("No attention was recorded: was the transformer run with the store recording?")
        return torch.stack(list(self.maps.values())).mean(0)


def _log_normaliser(q: torch.Tensor, k: torch.Tensor, scale: float, bias: torch.Tensor | None) -> torch.Tensor:
    s = torch.matmul(q, k.transpose(-1, -2)) * scale
    if bias is not None:
        s = s + bias
    return torch.logsumexp(s.float(), dim=-1)


class TrajectoryAttnProcessor:
    """Drop-in for diffusers' `CogVideoXAttnProcessor2_0` that records motion-token attention.

    Mirrors `CogVideoXAttnProcessor2_0.__call__` of diffusers 0.42.1 line for line (QK norms,
    rotary embedding on the video part, fused SDPA, output projection, text/video split); the
    only change is that RoPE is applied out of place (`torch.cat`), which is numerically the same
    and keeps autograd simple. With recording off it costs nothing extra.
    """

    def __init__(self, name: str, store: AttentionStore) -> None:
        self.name = name
        self.store = store

    def __call__(
        self,
        attn: Any,
        hidden_states: torch.Tensor,  # [B, N_video, D]
        encoder_hidden_states: torch.Tensor,  # [B, L_text, D]
        attention_mask: torch.Tensor | None = None,
        image_rotary_emb: tuple[torch.Tensor, torch.Tensor] | None = None,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        text_len = encoder_hidden_states.size(1)
        hidden_states = torch.cat([encoder_hidden_states, hidden_states], dim=1)
        batch_size, seq_len, _ = hidden_states.shape
        if attention_mask is not None:
            attention_mask = attn.prepare_attention_mask(attention_mask, seq_len, batch_size)
            attention_mask = attention_mask.view(batch_size, attn.heads, -1, attention_mask.shape[-1])

        query = attn.to_q(hidden_states)
        key = attn.to_k(hidden_states)
        value = attn.to_v(hidden_states)
        head_dim = key.shape[-1] // attn.heads
        query = query.view(batch_size, -1, attn.heads, head_dim).transpose(1, 2)
        key = key.view(batch_size, -1, attn.heads, head_dim).transpose(1, 2)
        value = value.view(batch_size, -1, attn.heads, head_dim).transpose(1, 2)
        if attn.norm_q is not None:
            query = attn.norm_q(query)
        if attn.norm_k is not None:
            key = attn.norm_k(key)
        if image_rotary_emb is not None:
            from diffusers.models.embeddings import apply_rotary_emb

            query = torch.cat([query[:, :, :text_len], apply_rotary_emb(query[:, :, text_len:], image_rotary_emb)], 2)
            if not attn.is_cross_attention:
                key = torch.cat([key[:, :, :text_len], apply_rotary_emb(key[:, :, text_len:], image_rotary_emb)], 2)

        out = F.scaled_dot_product_attention(query, key, value, attn_mask=attention_mask, dropout_p=0.0,
                                             is_causal=False)

        store = self.store
        if store.recording and store.token_indices:
            self._record(query, key, text_len, attn.scale, attention_mask)

        out = out.transpose(1, 2).reshape(batch_size, -1, attn.heads * head_dim)
        out = attn.to_out[0](out)
        out = attn.to_out[1](out)
        encoder_out, out = out.split([text_len, out.size(1) - text_len], dim=1)
        if store.recording and store.stop_after == self.name:
            raise EarlyExit(self.name)
        return out, encoder_out

    def _record(self, query: torch.Tensor, key: torch.Tensor, text_len: int, scale: float,
                attention_mask: torch.Tensor | None) -> None:
        store = self.store
        rows = None if store.batch_rows is None else torch.as_tensor(list(store.batch_rows), device=query.device)
        q = query[:, :, text_len:]  # [B, h, Nv, d] video queries
        if rows is not None:
            q = q.index_select(0, rows)
        keys = key[:, :, :text_len] if store.normalization == "text" else key  # [B, h, S', d]
        if rows is not None:
            keys = keys.index_select(0, rows)
        bias = None
        if attention_mask is not None:
            bias = attention_mask[:, :, text_len:, :keys.shape[2]]
            if bias.dtype == torch.bool:
                bias = torch.zeros_like(bias, dtype=q.dtype).masked_fill(~bias, float("-inf"))
            if rows is not None:
                bias = bias.index_select(0, rows)
        idx = torch.as_tensor(list(store.token_indices), device=q.device)
        if int(idx.max()) >= text_len:
            raise ValueError(f"Expected token indices < {text_len} (the text length), found {int(idx.max())}")
        k_sel = key[:, :, :text_len].index_select(2, idx)
        if rows is not None:
            k_sel = k_sel.index_select(0, rows)
        grad = torch.is_grad_enabled() and (q.requires_grad or keys.requires_grad)
        # queries per chunk: at most chunk_size, and at most _MAX_CHUNK_ELEMENTS scores per chunk
        per_query = q.shape[0] * q.shape[1] * keys.shape[2]
        chunk = max(1, min(int(store.chunk_size), _MAX_CHUNK_ELEMENTS // per_query))
        lse = []
        for s in range(0, q.shape[2], chunk):
            qc = q[:, :, s:s + chunk]
            bc = None if bias is None else bias[:, :, s:s + chunk]
            if grad:
                lse.append(checkpoint(_log_normaliser, qc, keys, scale, bc, use_reentrant=False))
            else:
                lse.append(_log_normaliser(qc, keys, scale, bc))
        log_z = torch.cat(lse, dim=2)  # [B', h, Nv]
        s_sel = torch.matmul(q, k_sel.transpose(-1, -2)).float() * scale  # [B', h, Nv, K]
        if bias is not None:
            s_sel = s_sel + bias.index_select(3, idx).float()
        probs = torch.exp(s_sel - log_z[..., None])
        store.maps[self.name] = probs.mean(dim=1)  # [B', Nv, K]


def attention_layer_names(transformer: Any, layers: Sequence[int | str] | None = None) -> list[str]:
    """Processor names (``transformer_blocks.N.attn1.processor``) of the blocks to hook.

    Args:
        transformer: a diffusers CogVideoX transformer.
        layers: None for all blocks, or block indices (negative counts from the end) or full
            processor names.
    """
    names = [n for n in transformer.attn_processors if n.startswith("transformer_blocks.")]
    if not names:
        raise ValueError(f"Expected a transformer with transformer_blocks.N.attn1 processors, found "
                         f"{list(transformer.attn_processors)[:4]}")
    names.sort(key=lambda n: int(n.split(".")[1]))
    if layers is None:
        return names
    out = []
    for layer in layers:
        if isinstance(layer, str):
            if layer not in names:
                raise ValueError(f"Expected a processor name among {names[:3]}..., found {layer!r}")
            out.append(layer)
        else:
            i = int(layer)
            if not -len(names) <= i < len(names):
                raise ValueError(f"Expected layer indices in [-{len(names)}, {len(names)}), found {i}")
            out.append(names[i])
    if not out:
        raise ValueError("Expected at least one layer to hook, found an empty list")
    return sorted(set(out), key=lambda n: int(n.split(".")[1]))


@contextlib.contextmanager
def install_trajectory_processors(transformer: Any, store: AttentionStore,
                                  layers: Sequence[int | str] | None = None) -> Iterator[list[str]]:
    """Swap `TrajectoryAttnProcessor` into the chosen blocks; restore the originals on exit.

    Yields the hooked processor names, in block order.
    """
    names = attention_layer_names(transformer, layers)
    original = dict(transformer.attn_processors)
    procs = dict(original)
    for n in names:
        procs[n] = TrajectoryAttnProcessor(n, store)
    transformer.set_attn_processor(procs)
    try:
        yield names
    finally:
        transformer.set_attn_processor(original)


def tokens_to_latent_grid(maps: torch.Tensor, latent_frames: int, latent_height: int, latent_width: int,
                          patch_size: int, patch_size_t: int | None = None) -> torch.Tensor:
    """Reshape per-video-token values back to the latent grid before patchification.

    Args:
        maps: [..., N_video, K] values per video token (in the transformer's (t, h, w) order).
        latent_frames, latent_height, latent_width: T_lat, H_lat, W_lat of the latents fed to the
            transformer (T_lat including any CogVideoX 1.5 padding frames).
        patch_size: p (spatial); patch_size_t: p_t (None or 1 for CogVideoX 1.0).

    Returns:
        [..., K, T_lat, H_lat, W_lat]: each token's value repeated over its p_t x p x p cells.
    """
    pt = int(patch_size_t or 1)
    p = int(patch_size)
    t, h, w = latent_frames // pt, latent_height // p, latent_width // p
    if latent_frames % pt or latent_height % p or latent_width % p:
        raise ValueError(f"Expected a latent grid divisible by the patch size ({pt}, {p}, {p}), found "
                         f"({latent_frames}, {latent_height}, {latent_width})")
    if maps.shape[-2] != t * h * w:
        raise ValueError(f"Expected {t * h * w} video tokens ({t} x {h} x {w}), found {maps.shape[-2]}")
    g = maps.movedim(-1, -2).reshape(*maps.shape[:-2], maps.shape[-1], t, h, w)
    return g.repeat_interleave(pt, dim=-3).repeat_interleave(p, dim=-2).repeat_interleave(p, dim=-1)
