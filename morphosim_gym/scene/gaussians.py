"""`Gaussians`: a set of 3D Gaussians with activated (user-facing) attributes."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any, Sequence

import numpy as np

__all__ = ["Gaussians"]

_FLOAT_FIELDS = ("means", "quats", "scales", "opacities", "colors")


def _is_torch(x: Any) -> bool:
    return type(x).__module__.startswith("torch")


def _as_numpy(x: Any) -> np.ndarray:
    if _is_torch(x):
        return x.detach().cpu().numpy()
    return np.asarray(x)


@dataclass(eq=False)
class Gaussians:
    """N 3D Gaussians in world coordinates (z-up, metres).

    Arrays are numpy (float32) or torch tensors; with torch tensors that require
    gradients, `morphosim_gym.render` returns differentiable torch outputs.

    Attributes:
        means: [N, 3] centres.
        quats: [N, 4] orientations as w, x, y, z (normalised by the renderer).
        scales: [N, 3] standard deviations along the local axes, metres, > 0.
        opacities: [N] peak opacities in [0, 1].
        colors: [N, 3] RGB in [0, 1].
        features: optional [N, D] latent features, rasterised like colour.
        object_ids: optional [N] int32 object id per Gaussian (-1 for none).

    Examples:
        >>> g = Gaussians(means=np.zeros((1, 3)), quats=[[1, 0, 0, 0]],
        ...               scales=np.full((1, 3), 0.1), opacities=[0.9], colors=[[1, 0, 0]])
        >>> len(g)
        1
    """

    means: Any
    quats: Any
    scales: Any
    opacities: Any
    colors: Any
    features: Any = None
    object_ids: Any = None

    def __post_init__(self) -> None:
        for name in _FLOAT_FIELDS + ("features",):
            value = getattr(self, name)
            if value is None or _is_torch(value):
                continue
            setattr(self, name, np.ascontiguousarray(value, dtype=np.float32))
        if self.object_ids is not None and not _is_torch(self.object_ids):
            ids = np.asarray(self.object_ids)
            if ids.dtype.kind not in "iu" and ids.size:
                raise ValueError(f"Expected integer object_ids, found dtype {ids.dtype}")
            self.object_ids = np.ascontiguousarray(ids, dtype=np.int32)
        self.validate()

    # ------------------------------------------------------------------ checks
    def validate(self) -> None:
        """Raise `ValueError` naming the field if any array is mis-shaped or out of range."""
        n = _shape(self.means, "means")[0] if _ndim(self.means) >= 1 else None
        expected = {"means": (3,), "quats": (4,), "scales": (3,), "opacities": (), "colors": (3,)}
        for name, tail in expected.items():
            shape = _shape(getattr(self, name), name)
            if len(shape) != 1 + len(tail) or shape[1:] != tail or shape[0] != n:
                raise ValueError(f"Expected {name} of shape {(n if n is not None else 'N',) + tail}, "
                                 f"found {shape}")
        if self.features is not None:
            shape = _shape(self.features, "features")
            if len(shape) != 2 or shape[0] != n or shape[1] < 1:
                raise ValueError(f"Expected features of shape ({n}, D) with D >= 1, found {shape}")
        if self.object_ids is not None:
            shape = _shape(self.object_ids, "object_ids")
            if shape != (n,):
                raise ValueError(f"Expected object_ids of shape ({n},), found {shape}")
        for name in _FLOAT_FIELDS + ("features",):
            value = getattr(self, name)
            if value is None:
                continue
            arr = _as_numpy(value)
            if not np.all(np.isfinite(arr)):
                bad = int(np.count_nonzero(~np.isfinite(arr)))
                raise ValueError(f"Expected finite {name}, found {bad} non-finite values")
        scales = _as_numpy(self.scales)
        if scales.size and scales.min() <= 0:
            raise ValueError(f"Expected scales > 0, found minimum {scales.min():.3g}")
        quat_norm = np.linalg.norm(_as_numpy(self.quats), axis=-1)
        if quat_norm.size and quat_norm.min() < 1e-12:
            raise ValueError("Expected non-zero quats, found a quaternion of norm 0")
        op = _as_numpy(self.opacities)
        if op.size and (op.min() < 0 or op.max() > 1):
            raise ValueError(f"Expected opacities in [0, 1], found range [{op.min():.3g}, {op.max():.3g}]")
        col = _as_numpy(self.colors)
        if col.size and (col.min() < 0 or col.max() > 1):
            raise ValueError(f"Expected colors in [0, 1], found range [{col.min():.3g}, {col.max():.3g}]")

    @classmethod
    def _trusted(cls, **arrays: Any) -> "Gaussians":
        """Build without validation, for internal producers whose output is valid by construction."""
        obj = object.__new__(cls)
        for f in fields(cls):
            setattr(obj, f.name, arrays.get(f.name))
        return obj

    # -------------------------------------------------------------- properties
    def __len__(self) -> int:
        return int(_shape(self.means, "means")[0])

    @property
    def num(self) -> int:
        """Number of Gaussians."""
        return len(self)

    @property
    def feature_dim(self) -> int:
        """D, the width of `features` (0 without features)."""
        return 0 if self.features is None else int(_shape(self.features, "features")[1])

    @property
    def is_torch(self) -> bool:
        """True when the arrays are torch tensors."""
        return _is_torch(self.means)

    # -------------------------------------------------------------- operations
    def subset(self, index: Any) -> "Gaussians":
        """The Gaussians selected by a boolean mask or an index array."""
        return Gaussians._trusted(**{f.name: (None if getattr(self, f.name) is None
                                               else getattr(self, f.name)[index])
                                     for f in fields(self)})

    def numpy(self) -> "Gaussians":
        """A copy with numpy arrays (detached from any autograd graph)."""
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = None if v is None else np.array(_as_numpy(v))
        return Gaussians._trusted(**out)

    def torch(self, device: str = "cpu", dtype: Any = None) -> "Gaussians":
        """A copy with torch tensors (float32 unless `dtype` is given)."""
        import torch

        dtype = dtype or torch.float32
        out = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if v is None:
                out[f.name] = None
            elif f.name == "object_ids":
                out[f.name] = torch.as_tensor(_as_numpy(v), dtype=torch.int32, device=device)
            else:
                out[f.name] = torch.as_tensor(_as_numpy(v), device=device).to(dtype)
        return Gaussians._trusted(**out)

    def replace(self, **changes: Any) -> "Gaussians":
        """A validated copy with some fields replaced."""
        return replace(self, **changes)

    @staticmethod
    def concat(parts: Sequence["Gaussians"]) -> "Gaussians":
        """Concatenate several sets; features and object ids are kept only if every part has them
        (a part without object ids gets -1)."""
        parts = [p for p in parts if p is not None]
        if not parts:
            raise ValueError("Expected at least one Gaussians to concatenate, found none")
        if len(parts) == 1:
            return parts[0]
        torch_mode = any(p.is_torch for p in parts)
        if torch_mode:
            import torch

            cat = torch.cat
            parts = [p if p.is_torch else p.torch() for p in parts]
        else:
            cat = np.concatenate
        out: dict[str, Any] = {name: cat([getattr(p, name) for p in parts]) for name in _FLOAT_FIELDS}
        dims = {p.feature_dim for p in parts}
        out["features"] = cat([p.features for p in parts]) if 0 not in dims and len(dims) == 1 else None
        if any(p.object_ids is not None for p in parts):
            ids = []
            for p in parts:
                if p.object_ids is not None:
                    ids.append(p.object_ids)
                elif torch_mode:
                    ids.append(torch.full((len(p),), -1, dtype=torch.int32))
                else:
                    ids.append(np.full(len(p), -1, dtype=np.int32))
            out["object_ids"] = cat(ids)
        else:
            out["object_ids"] = None
        return Gaussians._trusted(**out)

    @staticmethod
    def empty(feature_dim: int = 0) -> "Gaussians":
        """Zero Gaussians (renders the background)."""
        return Gaussians(
            means=np.zeros((0, 3)), quats=np.zeros((0, 4)), scales=np.zeros((0, 3)),
            opacities=np.zeros(0), colors=np.zeros((0, 3)),
            features=np.zeros((0, feature_dim)) if feature_dim else None,
            object_ids=np.zeros(0, dtype=np.int32),
        )

    def __repr__(self) -> str:
        kind = "torch" if self.is_torch else "numpy"
        return f"Gaussians(n={len(self)}, feature_dim={self.feature_dim}, arrays={kind})"


def _shape(x: Any, name: str) -> tuple:
    try:
        return tuple(int(s) for s in x.shape)
    except AttributeError as exc:  # pragma: no cover - defensive
        raise ValueError(f"Expected {name} to be an array, found {type(x).__name__}") from exc


def _ndim(x: Any) -> int:
    return len(getattr(x, "shape", ()))
