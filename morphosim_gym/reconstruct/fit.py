"""The geometry and motion fit: optimise the 4D model against every frame of the clip."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import torch
from tqdm.auto import tqdm

from ..render import rasterize
from ..scene import GeneratedClip
from ..scene.sky import sky_background
from ..priors import prior_confidences
from .losses import (arap_loss, depth_loss, empty_alpha_loss, mask_iou_loss, mask_loss, photometric_loss, psnr_torch,
                     scale_shift_depth_loss, smooth_motion_loss, track_loss)
from .model import DynamicGaussians, rbf_skinning
from .strategy import Strategy, accumulate, initialize_state, refine

__all__ = ["FitConfig", "fit", "ClipTensors"]

_DECAYED = ("means", "node_trans", "node_quats")    # parameter groups whose learning rate decays


@dataclass(frozen=True)
class FitConfig:
    """Optimisation settings (learning rates scale with the scene depth where marked).

    Attributes:
        iterations: optimisation steps (one frame each).
        lr_means: position learning rate, times the median scene depth.
        lr_scales, lr_quats, lr_opacity, lr_colors: per-Gaussian learning rates.
        lr_node_trans: learning rate of the node centres' displacements, times the median scene depth.
        lr_node_quats: learning rate of the node rotations (each about its own centre).
        w_ssim, w_depth, w_mask, w_mask_iou, w_empty, w_track, w_arap, w_smooth: loss weights.
        w_depth_invariant: weight of the scale- and shift-invariant depth term
            (`losses.scale_shift_depth_loss`, per instance and frame): the prior's depth shape
            without its per-object scale, which estimated depth gets wrong more than the shape.
            Not for a depth prior that is the generator's exact render (info["priors"]["depth"]
            "ground_truth"), fitted as before.
        confidence: weigh mask pixels, depth pixels and tracks by the priors' confidences
            (`priors.prior_confidences`: a mask's outline and jumpy tracks count less; exact
            tracks keep weight 1). The outline of the generator's exact masks counts less too:
            its pixels mix two objects' colours in the frames, and a hard instance target there
            fights the colour (ground-truth priors, input view: bus 41.6 -> 44.6 dB, mug 43.5 -> 46.0).
        depth_trim: fraction of each frame's largest relative depth errors left out of the depth term.
        track_delta: Huber threshold (pixels) of the track term (0: L1).
        lr_decay: the position and node-pose learning rates decay exponentially to this fraction
            of their start by the last iteration. Adam takes steps of about the learning rate
            whatever the gradient, so at a constant rate each frame's node pose keeps jittering
            by a fraction of a pixel around its optimum; the decay lets it settle.
        strategy: densification and pruning.
        backend: renderer ("cpu").
        progress: show a tqdm bar.
    """

    iterations: int = 1200
    lr_means: float = 2e-4
    lr_scales: float = 5e-3
    lr_quats: float = 1e-3
    lr_opacity: float = 3e-2
    lr_colors: float = 2.5e-2
    lr_node_trans: float = 1e-3
    lr_node_quats: float = 1e-3
    w_ssim: float = 0.2
    w_depth: float = 0.1
    w_mask: float = 0.2
    w_mask_iou: float = 0.1
    w_empty: float = 0.2
    w_track: float = 0.05
    w_arap: float = 1.0
    w_smooth: float = 1.0
    w_depth_invariant: float = 0.05
    confidence: bool = True
    lr_decay: float = 0.03
    depth_trim: float = 0.1
    track_delta: float = 1.0
    strategy: Strategy = field(default_factory=Strategy)
    backend: str = "cpu"
    progress: bool = True

    def __post_init__(self) -> None:
        if self.iterations < 1:
            raise ValueError(f"Expected at least 1 fit iteration, found {self.iterations}")
        if not 0.0 < self.lr_decay <= 1.0:
            raise ValueError(f"Expected lr_decay in (0, 1], found {self.lr_decay}")


class ClipTensors:
    """A clip's frames and priors as torch tensors, plus per-frame camera arrays."""

    def __init__(self, clip: GeneratedClip, instance_ids: list[int], confidence: bool = False) -> None:
        self.T = clip.num_frames
        self.H, self.W = clip.height, clip.width
        self.rgb = torch.from_numpy(clip.frames.astype(np.float32) / 255.0)
        self.depth = torch.from_numpy(clip.depth.astype(np.float32))
        self.masks = torch.from_numpy(clip.masks.astype(np.int64))
        # pixels with a depth but no instance (translucent matter such as particles in water):
        # their colour and depth are fitted, their instance is left free
        self.mask_valid = ~((self.masks < 0) & (self.depth > 0))
        self.instance_ids = list(instance_ids)
        self.viewmats = torch.from_numpy(np.stack([c.world_to_camera for c in clip.cameras]).astype(np.float32))
        self.Ks = torch.from_numpy(np.stack([c.K for c in clip.cameras]).astype(np.float32))
        self.nears = torch.tensor([c.near for c in clip.cameras], dtype=torch.float64)
        self.fx = float(clip.cameras[0].fx)
        mask_conf, track_conf = prior_confidences(clip) if confidence else (None, None)
        # per-pixel confidence of the mask prior [T, H, W] (None: all 1), per-track confidence [P]
        self.mask_weight = None if mask_conf is None else torch.from_numpy(mask_conf)
        self.track_weight = None if track_conf is None else torch.from_numpy(track_conf)

    def onehot(self, frame: int) -> torch.Tensor:
        """[H, W, K] one-hot instance masks (background pixels are all zero)."""
        m = self.masks[frame]
        out = torch.zeros(self.H, self.W, len(self.instance_ids))
        for k, inst in enumerate(self.instance_ids):
            out[..., k] = (m == inst).float()
        return out


