"""`gsplat` backend: the same contract as `cpu`, rendered by gsplat's CUDA kernels.

Optional: needs `pip install gsplat` and a CUDA GPU visible to torch; otherwise every
call raises `BackendUnavailableError` saying which of the two is missing.

Differences from the `cpu` kernels that a user may notice: gsplat bounds each Gaussian
by 3 sigma rather than by the exact 1/255 level set (a few faint edge pixels differ),
and `instance` is the object with the largest summed weight (rendered as one-hot
channels), not the single Gaussian with the largest weight.
"""

from __future__ import annotations

from ..errors import BackendUnavailableError

__all__ = ["check_gsplat", "rasterize_gsplat", "render_batch_gsplat"]

_MAX_INSTANCE_CHANNELS = 64


def check_gsplat() -> None:
    """Raise `BackendUnavailableError` unless gsplat and a CUDA GPU are both usable."""
    try:
        import gsplat  # noqa: F401
    except ImportError:
        raise BackendUnavailableError(
            "backend 'gsplat' is not available: the gsplat package is not installed "
            "(pip install 'morphosim-gym[gsplat]' on a machine with a CUDA GPU), use backend='cpu'"
        ) from None
    import torch

    if not torch.cuda.is_available():
        raise BackendUnavailableError(
            "backend 'gsplat' is not available: torch sees no CUDA GPU (torch.cuda.is_available() is False); "
            "use backend='cpu'"
        )


def rasterize_gsplat(means, quats, scales, opacities, colors, viewmats, Ks, width, height, features=None,
                     object_ids=None, background=None, nears=None) -> dict:
    """`rasterize` on gsplat. Same arguments and outputs as `morphosim_gym.render.cpu.rasterize_cpu`;
    outputs come back on the inputs' device."""
    check_gsplat()
    import torch
    from gsplat import rasterization

    home = means.device
    dev = torch.device("cuda")
    dtype = torch.float32
    C = viewmats.shape[0]
    channels = [colors.to(dev, dtype)]
    n_feat = 0 if features is None else features.shape[1]
    if n_feat:
        channels.append(features.to(dev, dtype))
    ids_unique = None
    if object_ids is not None:
        ids = object_ids.to(dev).long()
        ids_unique = torch.unique(ids[ids >= 0])
        if len(ids_unique) > _MAX_INSTANCE_CHANNELS:
            raise ValueError(f"Expected at most {_MAX_INSTANCE_CHANNELS} objects for the gsplat backend's "
                             f"instance map, found {len(ids_unique)}")
        onehot = (ids[:, None] == ids_unique[None, :]).to(dtype)
        channels.append(onehot)
    stacked = torch.cat(channels, dim=1)
    bg = torch.zeros(C, stacked.shape[1], device=dev, dtype=dtype)
    if background is not None:
        bg[:, :3] = background.to(dev, dtype)
    near = float(nears.min()) if nears is not None else 0.01
    img, alpha, _ = rasterization(
        means.to(dev, dtype), quats.to(dev, dtype), scales.to(dev, dtype), opacities.to(dev, dtype), stacked,
        viewmats.to(dev, dtype), Ks.to(dev, dtype), int(width), int(height), near_plane=near, eps2d=0.3,
        packed=False, tile_size=16, backgrounds=bg, render_mode="RGB+ED", rasterize_mode="classic",
    )
    alpha = alpha[..., 0]
    out = {"rgb": img[..., :3], "depth": torch.where(alpha > 0, img[..., -1], torch.zeros_like(alpha)),
           "alpha": alpha, "features": img[..., 3:3 + n_feat] if n_feat else None}
    if ids_unique is not None and len(ids_unique):
        weights = img[..., 3 + n_feat:-1]
        best, arg = weights.max(dim=-1)
        inst = torch.where(best > (1.0 - alpha), ids_unique[arg], torch.full_like(arg, -1))
    else:
        inst = torch.full(alpha.shape, -1, dtype=torch.long, device=dev)
    out["instance"] = inst.to(torch.int32)
    return {k: (None if v is None else v.to(home)) for k, v in out.items()}


