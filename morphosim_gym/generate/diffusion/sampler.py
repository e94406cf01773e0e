"""Guided denoising: the paper's Dynamic Control Submodule on a diffusers CogVideoX transformer.

`guided_sample` is the CogVideoX pipeline's denoising loop (classifier-free guidance, DDIM or
DPM scheduler step) with training-free trajectory guidance in the style of Mojito / layout
guidance: at each of the first K denoising steps, `inner_iters` times,

1. run the transformer on the conditional branch only, in autograd mode, with
   `TrajectoryAttnProcessor` recording the video->motion-token attention of the hooked layers
   (the forward stops after the last hooked layer; later layers cannot change those maps);
2. reshape the attention from patch tokens to the latent grid [T_lat, H_lat, W_lat] and compute
   E = mean over targets and latent frames of E_i (`energy.trajectory_loss`);
3. update ``latents <- latents - strength_k * dE/dlatents / rms(dE/dlatents)`` (or the raw
   gradient, ``grad_normalization="none"``);

then take the ordinary scheduler step from the updated latents.
"""

from __future__ import annotations

import contextlib
import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import torch

from .attention import AttentionStore, EarlyExit, install_trajectory_processors, tokens_to_latent_grid
from .energy import frame_energy, in_box_fraction, target_attention, trajectory_loss
from .targets import rasterize_boxes

__all__ = ["GuidanceConfig", "GuidanceTrace", "guided_sample", "cogvideox_rotary_embeddings"]


