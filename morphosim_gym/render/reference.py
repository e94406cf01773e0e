"""Readable torch reference of the splatting renderer (the `torch` backend).

Mirrors `morphosim_gym.render.cpu.rasterize_cpu` exactly (same projection, culling,
tiles, sort order, compositing rules and outputs) and gets its gradients from
autograd, so tests can check the compiled kernels, forward and backward, against it.
It never calls the fast path. It is written for clarity, not speed: each 16x16 tile
is composited densely over the Gaussians whose screen extent touches it.

Rules shared with the kernels:
    * camera-space z <= near: culled;
    * EWA: cov2d = J W Sigma W^T J^T + 0.3 I, with the Jacobian evaluated at x/z, y/z
      clamped to 1.3x the field of view (as in 3DGS);
    * opacity-aware extent: a Gaussian is drawn only where o * exp(-q/2) >= 1/255, i.e.
      q <= 2 ln(255 o); its screen box is +-sqrt(2 ln(255 o) * cov2d_ii) (+ a small margin);
      opacity below 1/255: culled;
    * per pixel, Gaussians in ascending depth (stable for ties); alpha = min(0.99, o exp(-q/2));
      alpha < 1/255: skipped; if T * (1 - alpha) < 1e-4 the pixel is finished before this
      Gaussian (early termination);
    * rgb = sum w_i c_i + T bg, alpha = 1 - T, depth = sum w_i z_i / alpha (0 where alpha = 0),
      features = sum w_i f_i, instance = object id of the largest w_i, or -1 where the
      remaining transmittance T is at least that weight (the background wins).
"""

from __future__ import annotations

import math
from typing import Optional

import torch

__all__ = ["project_torch", "rasterize_torch", "TILE", "ALPHA_MIN", "ALPHA_MAX", "T_MIN", "BLUR", "EXTENT_MARGIN"]

TILE = 16
ALPHA_MIN = 1.0 / 255.0
ALPHA_MAX = 0.99
T_MIN = 1e-4
BLUR = 0.3
FOV_CLAMP = 1.3
EXTENT_MARGIN = 0.05  # pixels added to each half-extent, so float rounding never drops a drawn pixel


def quat_to_rotmat_torch(quats: torch.Tensor) -> torch.Tensor:
    """[N, 4] (w, x, y, z), any norm -> [N, 3, 3] rotation matrices."""
    assert quats.ndim == 2 and quats.shape[1] == 4, f"quats: expected [N, 4], got {tuple(quats.shape)}"
    q = quats / quats.norm(dim=-1, keepdim=True)
    w, x, y, z = q.unbind(-1)
    return torch.stack([
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    ], dim=-1).reshape(-1, 3, 3)