def render_batch_gsplat(views, features: bool = False) -> list[dict]:
    """`render_batch` on gsplat: views of one resolution go to one `rasterization` call with a
    leading batch axis (each view its own Gaussians, padded to the longest with Gaussians at the
    camera centre, which the near plane culls, and its own camera). `views` are
    (parts: list of numpy `Gaussians`, camera, background [3]); returns one dict of numpy arrays
    per view (as `render` gives for one camera). `BackendUnavailableError` without gsplat or CUDA."""
    check_gsplat()
    import numpy as np

    from ..scene.gaussians import Gaussians

    groups: dict[tuple[int, int], list[int]] = {}
    for i, (_, cam, _) in enumerate(views):
        groups.setdefault((cam.width, cam.height), []).append(i)
    out: list = [None] * len(views)
    for (w, h), members in groups.items():
        merged = [Gaussians.concat(views[i][0]) for i in members]
        cams = [views[i][1] for i in members]
        bgs = np.stack([views[i][2] for i in members])
        for i, res in zip(members, _rasterize_padded(merged, cams, bgs, w, h, features)):
            out[i] = res
    return out


def _rasterize_padded(gs, cams, bgs, width: int, height: int, features: bool) -> list[dict]:
    import numpy as np
    import torch
    from gsplat import rasterization

    dev = torch.device("cuda")
    f32 = torch.float32
    B = len(gs)
    nmax = max(1, max(len(g) for g in gs))
    n_feat = gs[0].feature_dim if features else 0
    ids_all = np.concatenate([g.object_ids for g in gs if g.object_ids is not None] or [np.zeros(0, np.int32)])
    ids_unique = np.unique(ids_all[ids_all >= 0])
    if len(ids_unique) > _MAX_INSTANCE_CHANNELS:
        raise ValueError(f"Expected at most {_MAX_INSTANCE_CHANNELS} objects per resolution group for the gsplat "
                         f"backend's instance map, found {len(ids_unique)}")
    K_ch = 3 + n_feat + len(ids_unique)
    means = np.zeros((B, nmax, 3), np.float32)
    quats = np.zeros((B, nmax, 4), np.float32)
    quats[..., 0] = 1.0
    scales = np.full((B, nmax, 3), 1e-4, np.float32)
    opac = np.zeros((B, nmax), np.float32)
    chans = np.zeros((B, nmax, K_ch), np.float32)
    for b, (g, cam) in enumerate(zip(gs, cams)):
        n = len(g)
        means[b, n:] = cam.position            # padding: at the camera centre, culled by the near plane
        means[b, :n], quats[b, :n], scales[b, :n], opac[b, :n] = g.means, g.quats, g.scales, g.opacities
        chans[b, :n, :3] = g.colors
        if n_feat:
            chans[b, :n, 3:3 + n_feat] = g.features
        if len(ids_unique) and g.object_ids is not None:
            chans[b, :n, 3 + n_feat:] = g.object_ids[:, None] == ids_unique[None, :]
    viewmats = np.stack([c.world_to_camera for c in cams]).astype(np.float32)[:, None]
    Ks = np.stack([c.K for c in cams]).astype(np.float32)[:, None]
    bg = np.zeros((B, 1, K_ch), np.float32)
    bg[:, 0, :3] = bgs
    near = float(min(c.near for c in cams))

    def cuda(x):
        return torch.from_numpy(np.ascontiguousarray(x)).to(dev, f32)

    img, alpha, _ = rasterization(cuda(means), cuda(quats), cuda(scales), cuda(opac), cuda(chans), cuda(viewmats),
                                  cuda(Ks), int(width), int(height), near_plane=near, eps2d=0.3, packed=False,
                                  tile_size=16, backgrounds=cuda(bg), render_mode="RGB+ED", rasterize_mode="classic")
    img = img[:, 0]
    alpha = alpha[:, 0, ..., 0]
    depth = torch.where(alpha > 0, img[..., -1], torch.zeros_like(alpha))
    if len(ids_unique):
        best, arg = img[..., 3 + n_feat:-1].max(dim=-1)
        lut = torch.as_tensor(ids_unique, device=dev, dtype=torch.long)
        inst = torch.where(best > (1.0 - alpha), lut[arg], torch.full_like(arg, -1))
    else:
        inst = torch.full(alpha.shape, -1, dtype=torch.long, device=dev)
    rgb, depth, alpha = img[..., :3].cpu().numpy(), depth.cpu().numpy(), alpha.cpu().numpy()
    inst = inst.to(torch.int32).cpu().numpy()
    feats = img[..., 3:3 + n_feat].cpu().numpy() if n_feat else None
    return [{"rgb": rgb[b], "depth": depth[b], "alpha": alpha[b], "instance": inst[b],
             "features": None if feats is None else feats[b]} for b in range(B)]
