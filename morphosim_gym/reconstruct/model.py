"""The optimisable 4D model: canonical Gaussians, a motion scaffold of rigid nodes, a feature field.

Parameters live in one `torch.nn.Module`; activations follow 3DGS (log scales, opacity
logits, colour logits). Each Gaussian is skinned to up to `M` nodes with RBF weights on
its canonical distance to the node centres; static Gaussians are bound to no node.
Node poses are per frame: rotation (unit quaternion) and translation mapping canonical
points to that frame's world.
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from ..scene import Gaussians, Motion
from ..scene.rotations import quat_normalize, quat_to_matrix

__all__ = ["DynamicGaussians", "quat_to_rotmat", "rbf_skinning", "inverse_sigmoid", "gather_rows"]


def inverse_sigmoid(x: np.ndarray | torch.Tensor, eps: float = 1e-4):
    """logit, with the input clipped to (eps, 1 - eps)."""
    if isinstance(x, torch.Tensor):
        x = x.clamp(eps, 1 - eps)
        return torch.log(x / (1 - x))
    x = np.clip(x, eps, 1 - eps)
    return np.log(x / (1 - x))


def gather_rows(x: torch.Tensor, index: torch.Tensor) -> torch.Tensor:
    """x[index] for an integer index of any shape, with a deterministic backward.

    On CPU, the backward of advanced indexing (`x[index]`) accumulates repeated rows with
    atomic adds across threads, so the gradient of a row that many entries share (a node that
    skins thousands of Gaussians) changes in its last bits from run to run, and a long fit
    drifts apart. `index_select`'s backward sums in index order.
    """
    flat = torch.index_select(x, 0, index.reshape(-1))
    return flat.reshape(tuple(index.shape) + tuple(x.shape[1:]))


def quat_to_rotmat(q: torch.Tensor) -> torch.Tensor:
    """[..., 4] (w, x, y, z), any norm -> [..., 3, 3]."""
    q = q / q.norm(dim=-1, keepdim=True)
    w, x, y, z = q.unbind(-1)
    m = torch.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                     2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                     2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], dim=-1)
    return m.reshape(q.shape[:-1] + (3, 3))


def quat_mul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product of [..., 4] quaternions."""
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                        aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], dim=-1)


