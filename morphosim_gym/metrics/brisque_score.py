"""BRISQUE (Mittal, Moorthy and Bovik, 2012) through the `brisque` package's trained SVM model.

The `brisque` package (0.2.0) ships the LIVE-trained support-vector regressor and its feature
scaling, which we use as they are. Its feature extractor divides by an array's `shape` tuple
and so yields one-element arrays where the scaling step needs scalars, which NumPy 2 refuses;
`BrisqueScorer` flattens the features to plain floats before scoring (our wrapper, no change
to the installed package). Lower scores are better (about 0-100).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["BrisqueScorer", "brisque"]


def _model_class() -> Any:
    try:
        from brisque import BRISQUE
    except ImportError as exc:
        raise ImportError(f"Expected the brisque package (with libsvm-official and scikit-image) for BRISQUE, "
                          f'found it missing ({exc}); pip install -e ".[bench]"') from exc
    return BRISQUE


class BrisqueScorer:
    """BRISQUE scores with the packaged model (loaded once per scorer)."""

    def __init__(self) -> None:
        base = _model_class()

        class _Scalars(base):  # type: ignore[misc, valid-type]
            def calculate_brisque_features(self, image: np.ndarray, kernel_size: int = 7,
                                           sigma: float = 7 / 6) -> np.ndarray:
                feats = super().calculate_brisque_features(image, kernel_size=kernel_size, sigma=sigma)
                return np.array([np.asarray(f, dtype=np.float64).reshape(-1)[0] for f in feats], dtype=np.float64)

        self._model = _Scalars(url=False)

    def __call__(self, image: np.ndarray) -> float:
        """BRISQUE of an [H, W, 3] RGB image (uint8, or float in [0, 1]); lower is better."""
        a = np.asarray(image)
        if a.ndim != 3 or a.shape[2] not in (3, 4):
            raise ValueError(f"Expected an RGB image [H, W, 3], found shape {a.shape}")
        if a.dtype != np.uint8:
            a = (np.clip(a.astype(np.float64), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
        return float(self._model.score(a[..., :3]))


_DEFAULT: list[BrisqueScorer] = []


def brisque(image: np.ndarray) -> float:
    """BRISQUE of an RGB image with a shared scorer (see `BrisqueScorer`)."""
    if not _DEFAULT:
        _DEFAULT.append(BrisqueScorer())
    return _DEFAULT[0](image)