def _node_pairs(model: DynamicGaussians, k: int = 3) -> torch.Tensor:
    """Neighbouring node pairs (k nearest of the same instance) for ARAP."""
    c = model.node_centres
    objs = model.node_objects
    pairs = []
    for i in range(len(c)):
        same = torch.nonzero((objs == objs[i]) & (torch.arange(len(c)) != i)).squeeze(1)
        if len(same) == 0:
            continue
        d = (c[same] - c[i]).norm(dim=-1)
        for j in same[torch.argsort(d)[:k]]:
            pairs.append((i, int(j)))
    return torch.tensor(pairs, dtype=torch.long).reshape(-1, 2)


def _track_targets(clip: GeneratedClip, model: DynamicGaussians, reference: dict[int, int], dynamic: dict[int, bool]):
    """Canonical 3D points of dynamic-instance tracks (lifted at their reference frame), their
    skinning, 2D targets [P, T, 2], visibility [P, T] and the indices [P] of those tracks in the
    clip; None without tracks."""
    if clip.tracks is None or model.node_centres.shape[0] == 0:
        return None
    pts, nodes_inst, keep = [], [], []
    for p in range(len(clip.tracks)):
        vis = np.flatnonzero(clip.track_visible[p])
        if len(vis) < 2:
            continue
        uv = clip.tracks[p, vis[0]]
        c = int(np.clip(np.floor(uv[0]), 0, clip.width - 1))
        r = int(np.clip(np.floor(uv[1]), 0, clip.height - 1))
        inst = int(clip.masks[vis[0], r, c])
        if inst < 0 or not dynamic.get(inst, False):
            continue
        ref = reference[inst]
        if not clip.track_visible[p, ref]:
            continue
        uvr = clip.tracks[p, ref]
        c = int(np.clip(np.floor(uvr[0]), 0, clip.width - 1))
        r = int(np.clip(np.floor(uvr[1]), 0, clip.height - 1))
        z = float(clip.depth[ref, r, c])
        if z <= 0 or clip.masks[ref, r, c] != inst:
            continue
        # canonical = world at the reference frame, where the node poses are identity-initialised
        world = clip.cameras[ref].unproject(uvr[None], np.array([z]))[0]
        pts.append(world)
        nodes_inst.append(inst)
        keep.append(p)
    if not pts:
        return None
    pts = np.asarray(pts)
    nodes, weights = rbf_skinning(pts, np.asarray(nodes_inst), model.node_centres.numpy().astype(np.float64),
                                  model.node_objects.numpy(), model.slots)
    # canonical frame of each instance is its reference frame's world: undo the (initial) pose there
    return (torch.as_tensor(pts, dtype=torch.float32), torch.as_tensor(nodes, dtype=torch.long),
            torch.as_tensor(weights), torch.as_tensor(clip.tracks[keep]), torch.as_tensor(clip.track_visible[keep]),
            torch.as_tensor(np.asarray(keep, dtype=np.int64)))