def project_torch(means, quats, scales, opacities, viewmat, K, width: int, height: int, near: float):
    """Project N Gaussians into one camera. Mirrors the kernels' projection.

    Args:
        means: [N, 3]; quats: [N, 4]; scales: [N, 3]; opacities: [N]; viewmat: [4, 4] world->camera;
        K: [3, 3]; width, height: image size; near: near plane (camera z).

    Returns:
        dict with `xy` [N, 2] pixel centres, `depth` [N], `conic` [N, 3] (a, b, c of the inverse
        2D covariance), `extent` [N, 2] half-extents in pixels, `valid` [N] bool.
    """
    assert means.ndim == 2 and means.shape[1] == 3, f"means: expected [N, 3], got {tuple(means.shape)}"
    assert scales.shape == means.shape, f"scales: expected {tuple(means.shape)}, got {tuple(scales.shape)}"
    assert opacities.shape == means.shape[:1], f"opacities: expected [N], got {tuple(opacities.shape)}"
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    R_cam, t_cam = viewmat[:3, :3], viewmat[:3, 3]
    p = means @ R_cam.T + t_cam
    x, y, z = p.unbind(-1)
    valid = z > near
    zs = torch.where(valid, z, torch.ones_like(z))  # keep culled rows finite

    rot = quat_to_rotmat_torch(quats)
    M = rot * scales[:, None, :]                      # R S
    cov3 = M @ M.transpose(1, 2)                      # R S S^T R^T
    cov_cam = R_cam @ cov3 @ R_cam.T

    tan_fovx = 0.5 * width / fx
    tan_fovy = 0.5 * height / fy
    lim_x_pos = (width - cx) / fx + (FOV_CLAMP - 1.0) * tan_fovx
    lim_x_neg = cx / fx + (FOV_CLAMP - 1.0) * tan_fovx
    lim_y_pos = (height - cy) / fy + (FOV_CLAMP - 1.0) * tan_fovy
    lim_y_neg = cy / fy + (FOV_CLAMP - 1.0) * tan_fovy
    tx = zs * torch.clamp(x / zs, -lim_x_neg, lim_x_pos)
    ty = zs * torch.clamp(y / zs, -lim_y_neg, lim_y_pos)
    zeros = torch.zeros_like(zs)
    J = torch.stack([fx / zs, zeros, -fx * tx / (zs * zs),
                     zeros, fy / zs, -fy * ty / (zs * zs)], dim=-1).reshape(-1, 2, 3)
    cov2 = J @ cov_cam @ J.transpose(1, 2)
    a = cov2[:, 0, 0] + BLUR
    b = cov2[:, 0, 1]
    c = cov2[:, 1, 1] + BLUR
    det = a * c - b * b
    conic = torch.stack([c / det, -b / det, a / det], dim=-1)
    xy = torch.stack([fx * x / zs + cx, fy * y / zs + cy], dim=-1)

    op = opacities.detach()
    valid = valid & (op >= ALPHA_MIN) & (det.detach() > 0)
    level = 2.0 * torch.log(torch.clamp(255.0 * op, min=1.0))
    extent = torch.stack([torch.sqrt(level * a.detach()), torch.sqrt(level * c.detach())], dim=-1) + EXTENT_MARGIN
    return {"xy": xy, "depth": z, "conic": conic, "extent": extent, "valid": valid}


def rasterize_torch(
    means: torch.Tensor,        # [N, 3]
    quats: torch.Tensor,        # [N, 4]
    scales: torch.Tensor,       # [N, 3]
    opacities: torch.Tensor,    # [N]
    colors: torch.Tensor,       # [N, 3]
    viewmats: torch.Tensor,     # [C, 4, 4]
    Ks: torch.Tensor,           # [C, 3, 3]
    width: int,
    height: int,
    features: Optional[torch.Tensor] = None,    # [N, D]
    object_ids: Optional[torch.Tensor] = None,  # [N]
    background: Optional[torch.Tensor] = None,  # [3]
    nears: Optional[torch.Tensor] = None,       # [C]
) -> dict:
    """Render N Gaussians into C cameras. Reference twin of `rasterize_cpu`.

    Args:
        means: [N, 3]. quats: [N, 4] (w, x, y, z; normalised here). scales: [N, 3] std devs.
        opacities: [N]. colors: [N, 3]. viewmats: [C, 4, 4] world->camera (OpenCV). Ks: [C, 3, 3].
        width, height: image size. features: optional [N, D]. object_ids: optional [N] int.
        background: optional [3] colour (default black). nears: optional [C] near planes (0.01).

    Returns:
        dict with `rgb` [C, H, W, 3], `depth` [C, H, W], `alpha` [C, H, W], `instance` [C, H, W]
        int32 and, with features, `features` [C, H, W, D]; differentiable w.r.t. means, quats,
        scales, opacities, colors and features.

    Unlike the kernels it has no early exit for speed and does not support more than a few
    thousand Gaussians per tile within reasonable memory.
    """
    N = means.shape[0]
    C = viewmats.shape[0]
    assert viewmats.shape == (C, 4, 4), f"viewmats: expected [C, 4, 4], got {tuple(viewmats.shape)}"
    assert Ks.shape == (C, 3, 3), f"Ks: expected [{C}, 3, 3], got {tuple(Ks.shape)}"
    assert colors.shape == (N, 3), f"colors: expected [{N}, 3], got {tuple(colors.shape)}"
    dtype = means.dtype
    if background is None:
        background = torch.zeros(3, dtype=dtype)
    if nears is None:
        nears = torch.full((C,), 0.01, dtype=torch.float64)
    D = 0 if features is None else features.shape[1]
    if object_ids is None:
        object_ids = torch.full((N,), -1, dtype=torch.int32)

    tiles_x = math.ceil(width / TILE)
    tiles_y = math.ceil(height / TILE)
    out = {"rgb": [], "depth": [], "alpha": [], "instance": [], "features": []}
    for ci in range(C):
        proj = project_torch(means, quats, scales, opacities, viewmats[ci].to(dtype), Ks[ci].to(dtype),
                             width, height, float(nears[ci]))
        order = torch.sort(proj["depth"].detach(), stable=True).indices
        valid = proj["valid"][order]
        order = order[valid]
        xy, conic, depth = proj["xy"][order], proj["conic"][order], proj["depth"][order]
        ext = proj["extent"][order]
        op, col = opacities[order], colors[order]
        feat = features[order] if D else None
        ids = object_ids[order]
        lo = (xy.detach() - ext)
        hi = (xy.detach() + ext)

        rows = {k: [] for k in out}
        for ty in range(tiles_y):
            row = {k: [] for k in out}
            for tx in range(tiles_x):
                x0, y0 = tx * TILE, ty * TILE
                # pixel centres of this tile (a full 16x16 block; cropped at the end)
                px = x0 + torch.arange(TILE, dtype=dtype) + 0.5
                py = y0 + torch.arange(TILE, dtype=dtype) + 0.5
                gx, gy = torch.meshgrid(px, py, indexing="xy")          # [16, 16] (rows = y)
                pix = torch.stack([gx.reshape(-1), gy.reshape(-1)], -1)  # [P, 2]
                touch = (hi[:, 0] >= x0 + 0.5) & (lo[:, 0] <= x0 + TILE - 0.5) & \
                        (hi[:, 1] >= y0 + 0.5) & (lo[:, 1] <= y0 + TILE - 0.5)
                idx = torch.nonzero(touch).squeeze(1)
                res = _composite(pix, xy[idx], conic[idx], op[idx], col[idx], depth[idx],
                                 None if feat is None else feat[idx], ids[idx], background, dtype)
                for k in out:
                    row[k].append(None if res[k] is None else res[k].reshape((TILE, TILE) + res[k].shape[1:]))
            for k in out:
                rows[k].append(None if row[k][0] is None else torch.cat(row[k], dim=1))
        for k in out:
            out[k].append(None if rows[k][0] is None else torch.cat(rows[k], dim=0)[:height, :width])
    result = {k: torch.stack(v) for k, v in out.items() if v[0] is not None}
    result["instance"] = result["instance"].to(torch.int32)
    return result


