"""`Motion`: rigid poses of scaffold nodes over time, and Gaussians skinned to them.

A node is a rigid frame (a whole rigid object is one node; a deforming object is a
motion scaffold of several). At frame f node k maps canonical points x to
`R[f, k] @ x + T[f, k]`. Each Gaussian is bound to up to M nodes with weights that sum
to one (linear blend skinning); a Gaussian bound to no node is static.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numba
import numpy as np

from ..parallel import kernel_lock
from .rotations import quat_normalize, quat_slerp, quat_to_matrix

__all__ = ["Motion", "skin"]


@dataclass(eq=False)
class Motion:
    """Node trajectories and the skinning of Gaussians to nodes.

    Attributes:
        rotations: [T, K, 4] node rotations (w, x, y, z) per frame, canonical -> world.
        translations: [T, K, 3] node translations per frame, metres.
        skin_nodes: [N, M] int32 node index per binding, -1 for an unused slot.
        skin_weights: [N, M] float32 binding weights; each bound row sums to 1.
        node_objects: [K] int32 object id each node belongs to (-1 for none).
        shown: [T, K] bool, where each node is drawn (None: every node at every frame). A Gaussian
            bound to a node not shown at the frame nearest a time is not drawn then (a video's
            per-frame layers are shown only around their own frame).
    """

    rotations: np.ndarray
    translations: np.ndarray
    skin_nodes: np.ndarray
    skin_weights: np.ndarray
    node_objects: np.ndarray
    shown: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.rotations = np.ascontiguousarray(self.rotations, dtype=np.float64)
        self.translations = np.ascontiguousarray(self.translations, dtype=np.float64)
        self.skin_nodes = np.ascontiguousarray(self.skin_nodes, dtype=np.int32)
        self.skin_weights = np.ascontiguousarray(self.skin_weights, dtype=np.float32)
        self.node_objects = np.ascontiguousarray(self.node_objects, dtype=np.int32)
        r, tr = self.rotations, self.translations
        if r.ndim != 3 or r.shape[2] != 4 or r.shape[0] < 1:
            raise ValueError(f"Expected rotations of shape (T, K, 4) with T >= 1, found {r.shape}")
        if tr.shape != r.shape[:2] + (3,):
            raise ValueError(f"Expected translations of shape {r.shape[:2] + (3,)}, found {tr.shape}")
        if not (np.all(np.isfinite(r)) and np.all(np.isfinite(tr))):
            raise ValueError("Expected finite rotations and translations, found non-finite values")
        if r.size:
            norms = np.linalg.norm(r, axis=-1)
            if norms.min() < 1e-9:
                raise ValueError("Expected non-zero rotation quaternions, found a quaternion of norm 0")
            self.rotations = quat_normalize(r)
        k = r.shape[1]
        if self.skin_nodes.ndim != 2 or self.skin_weights.shape != self.skin_nodes.shape:
            raise ValueError(f"Expected skin_nodes and skin_weights of one shape (N, M), found "
                             f"{self.skin_nodes.shape} and {self.skin_weights.shape}")
        if self.skin_nodes.size and (self.skin_nodes.min() < -1 or self.skin_nodes.max() >= k):
            raise ValueError(f"Expected skin_nodes in [-1, {k}), found range "
                             f"[{self.skin_nodes.min()}, {self.skin_nodes.max()}]")
        if not np.all(np.isfinite(self.skin_weights)) or (self.skin_weights.size and self.skin_weights.min() < 0):
            raise ValueError("Expected finite, non-negative skin_weights")
        bound = self.skin_nodes >= 0
        sums = np.where(bound, self.skin_weights, 0).sum(axis=1)
        rows = bound.any(axis=1)
        if np.any(np.abs(sums[rows] - 1.0) > 1e-4):
            raise ValueError("Expected the skin_weights of each bound Gaussian to sum to 1, "
                             f"found sums in [{sums[rows].min():.4f}, {sums[rows].max():.4f}]")
        if self.node_objects.shape != (k,):
            raise ValueError(f"Expected node_objects of shape ({k},), found {self.node_objects.shape}")
        if self.shown is not None:
            shown = np.asarray(self.shown)
            if shown.shape != r.shape[:2] or shown.dtype != np.bool_:
                raise ValueError(f"Expected shown as a bool array of shape {r.shape[:2]}, found "
                                 f"{shown.dtype} {shown.shape}")
            self.shown = np.ascontiguousarray(shown)

    # ------------------------------------------------------------ constructors
    @classmethod
    def static(cls, num_gaussians: int, num_frames: int = 1) -> "Motion":
        """No nodes: every Gaussian stays where it is."""
        return cls(np.zeros((num_frames, 0, 4)), np.zeros((num_frames, 0, 3)),
                   np.full((num_gaussians, 1), -1), np.zeros((num_gaussians, 1)), np.zeros(0))

    @classmethod
    def rigid(cls, node_of_gaussian: np.ndarray, rotations: np.ndarray, translations: np.ndarray,
              node_objects: np.ndarray) -> "Motion":
        """Each Gaussian bound to one node (or -1 for static), weight 1."""
        nodes = np.asarray(node_of_gaussian, dtype=np.int32).reshape(-1, 1)
        return cls(rotations, translations, nodes, (nodes >= 0).astype(np.float32), node_objects)

    # -------------------------------------------------------------- properties
    @property
    def num_frames(self) -> int:
        """T."""
        return int(self.rotations.shape[0])

    @property
    def num_nodes(self) -> int:
        """K."""
        return int(self.rotations.shape[1])

    @property
    def num_gaussians(self) -> int:
        """N."""
        return int(self.skin_nodes.shape[0])

    # -------------------------------------------------------------- evaluation
    def node_poses(self, frame: float) -> tuple[np.ndarray, np.ndarray]:
        """Node rotations [K, 4] and translations [K, 3] at a fractional frame index, slerped and
        lerped between the two nearest frames."""
        t_count = self.num_frames
        if t_count == 1 or self.num_nodes == 0:
            return self.rotations[0], self.translations[0]
        i0 = int(np.floor(frame))
        i0 = min(max(i0, 0), t_count - 2)
        u = float(frame) - i0
        if u <= 0.0:
            return self.rotations[i0], self.translations[i0]
        if u >= 1.0:
            return self.rotations[i0 + 1], self.translations[i0 + 1]
        rot = quat_slerp(self.rotations[i0], self.rotations[i0 + 1], np.full(self.num_nodes, u))
        trans = (1.0 - u) * self.translations[i0] + u * self.translations[i0 + 1]
        return rot, trans

    def apply(self, means: np.ndarray, quats: np.ndarray, frame: float) -> tuple[np.ndarray, np.ndarray]:
        """World means [N, 3] and quats [N, 4] of canonical Gaussians at a fractional frame index."""
        rot, trans = self.node_poses(frame)
        return skin(means, quats, self.skin_nodes, self.skin_weights, rot, trans)

    def nearest_frame(self, frame: float) -> int:
        """The frame whose `shown` row applies at a fractional frame index (halves round up)."""
        return min(max(int(np.floor(float(frame) + 0.5)), 0), self.num_frames - 1)

    def drawn(self, frame: float) -> np.ndarray | None:
        """[N] bool: the Gaussians drawn at a fractional frame index (every bound node shown at the
        nearest frame; unbound ones always), or None when every Gaussian is drawn at every frame."""
        if self.shown is None:
            return None
        shown = self.shown[self.nearest_frame(frame)]
        if shown.all():
            return None
        rows, nodes = self._bindings()
        out = np.ones(self.num_gaussians, bool)
        out[rows[~shown[nodes]]] = False
        return out

    def _bindings(self) -> tuple[np.ndarray, np.ndarray]:
        """(row, node) of every binding of a Gaussian to a node, computed once: a scene freezes
        its skinning arrays."""
        cached = self.__dict__.get("_bindings_cache")
        if cached is None:
            row, slot = np.nonzero(self.skin_nodes >= 0)
            cached = self.__dict__["_bindings_cache"] = (row, self.skin_nodes[row, slot])
        return cached

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays that define this motion, by field name (`shown` only when set)."""
        out = {"rotations": self.rotations, "translations": self.translations, "skin_nodes": self.skin_nodes,
               "skin_weights": self.skin_weights, "node_objects": self.node_objects}
        if self.shown is not None:
            out["shown"] = self.shown
        return out

    def copy(self, **changes: Any) -> "Motion":
        """A copy with some arrays replaced (the others copied)."""
        arrays = {k: v.copy() for k, v in self.arrays().items()}
        arrays.update(changes)
        return Motion(**arrays)