def fit(model: DynamicGaussians, clip: GeneratedClip, reference: dict[int, int], dynamic: dict[int, bool],
        config: FitConfig | None = None, seed: int = 0, background: tuple[float, float, float] = (0, 0, 0),
        sky: np.ndarray | None = None) -> dict:
    """Optimise `model` in place against the clip. Returns a log (losses, PSNR, timings).
    With a `sky` image (`reconstruct.sky`) each frame's renders are composited over the sky
    seen along its rays instead of the `background` colour, as the fitted scene renders."""
    cfg = config or FitConfig()
    torch.manual_seed(seed)
    gen = torch.Generator().manual_seed(seed)
    order_rng = np.random.default_rng(seed)
    data = ClipTensors(clip, sorted(int(i) for i in np.unique(clip.masks) if i >= 0), confidence=cfg.confidence)
    # the generator's own depth renders are metric and exact: no scale to be blind to
    depth_origin = (clip.info.get("priors") or {}).get("depth") if isinstance(clip.info.get("priors"), dict) else None
    invariant_depth = cfg.w_depth_invariant > 0 and depth_origin != "ground_truth"
    scene_depth = float(np.median(clip.depth[clip.depth > 0]))
    bg = torch.tensor(background, dtype=torch.float32)
    behind = None if sky is None else torch.as_tensor(np.stack([sky_background(sky, c) for c in clip.cameras]))
    if behind is not None:
        bg = torch.zeros(3)
    # footprint of each Gaussian (initial pixel size), for densification thresholds
    footprint = model.scales().detach().max(dim=-1).values.clone()
    inst_index = {inst: k for k, inst in enumerate(data.instance_ids)}

    def onehot_features() -> torch.Tensor:
        idx = torch.tensor([inst_index.get(int(i), -1) for i in model.object_ids.tolist()])
        oh = torch.zeros(model.num, len(data.instance_ids))
        ok = idx >= 0
        oh[ok, idx[ok]] = 1.0
        return oh

    def make_optimizer() -> torch.optim.Optimizer:
        groups = [
            {"params": [model.means], "lr": cfg.lr_means * scene_depth, "name": "means"},
            {"params": [model.quats], "lr": cfg.lr_quats, "name": "quats"},
            {"params": [model.log_scales], "lr": cfg.lr_scales, "name": "log_scales"},
            {"params": [model.opacity_logits], "lr": cfg.lr_opacity, "name": "opacity_logits"},
            {"params": [model.color_logits], "lr": cfg.lr_colors, "name": "color_logits"},
        ]
        if model.node_trans.shape[1]:
            groups += [{"params": [model.node_trans], "lr": cfg.lr_node_trans * scene_depth, "name": "node_trans"},
                       {"params": [model.node_quats], "lr": cfg.lr_node_quats, "name": "node_quats"}]
        return torch.optim.Adam(groups, eps=1e-15, fused=True)   # one compiled step for all groups (4x the default loop)

    optimizer = make_optimizer()
    state = initialize_state(model)
    state["footprint"] = footprint
    tracks = _track_targets(clip, model, reference, dynamic)
    pairs = _node_pairs(model)
    node_c0 = model.node_centres.clone()
    onehot = onehot_features()
    log = {"loss": [], "psnr": [], "refine": []}
    start = time.perf_counter()
    frames = []
    bar = tqdm(range(cfg.iterations), desc="reconstruct", disable=not cfg.progress, leave=False)
    start_lr = {g["name"]: g["lr"] for g in optimizer.param_groups}
    for it in bar:
        decay = cfg.lr_decay ** (it / max(cfg.iterations - 1, 1))
        for g in optimizer.param_groups:
            if g["name"] in _DECAYED:
                g["lr"] = start_lr[g["name"]] * decay
        if not frames:
            frames = list(order_rng.permutation(data.T))
        t = int(frames.pop())
        means, quats = model.warp(t)
        out = rasterize(means, quats, model.scales(), model.opacities(), model.colors(), data.viewmats[t:t + 1],
                        data.Ks[t:t + 1], data.W, data.H, features=onehot, background=bg,
                        nears=data.nears[t:t + 1], backend=cfg.backend)
        rgb, depth, alpha, soft = out["rgb"][0], out["depth"][0], out["alpha"][0], out["features"][0]
        if behind is not None:
            rgb = rgb + (1.0 - alpha)[..., None] * behind[t]
        target = data.rgb[t]
        loss = photometric_loss(rgb, target, cfg.w_ssim)
        conf_t = None if data.mask_weight is None else data.mask_weight[t]
        loss = loss + cfg.w_depth * depth_loss(depth, data.depth[t], alpha, cfg.depth_trim, weight=conf_t)
        if invariant_depth:
            loss = loss + cfg.w_depth_invariant * scale_shift_depth_loss(depth, data.depth[t], alpha, data.masks[t],
                                                                         weight=conf_t)
        onehot_t = data.onehot(t)
        loss = loss + cfg.w_mask * mask_loss(soft, onehot_t, data.mask_valid[t], weight=conf_t)
        if cfg.w_mask_iou > 0:
            loss = loss + cfg.w_mask_iou * mask_iou_loss(soft, onehot_t, data.mask_valid[t], weight=conf_t)
        loss = loss + cfg.w_empty * empty_alpha_loss(alpha, data.depth[t] <= 0)
        # depth but no instance: translucent matter, drawn but thinner than the background behind it;
        # not along masks' outlines (an estimated mask a pixel or two short leaves a gap there)
        unlabelled = ~data.mask_valid[t] if conf_t is None else ~data.mask_valid[t] & (conf_t >= 1.0)
        loss = loss + cfg.w_empty * empty_alpha_loss(torch.relu(alpha - 0.5), unlabelled)
        if model.node_trans.shape[1]:
            if tracks is not None:
                pts, tn, tw, tuv, tvis, tidx = tracks
                tconf = None if data.track_weight is None else data.track_weight[tidx]
                world = model.points_at(pts, tn, tw, t)
                cam = data.viewmats[t]
                pc = world @ cam[:3, :3].T + cam[:3, 3]
                K = data.Ks[t]
                uv = torch.stack([K[0, 0] * pc[:, 0] / pc[:, 2] + K[0, 2], K[1, 1] * pc[:, 1] / pc[:, 2] + K[1, 2]], -1)
                loss = loss + cfg.w_track * track_loss(uv, tuv[:, t], tvis[:, t], float(data.W), cfg.track_delta,
                                                     weight=tconf)
            node_pos = model.points_at(node_c0, torch.arange(len(node_c0))[:, None],
                                       torch.ones(len(node_c0), 1), t)
            loss = loss + cfg.w_arap * arap_loss(node_pos, node_c0, pairs) / max(scene_depth ** 2, 1e-9)
            if 0 < t < data.T - 1:
                loss = loss + cfg.w_smooth * smooth_motion_loss(model.node_quats, model.node_trans / scene_depth,
                                                                torch.tensor([t]))
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        accumulate(state, model, state["footprint"])
        optimizer.step()
        s = cfg.strategy
        with torch.no_grad():
            model.quats.data /= model.quats.data.norm(dim=-1, keepdim=True)
            if s.max_footprints is not None:
                cap = torch.log(s.max_footprints * state["footprint"])[:, None]
                model.log_scales.data = torch.minimum(model.log_scales.data, cap)
        if s.refine_start <= it < s.refine_stop and (it - s.refine_start) % s.refine_every == s.refine_every - 1:
            counts = refine(model, optimizer, state, s, state["footprint"], gen)
            log["refine"].append({"iteration": it, **counts, "gaussians": model.num})
            onehot = onehot_features()
        if it % 25 == 0 or it == cfg.iterations - 1:
            p = psnr_torch(rgb.detach().clamp(0, 1), target)
            log["loss"].append(loss.item())
            log["psnr"].append(p)
            bar.set_postfix(loss=f"{loss.item():.4f}", psnr=f"{p:.2f}", n=model.num)
    log["seconds"] = time.perf_counter() - start
    log["iterations"] = cfg.iterations
    return log

