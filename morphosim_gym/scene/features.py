"""`FeatureDecoder`: a small MLP from the latent feature field into one 2D encoder's space.

The paper's decoders D^s are trained on rasterised 2D feature maps and applied
directly to per-Gaussian 3D features at edit time. Weights are stored as numpy
arrays so a scene needs no torch to be loaded, saved or queried.

`instance_codes` are the targets of the "instance" channel: one unit vector per instance id of
the 2D masks the field was distilled from, so that two objects with the same label ("sheep 1",
"sheep 2", whose sentence embeddings are 0.89 alike) still read apart.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["FeatureDecoder", "instance_codes", "INSTANCE_DIM"]

INSTANCE_DIM = 16


@dataclass(eq=False)
class FeatureDecoder:
    """MLP: `x -> W_L(... relu(W_1 x + b_1) ...) + b_L`.

    Attributes:
        name: the encoder space this decodes into (e.g. "semantic", "color").
        weights: per layer, [in, out] matrices.
        biases: per layer, [out] vectors.
        normalize: L2-normalise the output (for cosine-similarity spaces).
    """

    name: str
    weights: Sequence[np.ndarray]
    biases: Sequence[np.ndarray]
    normalize: bool = False

    def __post_init__(self) -> None:
        self.weights = [np.ascontiguousarray(w, dtype=np.float32) for w in self.weights]
        self.biases = [np.ascontiguousarray(b, dtype=np.float32) for b in self.biases]
        if not self.weights or len(self.weights) != len(self.biases):
            raise ValueError(f"Expected as many biases as weights (>= 1), found {len(self.weights)} weights "
                             f"and {len(self.biases)} biases")
        prev = None
        for i, (w, b) in enumerate(zip(self.weights, self.biases)):
            if w.ndim != 2 or b.shape != (w.shape[1],):
                raise ValueError(f"Expected layer {i} weight [in, out] and bias [out], found {w.shape}, {b.shape}")
            if prev is not None and w.shape[0] != prev:
                raise ValueError(f"Expected layer {i} input width {prev}, found {w.shape[0]}")
            if not (np.all(np.isfinite(w)) and np.all(np.isfinite(b))):
                raise ValueError(f"Expected finite weights in layer {i}")
            prev = w.shape[1]

    @property
    def in_dim(self) -> int:
        """Latent width D."""
        return int(self.weights[0].shape[0])

    @property
    def out_dim(self) -> int:
        """Encoder width D_s."""
        return int(self.weights[-1].shape[1])

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Decode [..., D] latents to [..., D_s]."""
        h = self._hidden(x)
        h = h @ self.weights[-1]
        h += self.biases[-1]
        if self.normalize:
            h /= np.maximum(np.sqrt(np.einsum("...i,...i->...", h, h)), 1e-12)[..., None]
        return h

    def similarity(self, x: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """[..., P] dot products of the decoded [..., D] latents with `targets` [P, D_s] (cosine
        similarities for a normalising decoder), equal to `self(x) @ targets.T`.

        The decoded vectors are never formed: the last layer is folded into the targets, and
        the norms come from the last layer's Gram matrix, so the cost is that of the hidden
        layers (a query over 60k Gaussians takes milliseconds instead of decoding 60k x 384)."""
        t = np.asarray(targets, dtype=np.float32)
        if t.ndim != 2 or t.shape[1] != self.out_dim:
            raise ValueError(f"Expected targets [P, {self.out_dim}], found {t.shape}")
        h = self._hidden(x)
        w, b = self.weights[-1], self.biases[-1]
        s = h @ (w @ t.T) + b @ t.T
        if self.normalize:
            # |h W + b|^2 = h (W W^T) h^T + 2 h (W b) + b b
            sq = np.einsum("...i,...i->...", h @ (w @ w.T), h) + 2.0 * (h @ (w @ b)) + b @ b
            s /= np.maximum(np.sqrt(np.maximum(sq, 0.0)), 1e-12)[..., None]
        return s

    def _hidden(self, x: np.ndarray) -> np.ndarray:
        """The input of the last layer for [..., D] latents."""
        h = np.asarray(x, dtype=np.float32)
        if h.shape[-1] != self.in_dim:
            raise ValueError(f"Expected features with last dimension {self.in_dim}, found {h.shape}")
        for w, b in zip(self.weights[:-1], self.biases[:-1]):
            h = np.maximum(h @ w + b, 0.0)
        return h

    def arrays(self) -> dict[str, np.ndarray]:
        """Flat dict of arrays for serialisation."""
        out = {}
        for i, (w, b) in enumerate(zip(self.weights, self.biases)):
            out[f"w{i}"] = w
            out[f"b{i}"] = b
        return out

    @classmethod
    def from_arrays(cls, name: str, arrays: dict[str, np.ndarray], normalize: bool) -> "FeatureDecoder":
        """Inverse of `arrays`."""
        n = len([k for k in arrays if k.startswith("w")])
        return cls(name, [arrays[f"w{i}"] for i in range(n)], [arrays[f"b{i}"] for i in range(n)], normalize)


def instance_codes(ids: Sequence[int], dim: int = INSTANCE_DIM) -> np.ndarray:
    """[len(ids), dim] unit vectors, one per instance id: the basis vector e_id for 0 <= id < dim
    (mutually orthogonal), a fixed random unit vector drawn from the id beyond that (or for a
    negative id)."""
    if dim < 1:
        raise ValueError(f"Expected an instance code width >= 1, found {dim}")
    out = np.zeros((len(ids), dim), np.float32)
    for row, k in enumerate(int(i) for i in ids):
        if 0 <= k < dim:
            out[row, k] = 1.0
        else:
            v = np.random.default_rng([abs(k), k < 0, 0x1D5]).normal(size=dim)
            out[row] = v / np.linalg.norm(v)
    return out