_SKIN_CHUNK = 4096   # Gaussians per parallel task of the skinning kernel


def skin(means: np.ndarray, quats: np.ndarray, skin_nodes: np.ndarray, skin_weights: np.ndarray,
         node_rotations: np.ndarray, node_translations: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear blend skinning of Gaussians: means [N, 3] and quats [N, 4] moved by nodes [K]."""
    if node_rotations.shape[0] == 0:
        return means.astype(np.float32, copy=True), quats.astype(np.float32, copy=True)
    mats = quat_to_matrix(node_rotations).astype(np.float64)
    q = np.ascontiguousarray(node_rotations, dtype=np.float64)
    t = np.ascontiguousarray(node_translations, dtype=np.float64)
    out_m = np.empty((means.shape[0], 3), dtype=np.float32)
    out_q = np.empty((means.shape[0], 4), dtype=np.float32)
    args = (np.ascontiguousarray(means, dtype=np.float32), np.ascontiguousarray(quats, dtype=np.float32),
            skin_nodes, skin_weights, mats, q, t, out_m, out_q)
    if means.shape[0] <= _SKIN_CHUNK:
        _skin_range(0, means.shape[0], *args)     # one chunk: skip the parallel launch
    else:
        with kernel_lock():                       # one launch at a time under numba's workqueue layer
            _skin_kernel(*args)
    return out_m, out_q


@numba.njit(cache=True, fastmath=False, nogil=True)
def _skin_range(start, stop, means, quats, nodes, weights, mats, nq, nt, out_m, out_q):  # pragma: no cover
    m_slots = nodes.shape[1]
    for i in range(start, stop):
        px = np.float64(means[i, 0])
        py = np.float64(means[i, 1])
        pz = np.float64(means[i, 2])
        ax = 0.0
        ay = 0.0
        az = 0.0
        bw = 0.0
        bx = 0.0
        by = 0.0
        bz = 0.0
        total = 0.0
        ref = -1
        for s in range(m_slots):
            k = nodes[i, s]
            if k < 0:
                continue
            w = np.float64(weights[i, s])
            total += w
            ax += w * (mats[k, 0, 0] * px + mats[k, 0, 1] * py + mats[k, 0, 2] * pz + nt[k, 0])
            ay += w * (mats[k, 1, 0] * px + mats[k, 1, 1] * py + mats[k, 1, 2] * pz + nt[k, 1])
            az += w * (mats[k, 2, 0] * px + mats[k, 2, 1] * py + mats[k, 2, 2] * pz + nt[k, 2])
            sign = 1.0
            if ref < 0:
                ref = k
            elif nq[k, 0] * nq[ref, 0] + nq[k, 1] * nq[ref, 1] + nq[k, 2] * nq[ref, 2] + nq[k, 3] * nq[ref, 3] < 0:
                sign = -1.0
            bw += sign * w * nq[k, 0]
            bx += sign * w * nq[k, 1]
            by += sign * w * nq[k, 2]
            bz += sign * w * nq[k, 3]
        if total <= 0.0:
            for c in range(3):
                out_m[i, c] = means[i, c]
            for c in range(4):
                out_q[i, c] = quats[i, c]
            continue
        out_m[i, 0] = ax
        out_m[i, 1] = ay
        out_m[i, 2] = az
        n = np.sqrt(bw * bw + bx * bx + by * by + bz * bz)
        bw /= n
        bx /= n
        by /= n
        bz /= n
        cw = np.float64(quats[i, 0])
        cx = np.float64(quats[i, 1])
        cy = np.float64(quats[i, 2])
        cz = np.float64(quats[i, 3])
        out_q[i, 0] = bw * cw - bx * cx - by * cy - bz * cz
        out_q[i, 1] = bw * cx + bx * cw + by * cz - bz * cy
        out_q[i, 2] = bw * cy - bx * cz + by * cw + bz * cx
        out_q[i, 3] = bw * cz + bx * cy - by * cx + bz * cw


@numba.njit(cache=True, parallel=True, nogil=True)
def _skin_kernel(means, quats, nodes, weights, mats, nq, nt, out_m, out_q):  # pragma: no cover
    n = means.shape[0]
    chunk = _SKIN_CHUNK
    n_chunks = (n + chunk - 1) // chunk
    for c in numba.prange(n_chunks):
        _skin_range(c * chunk, min(n, (c + 1) * chunk), means, quats, nodes, weights, mats, nq, nt, out_m, out_q)