@dataclass
class GuidanceConfig:
    """Trajectory attention guidance settings.

    Attributes:
        enabled: False samples without guidance (attention can still be recorded to measure E).
        strength: step size of the latent update. With ``grad_normalization="rms"`` it is the
            RMS (per latent element) of each update, in units of the latents (unit-variance noise
            at the start).
        guidance_steps: an int K (guide the first K denoising steps) or explicit step indices.
        inner_iters: gradient steps on E per guided denoising step.
        strength_schedule: ``"constant"``, or ``"linear"`` (decays from `strength` towards 0 over
            the guided steps).
        grad_normalization: ``"rms"`` (divide the gradient by its RMS) or ``"none"``.
        layers: transformer blocks to hook (indices, negative from the end, or processor
            names); None hooks all blocks.
        attention_normalization: ``"text"`` (softmax over text keys: the paper's sum_n A = 1)
            or ``"joint"`` (the model's own softmax over text + video keys).
        frame_reduction: how the loss combines the latent frames' E_i: ``"mean"`` (default;
            E in [0, 1], independent of clip length) or ``"sum"`` (sum_i E_i). Only the gradient's
            scale differs, which ``grad_normalization="rms"`` removes.
        min_energy: stop the inner iterations of a step once the loss is at or below this.
        chunk_size: video queries per chunk when computing attention normalisers.
    """

    enabled: bool = True
    strength: float = 0.1
    guidance_steps: int | tuple[int, ...] = 10
    inner_iters: int = 3
    strength_schedule: str = "constant"
    grad_normalization: str = "rms"
    layers: tuple[int | str, ...] | None = None
    attention_normalization: str = "text"
    frame_reduction: str = "mean"
    min_energy: float = 0.0
    chunk_size: int = 4096

    def __post_init__(self) -> None:
        if not (math.isfinite(float(self.strength)) and float(self.strength) >= 0):
            raise ValueError(f"Expected guidance.strength >= 0, found {self.strength}")
        self.strength = float(self.strength)
        if isinstance(self.guidance_steps, (int, np.integer)) and not isinstance(self.guidance_steps, bool):
            if self.guidance_steps < 0:
                raise ValueError(f"Expected guidance.guidance_steps >= 0, found {self.guidance_steps}")
            self.guidance_steps = int(self.guidance_steps)
        else:
            try:
                steps = tuple(int(s) for s in self.guidance_steps)
            except TypeError:
                raise ValueError(f"Expected guidance.guidance_steps as an int or a list of step indices, found "
                                 f"{self.guidance_steps!r}") from None
            if any(s < 0 for s in steps):
                raise ValueError(f"Expected guidance.guidance_steps indices >= 0, found {list(steps)}")
            self.guidance_steps = tuple(sorted(set(steps)))
        if int(self.inner_iters) < 1:
            raise ValueError(f"Expected guidance.inner_iters >= 1, found {self.inner_iters}")
        self.inner_iters = int(self.inner_iters)
        if self.strength_schedule not in ("constant", "linear"):
            raise ValueError(f"Expected guidance.strength_schedule 'constant' or 'linear', found "
                             f"{self.strength_schedule!r}")
        if self.grad_normalization not in ("rms", "none"):
            raise ValueError(f"Expected guidance.grad_normalization 'rms' or 'none', found {self.grad_normalization!r}")
        if self.attention_normalization not in ("text", "joint"):
            raise ValueError(f"Expected guidance.attention_normalization 'text' or 'joint', found "
                             f"{self.attention_normalization!r}")
        if self.frame_reduction not in ("mean", "sum"):
            raise ValueError(f"Expected guidance.frame_reduction 'mean' or 'sum', found {self.frame_reduction!r}")
        if self.layers is not None:
            self.layers = tuple(self.layers)
        if not float(self.min_energy) >= 0.0:
            raise ValueError(f"Expected guidance.min_energy >= 0, found {self.min_energy}")
        if int(self.chunk_size) < 1:
            raise ValueError(f"Expected guidance.chunk_size >= 1, found {self.chunk_size}")

    def step_strengths(self, num_inference_steps: int) -> dict[int, float]:
        """Denoising step index -> update strength, for the guided steps only."""
        if not self.enabled or self.strength == 0:
            return {}
        if isinstance(self.guidance_steps, int):
            steps = list(range(min(self.guidance_steps, num_inference_steps)))
        else:
            steps = [s for s in self.guidance_steps if s < num_inference_steps]
        n = len(steps)
        if self.strength_schedule == "linear":
            return {s: self.strength * (1.0 - k / n) for k, s in enumerate(steps)}
        return {s: self.strength for s in steps}

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly copy."""
        d = asdict(self)
        d["guidance_steps"] = d["guidance_steps"] if isinstance(d["guidance_steps"], int) else list(
            d["guidance_steps"])
        d["layers"] = None if d["layers"] is None else list(d["layers"])
        return d


@dataclass
class GuidanceTrace:
    """Measurements of one sampling run (all from the conditional branch of batch row 0).

    Attributes:
        timesteps: the scheduler's timesteps.
        energy: per denoising step, E (mean over targets and latent frames) of the attention at
            that step's classifier-free-guidance forward (after any guidance updates).
        in_box: per step, the attention mass fraction inside the boxes (mean over targets, frames).
        frame_energy: [n_steps, N_targets, T_lat] E_i per step.
        guidance: one dict per inner guidance iteration: step, iter, energy (the loss before the
            update, reduced over frames as `GuidanceConfig.frame_reduction` says),
            grad_rms, strength.
        attention: [N_targets, T_lat, H_lat, W_lat] attention of the last step on the latent grid.
        attention_mean: the same averaged over all steps.
        box_masks: [N_targets, T_lat, H_lat, W_lat] the rasterised boxes.
    """

    timesteps: list[int] = field(default_factory=list)
    energy: list[float] = field(default_factory=list)
    in_box: list[float] = field(default_factory=list)
    frame_energy: np.ndarray | None = None
    guidance: list[dict[str, float]] = field(default_factory=list)
    attention: np.ndarray | None = None
    attention_mean: np.ndarray | None = None
    box_masks: np.ndarray | None = None

    def summary(self) -> dict[str, Any]:
        """JSON-friendly numbers (no maps)."""
        return {"timesteps": self.timesteps, "energy": self.energy, "in_box": self.in_box,
                "mean_energy": float(np.mean(self.energy)) if self.energy else None,
                "mean_in_box": float(np.mean(self.in_box)) if self.in_box else None,
                "guidance": self.guidance}


def cogvideox_rotary_embeddings(transformer: Any, latent_frames: int, latent_height: int, latent_width: int,
                                device: torch.device | str) -> tuple[torch.Tensor, torch.Tensor] | None:
    """RoPE tables exactly as `CogVideoXPipeline._prepare_rotary_positional_embeddings` builds them,
    from the latent grid size (None when the transformer does not use rotary embeddings)."""
    cfg = transformer.config
    if not cfg.use_rotary_positional_embeddings:
        return None
    from diffusers.models.embeddings import get_3d_rotary_pos_embed
    from diffusers.pipelines.cogvideo.pipeline_cogvideox import get_resize_crop_region_for_grid

    p, p_t = cfg.patch_size, cfg.patch_size_t
    grid_h, grid_w = latent_height // p, latent_width // p
    base_w, base_h = cfg.sample_width // p, cfg.sample_height // p
    if p_t is None:
        crops = get_resize_crop_region_for_grid((grid_h, grid_w), base_w, base_h)
        return get_3d_rotary_pos_embed(embed_dim=cfg.attention_head_dim, crops_coords=crops,
                                       grid_size=(grid_h, grid_w), temporal_size=latent_frames, device=device)
    return get_3d_rotary_pos_embed(embed_dim=cfg.attention_head_dim, crops_coords=None, grid_size=(grid_h, grid_w),
                                   temporal_size=(latent_frames + p_t - 1) // p_t, grid_type="slice",
                                   max_size=(base_h, base_w), device=device)


def _is_dpm(scheduler: Any) -> bool:
    return type(scheduler).__name__ == "CogVideoXDPMScheduler"


def guided_sample(
    transformer: Any,
    scheduler: Any,
    latents: torch.Tensor,  # [B, T_lat, C, H_lat, W_lat]
    prompt_embeds: torch.Tensor,  # [B, L, D_text]
    negative_prompt_embeds: torch.Tensor | None = None,  # [B, L, D_text]
    token_indices: Sequence[Sequence[int]] = (),
    boxes_latent: Sequence[np.ndarray] = (),
    config: GuidanceConfig | None = None,
    *,
    num_inference_steps: int = 50,
    guidance_scale: float = 6.0,
    use_dynamic_cfg: bool = False,
    generator: torch.Generator | None = None,
    eta: float = 0.0,
    record: bool = False,
    callback: Callable[[int, int, torch.Tensor], None] | None = None,
) -> torch.Tensor | tuple[torch.Tensor, GuidanceTrace]:
    """Sample CogVideoX latents with trajectory attention guidance.

    Works with any diffusers `CogVideoXTransformer3DModel` (1.0: patch_size_t None; 1.5:
    patch_size_t = 2, T_lat must then be a multiple of it) and a CogVideoX DDIM / DPM scheduler
    (or any scheduler whose ``step(noise_pred, t, latents)`` follows diffusers' convention).
    Model dtype (fp32 / bf16 / fp16) and device follow the transformer; latents, guidance
    gradients and the scheduler step are kept in float32.

    Memory: a guided forward keeps autograd state only up to the last hooked layer (the forward
    stops there), and attention normalisers are checkpointed per chunk of queries, so the cost is
    about one training-style forward/backward through the hooked prefix of the model at batch 1.
    On large models hook fewer / earlier layers (`GuidanceConfig.layers`) to cut it. Gradient
    checkpointing of the transformer is not used during the run.

    Args:
        transformer: the denoiser; its attention processors are swapped for the run and restored.
        scheduler: the noise scheduler (its timesteps are reset here).
        latents: [B, T_lat, C, H_lat, W_lat] initial noise (multiplied by
            ``scheduler.init_noise_sigma`` here, as the pipeline does).
        prompt_embeds: [B, L, D_text] text embeddings of the prompt.
        negative_prompt_embeds: [B, L, D_text] for classifier-free guidance (needed when
            guidance_scale > 1).
        token_indices: per target, the text-token indices of its motion tokens.
        boxes_latent: per target, [T_lat, 4] normalised boxes per latent frame.
        config: guidance settings (default `GuidanceConfig()`).
        num_inference_steps, guidance_scale, use_dynamic_cfg, generator, eta: as in
            `CogVideoXPipeline.__call__`.
        record: also measure the motion-token attention at every step and return a
            `GuidanceTrace` (cheap: K columns of attention per hooked layer, no gradients).
        callback: called as ``callback(step, timestep, latents)`` after every scheduler step.

    Returns:
        [B, T_lat, C, H_lat, W_lat] denoised latents (float32), and the trace when `record`.

    Examples:
        >>> latents = guided_sample(transformer, scheduler, noise, embeds, neg, [[3]],
        ...                         [np.tile([0.5, 0.25, 0.75, 0.75], (3, 1))],
        ...                         GuidanceConfig(strength=0.5, guidance_steps=4), num_inference_steps=8)
        ...                         # doctest: +SKIP
    """
    cfg = config or GuidanceConfig()
    if latents.ndim != 5:
        raise ValueError(f"Expected latents of shape [B, T_lat, C, H_lat, W_lat], found {tuple(latents.shape)}")
    bsz, t_lat, _, h_lat, w_lat = latents.shape
    if prompt_embeds.ndim != 3 or prompt_embeds.shape[0] != bsz:
        raise ValueError(f"Expected prompt_embeds of shape [{bsz}, L, D], found {tuple(prompt_embeds.shape)}")
    token_indices = [list(map(int, t)) for t in token_indices]
    if len(token_indices) != len(boxes_latent):
        raise ValueError(f"Expected one box sequence per target, found {len(token_indices)} token lists and "
                         f"{len(boxes_latent)} box sequences")
    if any(not t for t in token_indices):
        raise ValueError("Expected at least one token index per target, found an empty list")
    do_cfg = guidance_scale > 1.0
    if do_cfg and negative_prompt_embeds is None:
        raise ValueError("Expected negative_prompt_embeds when guidance_scale > 1, found None")

    param = next(transformer.parameters())
    device, dtype = param.device, param.dtype
    p, p_t = transformer.config.patch_size, transformer.config.patch_size_t
    if p_t is not None and t_lat % p_t:
        raise ValueError(f"Expected T_lat divisible by patch_size_t={p_t}, found {t_lat}")

    # targets: unique recorded token columns, groups of positions per target, box masks [N, T, H, W]
    flat = sorted({i for t in token_indices for i in t})
    groups = [[flat.index(i) for i in t] for t in token_indices]
    masks_np = np.stack([rasterize_boxes(np.asarray(b), h_lat, w_lat) for b in boxes_latent]) if flat else None
    if masks_np is not None and masks_np.shape[1] != t_lat:
        raise ValueError(f"Expected {t_lat} latent-frame boxes per target, found {masks_np.shape[1]}")
    masks = None if masks_np is None else torch.from_numpy(masks_np).to(device)

    embeds = prompt_embeds.to(device=device, dtype=dtype)
    cond_uncond = torch.cat([negative_prompt_embeds.to(device=device, dtype=dtype), embeds]) if do_cfg else embeds
    rope = cogvideox_rotary_embeddings(transformer, t_lat, h_lat, w_lat, device)

    scheduler.set_timesteps(num_inference_steps, device=device)
    timesteps = scheduler.timesteps
    x = latents.to(device=device, dtype=torch.float32) * scheduler.init_noise_sigma
    step_params = set(inspect.signature(scheduler.step).parameters)
    extra = {k: v for k, v in (("eta", eta), ("generator", generator)) if k in step_params}
    strengths = cfg.step_strengths(len(timesteps)) if flat else {}

    store = AttentionStore(token_indices=flat, normalization=cfg.attention_normalization,
                           chunk_size=cfg.chunk_size)
    trace = GuidanceTrace(timesteps=[int(t) for t in timesteps])
    fe_steps: list[np.ndarray] = []
    attn_sum: np.ndarray | None = None

    def attention_grid() -> torch.Tensor:  # [B', N_targets, T, H, W]
        g = tokens_to_latent_grid(store.mean_map(), t_lat, h_lat, w_lat, p, p_t)
        return target_attention(g, groups)

    def forward(inp: torch.Tensor, emb: torch.Tensor, t: torch.Tensor) -> torch.Tensor | None:
        try:
            return transformer(hidden_states=inp, encoder_hidden_states=emb, timestep=t.expand(inp.shape[0]),
                               image_rotary_emb=rope, return_dict=False)[0]
        except EarlyExit:
            return None

    guidance_scale_now = guidance_scale
    old_pred_original_sample = None
    # gradient checkpointing would re-run the hooked processors during backward with recording off
    # (a different set of saved tensors), so it is switched off for the run and restored afterwards
    checkpointing = bool(getattr(transformer, "gradient_checkpointing", False))
    if checkpointing:
        transformer.gradient_checkpointing = False
    with contextlib.ExitStack() as restore:
        if checkpointing:
            restore.callback(setattr, transformer, "gradient_checkpointing", True)
        names = restore.enter_context(install_trajectory_processors(transformer, store, cfg.layers))
        for i, t in enumerate(timesteps):
            # --- trajectory guidance: gradient steps on E w.r.t. the latents
            if i in strengths:
                for j in range(cfg.inner_iters):
                    xg = x.detach().requires_grad_(True)
                    store.reset()
                    store.recording, store.batch_rows, store.stop_after = True, None, names[-1]
                    with torch.enable_grad():
                        forward(scheduler.scale_model_input(xg, t).to(dtype), embeds, t)
                        loss = trajectory_loss(attention_grid(), masks, cfg.frame_reduction)
                    store.recording = False
                    e = float(loss.detach())
                    if e <= cfg.min_energy:
                        trace.guidance.append({"step": i, "iter": j, "energy": e, "grad_rms": 0.0, "strength": 0.0})
                        break
                    (grad,) = torch.autograd.grad(loss, xg)
                    grad_rms = float(grad.pow(2).mean().sqrt())
                    if cfg.grad_normalization == "rms":
                        grad = grad / max(grad_rms, 1e-20)
                    x = (xg - strengths[i] * grad).detach()
                    trace.guidance.append({"step": i, "iter": j, "energy": e, "grad_rms": grad_rms,
                                           "strength": strengths[i]})
                    del loss, grad, xg
            # --- the ordinary denoising step (no gradients)
            store.reset()
            store.recording = bool(record and flat)
            store.batch_rows = [bsz] if do_cfg else [0]
            store.stop_after = None
            with torch.no_grad():
                inp = torch.cat([x, x]) if do_cfg else x
                noise_pred = forward(scheduler.scale_model_input(inp, t).to(dtype), cond_uncond, t).float()
                if store.recording:
                    grid = attention_grid()[0]  # [N, T, H, W]
                    fe = frame_energy(grid, masks)
                    trace.energy.append(float(fe.mean()))
                    trace.in_box.append(float(in_box_fraction(grid, masks).mean()))
                    fe_steps.append(fe.cpu().numpy())
                    g_np = grid.cpu().numpy()
                    attn_sum = g_np if attn_sum is None else attn_sum + g_np
                    trace.attention = g_np
            store.recording = False
            if use_dynamic_cfg:  # as CogVideoXPipeline does
                guidance_scale_now = 1 + guidance_scale * (
                    (1 - math.cos(math.pi * ((num_inference_steps - t.item()) / num_inference_steps) ** 5.0)) / 2)
            if do_cfg:
                uncond, cond = noise_pred.chunk(2)
                noise_pred = uncond + guidance_scale_now * (cond - uncond)
            if _is_dpm(scheduler):
                x, old_pred_original_sample = scheduler.step(noise_pred, old_pred_original_sample, t,
                                                             timesteps[i - 1] if i > 0 else None, x, **extra,
                                                             return_dict=False)
            else:
                x = scheduler.step(noise_pred, t, x, **extra, return_dict=False)[0]
            x = x.float()
            if callback is not None:
                callback(i, int(t), x)
    if not record:
        return x
    if fe_steps:
        trace.frame_energy = np.stack(fe_steps)
        trace.attention_mean = attn_sum / len(fe_steps)
    trace.box_masks = masks_np
    return x, trace
