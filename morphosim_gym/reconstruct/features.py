"""The distilled feature field (paper, after Feature 4X): a latent f_j per Gaussian, rasterised like
colour, and small MLP decoders D^s into each 2D encoder's space, trained with MSE against the
encoders' per-pixel feature maps.

2D encoders are pluggable (`PixelEncoder`). Offline defaults:

* `LabelEmbeddingEncoder` ("semantic"): each pixel is the sentence embedding (MiniLM, the
  shared `morphosim_gym.language.embeddings`) of its instance label; queries such as "the
  vehicle" are embedded the same way at edit time;
* `InstanceCodeEncoder` ("instance"): each pixel is the unit code of its mask's instance id
  (`scene.instance_codes`), so objects that share a label or a meaning ("sheep 1" and "sheep 2")
  stay apart in the field; the selector weighs the query's meaning by it;
* `ColorEncoder` ("color"): each pixel's CIE Lab colour, scaled to about [-1, 1].

`ClipImageEncoder` uses a CLIP-style vision model from a local directory when one is
configured (transformers `CLIPModel`), with patch features upsampled to pixels.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, Sequence

import numpy as np
import torch
from torch import nn
from tqdm.auto import tqdm

from ..errors import BackendUnavailableError
from ..metrics import rgb_to_lab
from ..render import rasterize
from ..scene import INSTANCE_DIM, FeatureDecoder, GeneratedClip, instance_codes
from .model import DynamicGaussians

__all__ = ["PixelEncoder", "IndexedPixelEncoder", "LabelEmbeddingEncoder", "InstanceCodeEncoder", "ColorEncoder", "ClipImageEncoder", "FeatureConfig",
           "distill_features", "MLP"]


class PixelEncoder(Protocol):
    """A 2D feature encoder E^s: per-pixel targets for one frame of a clip."""

    name: str
    dim: int
    normalize: bool

    def encode(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """(features [H, W, dim] float32, valid [H, W] bool) of a frame."""
        ...


class IndexedPixelEncoder(PixelEncoder, Protocol):
    """An encoder whose pixels take one of a few vectors (one per instance of the masks): the
    distillation keeps each frame as an index map and a table, not as a dense [H, W, dim] map
    (a 384-dim sentence embedding per pixel is 25 MB a 128 px frame, 1.2 GB for 49 frames)."""

    def encode_indexed(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(index [H, W] int64, table [K, dim] float32, valid [H, W] bool): pixel (r, c)'s
        feature is table[index[r, c]]; `encode` gives table[index]."""
        ...


def _indexed(masks: np.ndarray, vectors: dict[int, np.ndarray], dim: int) -> tuple[np.ndarray, np.ndarray]:
    """(index [H, W], table [K + 1, dim]) of an instance map: row 0 of the table is zeros (pixels
    whose instance has no vector), row k + 1 the vector of the k-th instance in sorted order."""
    ids = np.array(sorted(vectors), np.int64)
    table = np.zeros((len(ids) + 1, dim), np.float32)
    if len(ids) == 0:
        return np.zeros(masks.shape, np.int64), table
    table[1:] = np.stack([vectors[int(i)] for i in ids])
    pos = np.clip(np.searchsorted(ids, masks), 0, len(ids) - 1)
    index = np.where(ids[pos] == masks, pos + 1, 0).astype(np.int64)
    return index, table


