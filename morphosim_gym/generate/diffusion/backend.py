"""`DiffusionClipBackend`: a CogVideoX text-to-video pipeline with trajectory attention guidance,
behind the same `GeneratedClip` contract as the procedural generator.

Weights are never downloaded: `DiffusionConfig.weights_path` must be a local directory holding a
diffusers CogVideoX pipeline (``model_index.json`` plus ``transformer/``, ``vae/``,
``scheduler/`` and, unless prompt embeddings are passed in, ``tokenizer/`` and
``text_encoder/``), e.g. one saved with ``CogVideoXPipeline.save_pretrained``.

The generated video has no camera of its own: it is treated as seen by ONE FIXED pinhole camera
(every frame gets the same `Camera`): by default `DEFAULT_FOV_Y_DEG` vertical field of view,
placed at `DEFAULT_EYE` looking at `DEFAULT_TARGET` (world z-up, metres), the same framing as the
architecture's example camera. Pass `camera=` to `generate` to choose another (it is resized to
the clip's resolution). The pose is a convention, not an estimate.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import BackendUnavailableError
from ...scene.camera import Camera
from ...scene.clip import GeneratedClip
from .priors import DefaultPriorEstimators, PriorEstimators
from .sampler import GuidanceConfig, guided_sample
from .targets import GuidanceTarget, boxes_to_latent_frames, token_indices_for_words

__all__ = ["DiffusionConfig", "DiffusionClipBackend", "DEFAULT_FOV_Y_DEG", "DEFAULT_EYE", "DEFAULT_TARGET",
           "PIP_HINT"]

DEFAULT_FOV_Y_DEG = 60.0
DEFAULT_EYE = (0.0, -4.0, 2.0)
DEFAULT_TARGET = (0.0, 0.0, 0.5)
PIP_HINT = 'pip install "morphosim-gym[diffusion]"  (diffusers, transformers)'
_DTYPES = ("auto", "float32", "bfloat16", "float16")
_REQUIRED_PARTS = ("transformer", "vae", "scheduler")


@dataclass
class DiffusionConfig:
    """Settings of the diffusion clip backend.

    Attributes:
        weights_path: local directory of a diffusers CogVideoX pipeline (never downloaded).
        device: "cuda", "cpu", "cuda:1"...; None picks "cuda" when available, else "cpu".
        dtype: "auto" (bfloat16 on CUDA, float32 on CPU), "float32", "bfloat16" or "float16".
        num_inference_steps: denoising steps.
        guidance_scale: classifier-free guidance weight (<= 1 disables CFG).
        use_dynamic_cfg: CogVideoX's cosine CFG schedule.
        height, width: frame size in pixels (multiples of VAE factor x patch size, 16 for CogVideoX).
        num_frames: video frames, 1 + r k for the VAE's temporal compression r (49 for CogVideoX).
        fps: frame rate written into the clip (CogVideoX 1.0 was trained at 8 fps).
        negative_prompt: text for the unconditional branch.
        max_sequence_length: text tokens (None: the transformer's max_text_seq_length).
        fov_y_deg, camera_eye, camera_target: the default fixed camera (see the module docstring).
            `SimConfig(generator="diffusion")` (`planned.PlannedDiffusionGenerator`) plans with
            fov_y_deg and uses the planner's camera instead of camera_eye / camera_target.
        vae_tiling: decode in tiles (saves GPU memory at 720p).
        guidance: trajectory attention guidance (`GuidanceConfig`).
    """

    weights_path: str | Path | None = None
    device: str | None = None
    dtype: str = "auto"
    num_inference_steps: int = 50
    guidance_scale: float = 6.0
    use_dynamic_cfg: bool = False
    height: int = 480
    width: int = 720
    num_frames: int = 49
    fps: float = 8.0
    negative_prompt: str = ""
    max_sequence_length: int | None = None
    fov_y_deg: float = DEFAULT_FOV_Y_DEG
    camera_eye: tuple[float, float, float] = DEFAULT_EYE
    camera_target: tuple[float, float, float] = DEFAULT_TARGET
    vae_tiling: bool = False
    guidance: GuidanceConfig = field(default_factory=GuidanceConfig)

    def __post_init__(self) -> None:
        if self.dtype not in _DTYPES:
            raise ValueError(f"Expected diffusion.dtype in {list(_DTYPES)}, found {self.dtype!r}")
        for name in ("num_inference_steps", "height", "width", "num_frames"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"Expected diffusion.{name} as a positive integer, found {v!r}")
            setattr(self, name, int(v))
        for name, low in (("guidance_scale", 0.0), ("fps", None), ("fov_y_deg", None)):
            v = float(getattr(self, name))
            if not math.isfinite(v) or (v < low if low is not None else v <= 0):
                want = f">= {low}" if low is not None else "> 0"
                raise ValueError(f"Expected diffusion.{name} as a finite number {want}, found {getattr(self, name)!r}")
            setattr(self, name, v)
        if self.fov_y_deg >= 180:
            raise ValueError(f"Expected diffusion.fov_y_deg in (0, 180), found {self.fov_y_deg}")
        if self.max_sequence_length is not None and int(self.max_sequence_length) < 1:
            raise ValueError(f"Expected diffusion.max_sequence_length >= 1, found {self.max_sequence_length}")
        if self.weights_path is not None:
            self.weights_path = Path(self.weights_path).expanduser()
        if isinstance(self.guidance, Mapping):
            self.guidance = _guidance_from_dict(self.guidance)
        if not isinstance(self.guidance, GuidanceConfig):
            raise ValueError(f"Expected diffusion.guidance as a GuidanceConfig or a mapping, found "
                             f"{type(self.guidance).__name__}")
        for name in ("camera_eye", "camera_target"):
            v = np.asarray(getattr(self, name), dtype=np.float64)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"Expected diffusion.{name} as 3 finite numbers, found {getattr(self, name)!r}")
            setattr(self, name, tuple(float(x) for x in v))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> DiffusionConfig:
        """From a (YAML) mapping; unknown keys raise a ValueError naming them."""
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - known)
        if unknown:
            raise ValueError(f"Expected diffusion keys among {sorted(known)}, found unknown {unknown}")
        return cls(**dict(d))

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly copy."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        d["weights_path"] = None if self.weights_path is None else str(self.weights_path)
        d["camera_eye"], d["camera_target"] = list(self.camera_eye), list(self.camera_target)
        d["guidance"] = self.guidance.to_dict()
        return d


def _guidance_from_dict(d: Mapping[str, Any]) -> GuidanceConfig:
    known = {f.name for f in dataclasses.fields(GuidanceConfig)}
    unknown = sorted(set(d) - known)
    if unknown:
        raise ValueError(f"Expected diffusion.guidance keys among {sorted(known)}, found unknown {unknown}")
    return GuidanceConfig(**dict(d))


def check_weights_path(path: Path | None) -> Path:
    """Validate a local diffusers pipeline directory without loading it; raise
    `BackendUnavailableError` naming the path and what is missing."""
    if path is None:
        raise BackendUnavailableError(
            "The diffusion backend needs local model weights: set diffusion.weights_path to a directory "
            "holding a diffusers CogVideoX pipeline (saved with CogVideoXPipeline.save_pretrained); "
            "weights are never downloaded at run time")
    p = Path(path)
    if not p.exists():
        raise BackendUnavailableError(f"Diffusion weights path {str(p)!r} does not exist; expected a local "
                                      f"directory holding a diffusers CogVideoX pipeline (model_index.json, "
                                      f"transformer/, vae/, scheduler/)")
    if not p.is_dir():
        raise BackendUnavailableError(f"Diffusion weights path {str(p)!r} is not a directory; expected a "
                                      f"diffusers CogVideoX pipeline directory")
    index = p / "model_index.json"
    if not index.is_file():
        raise BackendUnavailableError(f"Diffusion weights path {str(p)!r} has no model_index.json; expected a "
                                      f"diffusers CogVideoX pipeline directory")
    try:
        meta = json.loads(index.read_text())
    except (OSError, ValueError) as e:
        raise BackendUnavailableError(f"Diffusion weights path {str(p)!r}: model_index.json is unreadable "
                                      f"({e})") from e
    cls_name = str(meta.get("_class_name", ""))
    if not cls_name.startswith("CogVideoX"):
        raise BackendUnavailableError(f"Diffusion weights path {str(p)!r} holds a {cls_name or 'unknown'} "
                                      f"pipeline; expected a CogVideoX text-to-video pipeline")
    missing = [part for part in _REQUIRED_PARTS if not (p / part).is_dir()]
    if missing:
        raise BackendUnavailableError(f"Diffusion weights path {str(p)!r} lacks {missing}; expected the "
                                      f"subfolders {list(_REQUIRED_PARTS)} of a diffusers CogVideoX pipeline")
    return p


def _import_diffusers() -> Any:
    try:
        import diffusers
    except ImportError as e:
        raise BackendUnavailableError(
            f"The diffusion backend needs diffusers, which is not installed: {PIP_HINT}") from e
    return diffusers


class DiffusionClipBackend:
    """Text + trajectory boxes -> `GeneratedClip`, with a CogVideoX model and the paper's Dynamic
    Control Submodule (trajectory attention guidance).

    Args:
        config: `DiffusionConfig`; its weights_path is checked here (BackendUnavailableError
            naming the path when missing or invalid) and loaded on first use (or by `load`).
        pipeline: an already built diffusers `CogVideoXPipeline` to use instead of loading
            weights (tests use tiny random ones); weights_path is then ignored. It is moved to
            the configured device and dtype in place and its modules are frozen (eval, no grad).
        priors: depth / masks / tracks estimators (default `DefaultPriorEstimators`, heuristic).

    Examples:
        >>> backend = DiffusionClipBackend(DiffusionConfig(weights_path="/models/CogVideoX-2b"))
        ... # doctest: +SKIP
        >>> boxes = np.linspace([0.7, 0.4, 0.9, 0.7], [0.1, 0.4, 0.3, 0.7], 49)
        >>> clip = backend.generate("a bus moves from right to left", [GuidanceTarget(["bus"], boxes)], seed=0)
        ... # doctest: +SKIP
        >>> clip.frames.shape, len(clip.cameras), clip.masks.shape   # doctest: +SKIP
        ((49, 480, 720, 3), 49, (49, 480, 720))
    """

    name = "diffusion"

    def __init__(self, config: DiffusionConfig | None = None, *, pipeline: Any = None,
                 priors: PriorEstimators | None = None) -> None:
        self.config = config or DiffusionConfig()
        _import_diffusers()
        import torch

        self._torch = torch
        self._pipe = pipeline
        if pipeline is None:
            self._weights = check_weights_path(self.config.weights_path)
        else:
            self._weights = None
        self.device = self._resolve_device(self.config.device)
        self.dtype = self._resolve_dtype(self.config.dtype)
        self.priors = priors if priors is not None else DefaultPriorEstimators()
        if not isinstance(self.priors, PriorEstimators):
            raise ValueError(f"Expected priors with depth / masks / tracks methods, found {type(self.priors).__name__}")
        if pipeline is not None:
            self._prepare(pipeline)

    # -------------------------------------------------------------- loading
    def _resolve_device(self, device: str | None) -> Any:
        torch = self._torch
        if device is None:
            return torch.device("cuda" if torch.cuda.is_available() else "cpu")
        dev = torch.device(device)
        if dev.type == "cuda" and not torch.cuda.is_available():
            raise BackendUnavailableError(f"diffusion.device={device!r} but CUDA is not available here "
                                          f"(torch {torch.__version__}); use device='cpu' or a CUDA build of torch")
        return dev

    def _resolve_dtype(self, name: str) -> Any:
        torch = self._torch
        if name == "auto":
            return torch.bfloat16 if self.device.type == "cuda" else torch.float32
        return {"float32": torch.float32, "bfloat16": torch.bfloat16, "float16": torch.float16}[name]

    def load(self) -> Any:
        """Load (once) and return the pipeline from weights_path, local files only."""
        if self._pipe is not None:
            return self._pipe
        diffusers = _import_diffusers()
        try:
            pipe = diffusers.CogVideoXPipeline.from_pretrained(str(self._weights), dtype=self.dtype,
                                                               local_files_only=True)
        except Exception as e:  # a broken or partial directory: say which and why
            raise BackendUnavailableError(f"Could not load a CogVideoX pipeline from diffusion weights path "
                                          f"{str(self._weights)!r}: {type(e).__name__}: {e}") from e
        self._prepare(pipe)
        return self._pipe

    def _prepare(self, pipe: Any) -> None:
        cfg = self.config
        for part in ("transformer", "vae", "scheduler"):
            if getattr(pipe, part, None) is None:
                raise BackendUnavailableError(f"Expected a CogVideoX pipeline with a {part}, found none")
        pipe.to(self.device)
        for part in ("transformer", "vae", "text_encoder"):
            module = getattr(pipe, part, None)
            if module is not None:
                if next(module.parameters()).dtype != self.dtype:
                    module.to(dtype=self.dtype)
                module.requires_grad_(False)
                module.eval()
        if cfg.vae_tiling:
            pipe.vae.enable_tiling()
        r = int(pipe.vae_scale_factor_temporal)
        if (cfg.num_frames - 1) % r:
            raise ValueError(f"Expected diffusion.num_frames = 1 + {r} k for this VAE, found {cfg.num_frames}")
        s = int(pipe.vae_scale_factor_spatial) * int(pipe.transformer.config.patch_size)
        if cfg.height % s or cfg.width % s:
            raise ValueError(f"Expected diffusion.height and width as multiples of {s}, found "
                             f"{cfg.height}x{cfg.width}")
        self._pipe = pipe

    @property
    def pipeline(self) -> Any:
        """The diffusers pipeline (loaded on first access)."""
        return self.load()

    # ------------------------------------------------------------ generation
    def default_camera(self) -> Camera:
        """The fixed pinhole camera the generated view is assigned (see the module docstring)."""
        c = self.config
        return Camera.look_at(c.camera_eye, c.camera_target, c.width, c.height, c.fov_y_deg)

    def generate(self, prompt: str, targets: Sequence[GuidanceTarget] = (), seed: int = 0,
                 camera: Camera | None = None, *, prompt_embeds: Any = None,
                 negative_prompt_embeds: Any = None) -> GeneratedClip:
        """Generate a clip whose motion-token attention follows the targets' boxes.

        Args:
            prompt: the scene description (recorded in the clip; encoded with the pipeline's
                text encoder unless `prompt_embeds` is given).
            targets: moving objects to steer, each with config.num_frames boxes; empty means
                plain text-to-video sampling.
            seed: seeds the initial noise (drawn on the CPU, so the same on every device).
            camera: the fixed camera to assign to every frame (default `default_camera()`).
            prompt_embeds: [1, L, D] text embeddings to use instead of the text encoder (then every
                target needs explicit token_indices unless the pipeline has a tokenizer).
            negative_prompt_embeds: [1, L, D] for classifier-free guidance (default: encoded
                `config.negative_prompt`, or zeros when prompt_embeds are given without a text encoder).

        Returns:
            `GeneratedClip` with frames [T, H, W, 3] uint8, T identical cameras, fps, priors from
            `self.priors` (depth, masks + labels, tracks), ground_truth None, and in `info` the
            guidance measurements (per-step energy and in-box attention fraction, the guidance
            iterations), the token indices used and the settings.
        """
        torch = self._torch
        cfg = self.config
        if not isinstance(prompt, str) or not prompt.strip():
            raise ValueError(f"Expected a non-empty prompt, found {prompt!r}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"Expected seed as a non-negative integer, found {seed!r}")
        targets = list(targets)
        for k, tgt in enumerate(targets):
            if not isinstance(tgt, GuidanceTarget):
                raise ValueError(f"Expected targets[{k}] as a GuidanceTarget, found {type(tgt).__name__}")
            if tgt.num_frames != cfg.num_frames:
                raise ValueError(f"Expected {cfg.num_frames} boxes (one per video frame) for target "
                                 f"{tgt.label!r}, found {tgt.num_frames}")
        cam = self.default_camera() if camera is None else camera
        if not isinstance(cam, Camera):
            raise ValueError(f"Expected camera as a Camera or None, found {type(cam).__name__}")
        if (cam.width, cam.height) != (cfg.width, cfg.height):
            cam = cam.resized(cfg.width, cfg.height)
        pipe = self.load()
        t_start = time.perf_counter()

        # text
        max_len = int(cfg.max_sequence_length or pipe.transformer.config.max_text_seq_length)
        do_cfg = cfg.guidance_scale > 1.0
        if prompt_embeds is None:
            if pipe.tokenizer is None or pipe.text_encoder is None:
                raise ValueError("Expected prompt_embeds: this pipeline has no tokenizer / text encoder")
            prompt_embeds, neg = pipe.encode_prompt(prompt, cfg.negative_prompt, do_classifier_free_guidance=do_cfg,
                                                    max_sequence_length=max_len, device=self.device,
                                                    dtype=self.dtype)
            negative_prompt_embeds = neg if negative_prompt_embeds is None else negative_prompt_embeds
        elif do_cfg and negative_prompt_embeds is None:
            if pipe.tokenizer is not None and pipe.text_encoder is not None:
                negative_prompt_embeds, _ = pipe.encode_prompt(cfg.negative_prompt, None, False,
                                                               max_sequence_length=max_len, device=self.device,
                                                               dtype=self.dtype)
            else:
                negative_prompt_embeds = torch.zeros_like(torch.as_tensor(prompt_embeds))
        prompt_embeds = torch.as_tensor(prompt_embeds).to(self.device, self.dtype)
        if prompt_embeds.ndim != 3 or prompt_embeds.shape[0] != 1:
            raise ValueError(f"Expected prompt_embeds of shape [1, L, D], found {tuple(prompt_embeds.shape)}")
        if negative_prompt_embeds is not None:
            negative_prompt_embeds = torch.as_tensor(negative_prompt_embeds).to(self.device, self.dtype)
        text_len = prompt_embeds.shape[1]
        token_indices = []
        for tgt in targets:
            if tgt.token_indices:
                idx = list(tgt.token_indices)
            elif pipe.tokenizer is not None:
                idx = token_indices_for_words(pipe.tokenizer, prompt, tgt.words, max_len)
            else:
                raise ValueError(f"Expected token_indices for target {tgt.label!r}: the pipeline has no tokenizer "
                                 f"to find {list(tgt.words)} in the prompt")
            if max(idx) >= text_len:
                raise ValueError(f"Expected token indices < {text_len} for target {tgt.label!r}, found {max(idx)}")
            token_indices.append(idx)

        # latents (CogVideoX 1.5 pads latent frames at the start to a multiple of patch_size_t)
        r = int(pipe.vae_scale_factor_temporal)
        sf = int(pipe.vae_scale_factor_spatial)
        t_lat = (cfg.num_frames - 1) // r + 1
        p_t = pipe.transformer.config.patch_size_t
        pad = (-t_lat) % p_t if p_t else 0
        shape = (1, t_lat + pad, int(pipe.transformer.config.in_channels), cfg.height // sf, cfg.width // sf)
        gen = torch.Generator(device="cpu").manual_seed(int(seed))
        noise = torch.randn(shape, generator=gen, dtype=torch.float32)
        boxes_lat = []
        for tgt in targets:
            b = boxes_to_latent_frames(tgt.boxes, r)
            boxes_lat.append(np.concatenate([np.repeat(b[:1], pad, 0), b]) if pad else b)

        latents, trace = guided_sample(
            pipe.transformer, pipe.scheduler, noise, prompt_embeds, negative_prompt_embeds, token_indices, boxes_lat,
            cfg.guidance, num_inference_steps=cfg.num_inference_steps, guidance_scale=cfg.guidance_scale,
            use_dynamic_cfg=cfg.use_dynamic_cfg, generator=torch.Generator(device="cpu").manual_seed(int(seed) + 1),
            record=True)
        t_sample = time.perf_counter() - t_start

        # decode
        with torch.no_grad():
            video = pipe.decode_latents(latents[:, pad:].to(self.dtype))  # [1, C, T, H, W] in [-1, 1]
        frames = ((video[0].float().permute(1, 2, 3, 0) / 2 + 0.5).clamp(0, 1) * 255).round()
        frames = frames.to(torch.uint8).cpu().numpy()
        if frames.shape[:3] != (cfg.num_frames, cfg.height, cfg.width):
            raise RuntimeError(f"Expected decoded frames of shape {(cfg.num_frames, cfg.height, cfg.width)}, "
                               f"found {frames.shape[:3]}")

        # priors
        attention = None if trace.attention_mean is None else trace.attention_mean[:, pad:]
        depth = self.priors.depth(frames, cam)
        mask_out = self.priors.masks(frames, attention, targets) if targets else None
        masks, labels = (None, {}) if mask_out is None else mask_out
        track_out = self.priors.tracks(frames)
        tracks, visible = (None, None) if track_out is None else track_out

        info = {
            "backend": self.name,
            "seed": int(seed),
            "weights_path": None if self._weights is None else str(self._weights),
            "model": type(pipe.transformer).__name__,
            "device": str(self.device),
            "dtype": str(self.dtype).replace("torch.", ""),
            "camera": "fixed pinhole (convention, not estimated)",
            "fov_y_deg": cam.fov_y_deg,
            "targets": [t.to_dict() for t in targets],
            "token_indices": token_indices,
            "guidance": trace.summary() if targets else None,
            "settings": cfg.to_dict(),
            "priors": type(self.priors).__name__,
            "seconds": {"sampling": t_sample, "total": time.perf_counter() - t_start},
        }
        return GeneratedClip(frames=frames, cameras=(cam,) * cfg.num_frames, fps=cfg.fps, depth=depth, masks=masks,
                             labels=labels, tracks=tracks, track_visible=visible, prompt=prompt, ground_truth=None,
                             info=info)