def rbf_skinning(points: np.ndarray, point_objects: np.ndarray, centres: np.ndarray, node_objects: np.ndarray,
                 slots: int = 4, radius: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Bind points to their nearest nodes of the same object: node indices [n, slots] (-1 unused)
    and normalised RBF weights exp(-d^2 / (2 r^2)) [n, slots]; points of objects without nodes
    stay unbound."""
    n = len(points)
    nodes = np.full((n, slots), -1, np.int32)
    weights = np.zeros((n, slots), np.float32)
    for obj in np.unique(node_objects):
        own_nodes = np.flatnonzero(node_objects == obj)
        own_pts = np.flatnonzero(point_objects == obj)
        if len(own_nodes) == 0 or len(own_pts) == 0:
            continue
        c = centres[own_nodes]
        d2 = ((points[own_pts, None, :] - c[None]) ** 2).sum(-1)
        k = min(slots, len(own_nodes))
        order = np.argsort(d2, axis=1)[:, :k]
        dk = np.take_along_axis(d2, order, axis=1)
        if radius is None:
            spread = np.sqrt(np.median(dk[:, -1])) if k > 1 else 1.0
            r = max(spread, 1e-3)
        else:
            r = radius
        w = np.exp(-(dk - dk[:, :1]) / (2 * r * r))
        w /= w.sum(axis=1, keepdims=True)
        nodes[own_pts, :k] = own_nodes[order]
        weights[own_pts, :k] = w
    return nodes, weights


class DynamicGaussians(nn.Module):
    """Canonical Gaussians + per-frame node poses (+ optional latent features).

    Args:
        means, quats, scales, opacities, colors: initial canonical Gaussians (activated values).
        object_ids: [N] instance each Gaussian was initialised from.
        node_centres: [K, 3] canonical node positions; node_objects: [K] their instances.
        node_rot: [T, K, 3, 3], node_trans: [T, K, 3] initial poses (x_t = R x + t, rotations about
            the world origin, as `Motion` stores them).
        slots: nodes per Gaussian.

    Each node turns about its own centre: the parameter `node_trans` is the node centre's
    displacement (t + R c - c), so an optimiser's step on a node's rotation does not also move it.
    Turned about the world origin, an object metres away from it moved by metres times each of
    Adam's (unit-size) steps on its rotation: a kite's fitted path ended 10-17 px off on 4 of 13
    input views, its initial poses within 1 px.
    """

    def __init__(self, means, quats, scales, opacities, colors, object_ids, node_centres, node_objects,
                 node_rot, node_trans, slots: int = 4) -> None:
        super().__init__()
        f = torch.float32
        self.means = nn.Parameter(torch.as_tensor(means, dtype=f))
        self.quats = nn.Parameter(torch.as_tensor(quat_normalize(np.asarray(quats, np.float64)), dtype=f))
        self.log_scales = nn.Parameter(torch.log(torch.as_tensor(scales, dtype=f)))
        self.opacity_logits = nn.Parameter(torch.as_tensor(inverse_sigmoid(np.asarray(opacities)), dtype=f))
        self.color_logits = nn.Parameter(torch.as_tensor(inverse_sigmoid(np.asarray(colors), 1e-3), dtype=f))
        self.register_buffer("object_ids", torch.as_tensor(np.asarray(object_ids), dtype=torch.int32))
        self.register_buffer("node_centres", torch.as_tensor(node_centres, dtype=f))
        self.register_buffer("node_objects", torch.as_tensor(np.asarray(node_objects), dtype=torch.int32))
        from ..scene.rotations import matrix_to_quat

        rq = matrix_to_quat(np.asarray(node_rot)) if len(node_centres) else np.zeros((len(node_rot), 0, 4))
        self.node_quats = nn.Parameter(torch.as_tensor(rq, dtype=f))
        c = np.asarray(node_centres, np.float64).reshape(-1, 3)
        moved = np.einsum("tkij,kj->tki", np.asarray(node_rot, np.float64).reshape(-1, len(c), 3, 3), c) \
            if len(c) else np.zeros((len(node_rot), 0, 3))
        self.node_trans = nn.Parameter(torch.as_tensor(np.asarray(node_trans, np.float64) + moved - c, dtype=f))
        self.slots = slots
        self.features: nn.Parameter | None = None
        self.rebind()

    # -------------------------------------------------------------- binding
    @torch.no_grad()
    def rebind(self) -> None:
        """Recompute the skinning of every Gaussian (after densification or pruning)."""
        nodes, weights = rbf_skinning(self.means.detach().numpy().astype(np.float64), self.object_ids.numpy(),
                                      self.node_centres.numpy().astype(np.float64), self.node_objects.numpy(),
                                      self.slots)
        self.skin_nodes = torch.as_tensor(nodes, dtype=torch.long)
        self.skin_weights = torch.as_tensor(weights, dtype=torch.float32)
        self.bound = (self.skin_nodes >= 0).any(dim=1)
        # what `warp` reads of the binding, once per binding: the bound rows, each one's weight on
        # every node [B, K] (a few nodes per moving object: dense products beat gathering [B, M]
        # node transforms and scattering their gradients back) and its first node
        rows = torch.nonzero(self.bound).reshape(-1)
        nodes = self.skin_nodes.index_select(0, rows).clamp(min=0)
        self._bound_rows = rows
        self._bound_first = nodes[:, 0]
        self._bound_dense = torch.zeros(len(rows), self.node_quats.shape[1]).scatter_add_(
            1, nodes, self.skin_weights.index_select(0, rows))

    # ----------------------------------------------------------- properties
    @property
    def num(self) -> int:
        return int(self.means.shape[0])

    @property
    def num_frames(self) -> int:
        return int(self.node_trans.shape[0])

    def scales(self) -> torch.Tensor:
        return torch.exp(self.log_scales)

    def opacities(self) -> torch.Tensor:
        return torch.sigmoid(self.opacity_logits)

    def colors(self) -> torch.Tensor:
        return torch.sigmoid(self.color_logits)

    # --------------------------------------------------------------- motion
    def warp(self, frame: int) -> tuple[torch.Tensor, torch.Tensor]:
        """World means [N, 3] and quats [N, 4] at an integer frame (linear blend skinning)."""
        if self.node_quats.shape[1] == 0:
            return self.means, self.quats
        q = self.node_quats[frame] / self.node_quats[frame].norm(dim=-1, keepdim=True)   # [K, 4]
        R = quat_to_rotmat(q)                                                            # [K, 3, 3]
        tr = self._origin_trans(R, frame)                                                # [K, 3]
        rows, dense = self._bound_rows, self._bound_dense                               # [B], [B, K]
        blended = dense @ torch.cat([R.reshape(-1, 9), tr], dim=1)                       # [B, 12]
        m = self.means.index_select(0, rows)
        moved = (blended[:, :9].reshape(-1, 3, 3) * m[:, None, :]).sum(-1) + blended[:, 9:]
        means = self.means.index_copy(0, rows, moved)
        # each node's quaternion on the side of the Gaussian's first node's (q and -q are one rotation)
        with torch.no_grad():
            sign = torch.where(q @ q.T < 0, -1.0, 1.0).index_select(0, self._bound_first)  # [B, K]
        blend = (dense * sign) @ q
        blend = blend / blend.norm(dim=-1, keepdim=True)
        quats = self.quats.index_copy(0, rows, quat_mul(blend, self.quats.index_select(0, rows)))
        return means, quats

    def _origin_trans(self, R: torch.Tensor, frame: int) -> torch.Tensor:
        """[K, 3] each node's translation about the world origin at a frame (x_t = R x + t) from its
        rotations R [K, 3, 3] and its centre's displacement `node_trans[frame]`: t = d + c - R c."""
        c = self.node_centres
        return self.node_trans[frame] + c - (R @ c[:, :, None])[..., 0]

    def points_at(self, points: torch.Tensor, nodes: torch.Tensor, weights: torch.Tensor, frame: int) -> torch.Tensor:
        """Move canonical points [P, 3] with given skinning [P, M] to a frame."""
        q = self.node_quats[frame] / self.node_quats[frame].norm(dim=-1, keepdim=True)
        R = quat_to_rotmat(q)
        tr = self._origin_trans(R, frame)
        idx = nodes.clamp(min=0)
        moved = torch.einsum("pmij,pj->pmi", gather_rows(R, idx), points) + gather_rows(tr, idx)
        w = torch.where(nodes >= 0, weights, torch.zeros_like(weights))
        return (w[..., None] * moved).sum(1)

    # ---------------------------------------------------------------- export
    @torch.no_grad()
    def to_scene_parts(self) -> tuple[Gaussians, Motion]:
        """Canonical `Gaussians` (numpy) and the `Motion` of this model."""
        feats = None if self.features is None else self.features.detach().numpy().copy()
        g = Gaussians(means=self.means.detach().numpy().copy(), quats=self.quats.detach().numpy().copy(),
                      scales=self.scales().numpy().copy(), opacities=self.opacities().numpy().copy(),
                      colors=self.colors().numpy().copy(), features=feats,
                      object_ids=self.object_ids.numpy().copy())
        q = self.node_quats.detach().numpy().astype(np.float64)
        if q.size:
            q = q / np.linalg.norm(q, axis=-1, keepdims=True)
        c = self.node_centres.numpy().astype(np.float64)
        trans = self.node_trans.detach().numpy().astype(np.float64) + c
        if q.size:
            trans -= np.einsum("tkij,kj->tki", quat_to_matrix(q), c)
        motion = Motion(q, trans, self.skin_nodes.numpy(),
                        self.skin_weights.numpy(), self.node_objects.numpy())
        return g, motion

    def extra_repr(self) -> str:
        return f"gaussians={self.num}, nodes={self.node_centres.shape[0]}, frames={self.num_frames}"

