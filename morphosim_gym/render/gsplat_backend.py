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

__all__ = ["check_gsplat", "rasterize_gsplat"]

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