class LabelEmbeddingEncoder:
    """Each pixel -> the sentence embedding of its instance label (from the clip's masks)."""

    name = "semantic"
    normalize = True

    def __init__(self) -> None:
        from ..language import embeddings

        self._emb = embeddings
        self.dim = embeddings.embedding_dim()
        self._by_label: dict[str, np.ndarray] = {}

    def _vectors(self, clip: GeneratedClip) -> dict[int, np.ndarray]:
        """Each of the clip's instance ids -> its label's embedding (embedded once per label, so
        one encoder serves clips that number their instances differently)."""
        missing = sorted({name for name in clip.labels.values() if name not in self._by_label})
        if missing:
            self._by_label.update(zip(missing, self._emb.embed(missing)))
        return {i: self._by_label[name] for i, name in clip.labels.items()}

    def encode_indexed(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if clip.masks is None:
            raise ValueError("Expected a clip with instance masks for the semantic encoder, found none")
        vectors = self._vectors(clip)
        m = clip.masks[frame]
        index, table = _indexed(m, vectors, self.dim)
        return index, table, m >= 0

    def encode(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray]:
        index, table, valid = self.encode_indexed(clip, frame)
        return table[index], valid


class InstanceCodeEncoder:
    """Each pixel -> the unit code of its mask's instance id (`scene.instance_codes`)."""

    name = "instance"
    normalize = True
    dim = INSTANCE_DIM

    def encode_indexed(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if clip.masks is None:
            raise ValueError("Expected a clip with instance masks for the instance encoder, found none")
        m = clip.masks[frame]
        ids = np.unique(m[m >= 0]).tolist()
        index, table = _indexed(m, dict(zip(ids, instance_codes(ids, self.dim))), self.dim)
        return index, table, m >= 0

    def encode(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray]:
        index, table, valid = self.encode_indexed(clip, frame)
        return table[index], valid


class ColorEncoder:
    """Each pixel -> its Lab colour scaled to about [-1, 1] (L / 50 - 1, a / 100, b / 100)."""

    name = "color"
    dim = 3
    normalize = False

    def encode(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray]:
        lab = rgb_to_lab(clip.frames[frame])
        out = np.stack([lab[..., 0] / 50.0 - 1.0, lab[..., 1] / 100.0, lab[..., 2] / 100.0], -1).astype(np.float32)
        valid = clip.depth[frame] > 0 if clip.depth is not None else np.ones(out.shape[:2], bool)
        return out, valid


class ClipImageEncoder:
    """A CLIP-style vision encoder from local weights (a directory saved by transformers'
    `CLIPModel.save_pretrained`); patch embeddings projected to the joint space, upsampled to pixels.

    Raises:
        BackendUnavailableError: transformers missing or no usable model at `path`.
    """

    name = "clip"
    normalize = True

    def __init__(self, path: str | Path, device: str = "cpu") -> None:
        p = Path(path)
        if not (p / "config.json").exists():
            raise BackendUnavailableError(f"CLIP encoder: no model at {p} (expected a transformers CLIPModel "
                                          f"directory with config.json)")
        try:
            from transformers import CLIPModel
        except ImportError as exc:
            raise BackendUnavailableError(f"CLIP encoder needs transformers: pip install transformers ({exc})") from None
        self.model = CLIPModel.from_pretrained(str(p), local_files_only=True).eval().to(device)
        self.device = device
        self.dim = int(self.model.config.projection_dim)
        vc = self.model.config.vision_config
        self.size = int(vc.image_size)
        self.patch = int(vc.patch_size)

    @torch.no_grad()
    def encode(self, clip: GeneratedClip, frame: int) -> tuple[np.ndarray, np.ndarray]:
        img = torch.from_numpy(clip.frames[frame].astype(np.float32) / 255.0).permute(2, 0, 1)[None]
        x = torch.nn.functional.interpolate(img, size=(self.size, self.size), mode="bilinear", align_corners=False)
        mean = torch.tensor([0.4815, 0.4578, 0.4082])[None, :, None, None]
        std = torch.tensor([0.2686, 0.2613, 0.2758])[None, :, None, None]
        out = self.model.vision_model(pixel_values=((x - mean) / std).to(self.device))
        tokens = self.model.vision_model.post_layernorm(out.last_hidden_state[:, 1:])
        proj = self.model.visual_projection(tokens)                              # [1, P, dim]
        g = self.size // self.patch
        fmap = proj.reshape(1, g, g, self.dim).permute(0, 3, 1, 2)
        fmap = torch.nn.functional.interpolate(fmap, size=(clip.height, clip.width), mode="bilinear",
                                               align_corners=False)[0].permute(1, 2, 0)
        fmap = fmap / fmap.norm(dim=-1, keepdim=True).clamp(min=1e-6)
        return fmap.cpu().numpy().astype(np.float32), np.ones((clip.height, clip.width), bool)


class MLP(nn.Module):
    """D -> hidden -> out with ReLU (a decoder D^s)."""

    def __init__(self, d_in: int, d_out: int, hidden: int = 64) -> None:
        super().__init__()
        self.l1 = nn.Linear(d_in, hidden)
        self.l2 = nn.Linear(hidden, d_out)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.l2(torch.relu(self.l1(x)))

    def export(self, name: str, normalize: bool) -> FeatureDecoder:
        """As a numpy `FeatureDecoder` (weights [in, out])."""
        return FeatureDecoder(name, [self.l1.weight.detach().numpy().T.copy(), self.l2.weight.detach().numpy().T.copy()],
                              [self.l1.bias.detach().numpy().copy(), self.l2.bias.detach().numpy().copy()], normalize)


@dataclass(frozen=True)
class FeatureConfig:
    """Feature-field distillation settings.

    Attributes:
        dim: D, the latent width per Gaussian.
        iterations: distillation steps (one frame each).
        resolution: feature maps are rendered at this fraction of the clip's resolution (the
            encoders' maps are sampled at the same pixel centres). Full resolution by default:
            at half, each Gaussian's screen footprint (and its 0.3 px low-pass) doubles relative
            to the objects, border Gaussians learn features blended with their neighbours', and
            selections leave rims behind (1-9% of an object's Gaussians on the paper scenes).
        pixels: pixels sampled per step for the decoders' loss (0: all).
        lr_features, lr_decoders: learning rates.
        hidden: decoder hidden width.
        encoders: which offline encoders ("semantic", "instance", "color"); `clip_path` adds a CLIP-style one.
        clip_path: local directory of a CLIP model, or None.
        backend: renderer.
        progress: tqdm bar.
        fill_unseen: Gaussians whose latents no supervised pixel reached (an object's far side
            or underside added by completion, Gaussians hidden behind others in every frame)
            take the mean latent of their `fill_neighbours` nearest supervised Gaussians, instead
            of keeping their colour-only start (which decodes as whatever shares their colour).
            Off by default: on the 9 example prompts (estimated priors) it raised the worst
            object's selection min(P, R) from 0.66 to 0.71 and the mean from 0.88 to 0.90 (car 0.75
            -> 0.88), but on the 8 held-out prompts the mean went 0.91 -> 0.89 (van 0.93 -> 0.85):
            neighbours across an object's border carry the other object's latent.
    """

    dim: int = 32
    iterations: int = 200
    resolution: float = 1.0
    pixels: int = 2048
    lr_features: float = 1e-2
    lr_decoders: float = 3e-3
    hidden: int = 64
    encoders: tuple[str, ...] = ("semantic", "instance", "color")
    clip_path: str | None = None
    backend: str = "cpu"
    progress: bool = True
    fill_unseen: bool = False
    fill_neighbours: int = 8


OFFLINE_ENCODERS = {"semantic": LabelEmbeddingEncoder, "instance": InstanceCodeEncoder, "color": ColorEncoder}


def _encoders(cfg: FeatureConfig) -> list:
    out = []
    for name in cfg.encoders:
        if name not in OFFLINE_ENCODERS:
            raise ValueError(f"Expected encoders among {tuple(OFFLINE_ENCODERS)}, found {name!r}")
        out.append(OFFLINE_ENCODERS[name]())
    if cfg.clip_path:
        out.append(ClipImageEncoder(cfg.clip_path))
    return out


def _initial_latents(model: DynamicGaussians, clip: GeneratedClip, encoders: Sequence[PixelEncoder], dim: int,
                     rng: np.random.Generator, frames: int = 12, depth_tolerance: float = 0.05) -> np.ndarray:
    """[N, dim] starting latents from what the frames show, never from the Gaussians' instance ids:
    a fixed random projection of each Gaussian's Lab colour, plus a random projection of the
    mask-based encoders' pixel features ("semantic", "instance") where the Gaussian's centre lands,
    within `depth_tolerance` of the depth prior (so it is seen there, not hidden), in one of
    `frames` frames spread over the clip (averaged over those frames), plus noise. Gaussians that
    no view shows start from their colour alone."""
    with torch.no_grad():
        rgb = model.colors().detach().numpy().astype(np.float64)
    lab = rgb_to_lab(rgb) / np.array([50.0, 64.0, 64.0]) - np.array([1.0, 0.0, 0.0])
    init = 0.3 * lab @ rng.normal(size=(3, dim)) + 0.05 * rng.normal(size=(len(lab), dim))
    from_masks = [e for e in encoders if e.name in ("semantic", "instance")]
    if not from_masks or clip.masks is None:
        return init
    projs = [rng.normal(size=(e.dim, dim)) for e in from_masks]
    seen = np.zeros(len(lab), bool)
    code = np.zeros_like(init)
    hits = np.zeros(len(lab))
    H, W = clip.height, clip.width
    for t in sorted(set(np.linspace(0, clip.num_frames - 1, max(1, frames)).round().astype(int).tolist())):
        with torch.no_grad():
            means, _ = model.warp(t)
        uv, z = clip.cameras[t].project(means.detach().numpy().astype(np.float64))
        with np.errstate(invalid="ignore"):
            c, r = np.floor(uv[:, 0]), np.floor(uv[:, 1])
            ok = (z > clip.cameras[t].near) & (c >= 0) & (c < W) & (r >= 0) & (r < H)
        encoded = [_FrameTarget.encode(e, clip, t) for e in from_masks]
        valid = encoded[0].valid
        idx = np.flatnonzero(ok)
        ci, ri = c[idx].astype(int), r[idx].astype(int)
        if clip.depth is not None:                  # visible there: at the depth prior's depth
            prior = clip.depth[t, ri, ci]
            valid_here = valid[ri, ci] & (np.abs(z[idx] - prior) <= depth_tolerance * prior)
        else:
            valid_here = valid[ri, ci]
        idx, ci, ri = idx[valid_here], ci[valid_here], ri[valid_here]
        for target, proj in zip(encoded, projs):
            code[idx] += target.at(ri * W + ci).astype(np.float64) @ proj
        hits[idx] += 1
        seen[idx] = True
    code[seen] /= hits[seen, None]
    return init + code


def distill_features(model: DynamicGaussians, clip: GeneratedClip, config: FeatureConfig | None = None,
                     seed: int = 0, encoders: Sequence[PixelEncoder] | None = None) -> tuple[dict[str, FeatureDecoder], dict]:
    """Learn per-Gaussian latents (set as `model.features`) and one decoder per encoder, with the
    geometry and motion frozen. Returns (decoders, log)."""
    cfg = config or FeatureConfig()
    encs = list(encoders) if encoders is not None else _encoders(cfg)
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    T, H, W = clip.num_frames, clip.height, clip.width
    init = _initial_latents(model, clip, encs, cfg.dim, rng)
    model.features = nn.Parameter(torch.as_tensor(init, dtype=torch.float32))
    decoders = nn.ModuleList([MLP(cfg.dim, e.dim, cfg.hidden) for e in encs])
    opt = torch.optim.Adam([{"params": [model.features], "lr": cfg.lr_features},
                            {"params": decoders.parameters(), "lr": cfg.lr_decoders}], fused=True)
    targets = {}
    start = time.perf_counter()
    if not 0 < cfg.resolution <= 1:
        raise ValueError(f"Expected resolution in (0, 1], found {cfg.resolution}")
    Wf, Hf = max(8, int(round(W * cfg.resolution))), max(8, int(round(H * cfg.resolution)))
    sx, sy = Wf / W, Hf / H
    # the full-resolution pixel under each reduced pixel's centre
    cols = np.minimum(((np.arange(Wf) + 0.5) / sx).astype(int), W - 1)
    rows = np.minimum(((np.arange(Hf) + 0.5) / sy).astype(int), H - 1)
    viewmats = torch.from_numpy(np.stack([c.world_to_camera for c in clip.cameras]).astype(np.float32))
    Ks = np.stack([c.K for c in clip.cameras]).astype(np.float32)
    Ks[:, 0] *= sx
    Ks[:, 1] *= sy
    Ks = torch.from_numpy(Ks)
    nears = torch.tensor([c.near for c in clip.cameras], dtype=torch.float64)
    with torch.no_grad():
        scales, opac, colors = model.scales().detach(), model.opacities().detach(), model.colors().detach()
    order: list[int] = []
    losses = []
    reached = np.zeros(model.num)           # how much supervision each Gaussian's latent received
    bar = tqdm(range(cfg.iterations), desc="feature field", disable=not cfg.progress, leave=False)
    for it in bar:
        if not order:
            order = list(rng.permutation(T))
        t = int(order.pop())
        if t not in targets:
            targets[t] = [_FrameTarget.encode(e, clip, t, rows, cols).as_torch() for e in encs]
        with torch.no_grad():
            means, quats = model.warp(t)
        out = rasterize(means.detach(), quats.detach(), scales, opac, colors, viewmats[t:t + 1], Ks[t:t + 1], Wf, Hf,
                        features=model.features, nears=nears[t:t + 1], backend=cfg.backend)
        fmap = out["features"][0]                                               # [H, W, D]
        alpha = out["alpha"][0].detach()
        loss = fmap.sum() * 0.0
        for dec, target in zip(decoders, targets[t]):
            idx = torch.nonzero((target.valid & (alpha > 0.5)).reshape(-1)).squeeze(1)
            if cfg.pixels and len(idx) > cfg.pixels:
                idx = idx[torch.from_numpy(rng.choice(len(idx), cfg.pixels, replace=False))]
            if len(idx):
                f = fmap.reshape(-1, fmap.shape[-1])[idx] / alpha.reshape(-1)[idx][:, None]   # alpha-normalised
                pred = dec(f)
                loss = loss + ((pred - target.at(idx)) ** 2).mean()
        opt.zero_grad(set_to_none=True)
        loss.backward()
        if cfg.fill_unseen and model.features.grad is not None:
            reached += model.features.grad.detach().abs().sum(1).numpy().astype(np.float64)
        opt.step()
        if it % 25 == 0:
            losses.append(loss.item())
            bar.set_postfix(loss=f"{loss.item():.4f}")
    filled = _fill_unseen(model, reached, cfg.fill_neighbours, T // 2) if cfg.fill_unseen else 0
    exported = {e.name: dec.export(e.name, e.normalize) for e, dec in zip(encs, decoders)}
    return exported, {"loss": losses, "seconds": time.perf_counter() - start, "iterations": cfg.iterations,
                      "filled": filled}


@dataclass(frozen=True)
class _FrameTarget:
    """One encoder's targets for one frame, flat over its pixels: `values` [P, dim] (`index` None)
    or a table [K, dim] with each pixel's row in `index` [P] (an `IndexedPixelEncoder`); `valid`
    [H, W]. Numpy arrays, or torch tensors after `as_torch`."""

    values: np.ndarray | torch.Tensor
    index: np.ndarray | torch.Tensor | None
    valid: np.ndarray | torch.Tensor

    @classmethod
    def encode(cls, encoder: PixelEncoder, clip: GeneratedClip, frame: int, rows: np.ndarray | None = None,
               cols: np.ndarray | None = None) -> "_FrameTarget":
        """The encoder's targets of a frame at these rows and columns (None: every pixel)."""
        rows = np.arange(clip.height) if rows is None else rows
        cols = np.arange(clip.width) if cols is None else cols
        if hasattr(encoder, "encode_indexed"):
            index, table, valid = encoder.encode_indexed(clip, frame)
            return cls(np.ascontiguousarray(table), _at_pixels(index, rows, cols).reshape(-1), _at_pixels(valid, rows, cols))
        feat, valid = encoder.encode(clip, frame)
        return cls(_at_pixels(feat, rows, cols).reshape(-1, feat.shape[-1]), None, _at_pixels(valid, rows, cols))

    def as_torch(self) -> "_FrameTarget":
        return _FrameTarget(*(None if a is None else torch.from_numpy(a) for a in (self.values, self.index, self.valid)))

    def at(self, pixels: np.ndarray | torch.Tensor) -> np.ndarray | torch.Tensor:
        """[n, dim] targets of these flat pixel indices."""
        return self.values[pixels] if self.index is None else self.values[self.index[pixels]]


def _at_pixels(a: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """An encoder's map [H, W, ...] at these rows and columns, C-contiguous: the map itself at full
    resolution (a per-pixel embedding map is tens of MB a frame: no copies), else one gather."""
    if len(rows) == a.shape[0] and len(cols) == a.shape[1] and (rows == np.arange(len(rows))).all() \
            and (cols == np.arange(len(cols))).all():
        return np.ascontiguousarray(a)
    return np.ascontiguousarray(a[rows[:, None], cols[None, :]])


def _fill_unseen(model: DynamicGaussians, reached: np.ndarray, k: int, frame: int, floor: float = 1e-3) -> int:
    """Give each Gaussian whose latent received almost no supervision (`reached` <= `floor` x the
    median of those that received any) the mean latent of its `k` nearest supervised Gaussians at
    `frame`; returns how many were filled."""
    from scipy.spatial import cKDTree

    some = reached[reached > 0]
    if some.size == 0:
        return 0
    unseen = reached <= floor * float(np.median(some))
    if not unseen.any() or unseen.all():
        return 0
    with torch.no_grad():
        means = model.warp(frame)[0].detach().numpy().astype(np.float64)
        latents = model.features.detach().numpy()
        _, nearest = cKDTree(means[~unseen]).query(means[unseen], k=min(k, int((~unseen).sum())))
        nearest = nearest.reshape(int(unseen.sum()), -1)
        filled = latents[~unseen][nearest].mean(1)
        model.features.data[torch.from_numpy(np.flatnonzero(unseen))] = torch.as_tensor(filled, dtype=torch.float32)
    return int(unseen.sum())