def _composite(pix, xy, conic, op, col, depth, feat, ids, background, dtype):
    """Front-to-back compositing of depth-sorted Gaussians over pixels [P, 2]."""
    P, n = pix.shape[0], xy.shape[0]
    d = xy[None, :, :] - pix[:, None, :]                              # [P, n, 2]
    a, b, c = conic[:, 0], conic[:, 1], conic[:, 2]
    power = -0.5 * (a * d[..., 0] ** 2 + c * d[..., 1] ** 2) - b * d[..., 0] * d[..., 1]
    alpha = torch.clamp(op * torch.exp(power), max=ALPHA_MAX)
    drawn = (alpha >= ALPHA_MIN) & (power <= 0)
    alpha = torch.where(drawn, alpha, torch.zeros_like(alpha))
    one_minus = 1.0 - alpha
    T_incl = torch.cumprod(one_minus, dim=1)                          # T after each Gaussian
    alive = T_incl >= T_MIN                                           # prefix: not yet terminated
    alpha = torch.where(alive, alpha, torch.zeros_like(alpha))
    T_incl = torch.cumprod(1.0 - alpha, dim=1)
    T_excl = torch.cat([torch.ones(P, 1, dtype=dtype), T_incl[:, :-1]], dim=1)
    w = alpha * T_excl                                                # [P, n]
    T_final = T_incl[:, -1] if n else torch.ones(P, dtype=dtype)
    rgb = w @ col + T_final[:, None] * background[None, :]
    acc = 1.0 - T_final
    dsum = w @ depth
    depth_out = torch.where(acc > 0, dsum / torch.where(acc > 0, acc, torch.ones_like(acc)), torch.zeros_like(acc))
    features = (w @ feat) if feat is not None else None
    if n:
        wmax, arg = w.detach().max(dim=1)
        inst = torch.where(wmax > T_final.detach(), ids[arg].to(torch.int64), torch.full_like(arg, -1))
    else:
        inst = torch.full((P,), -1, dtype=torch.int64)
    return {"rgb": rgb, "depth": depth_out, "alpha": acc, "instance": inst, "features": features}
