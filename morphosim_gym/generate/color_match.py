"""Recolouring a sampled object so that its average colour is the one the prompt asked for."""

from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["match_mean_color", "tint_keep_shading"]


def match_mean_color(colors: np.ndarray, weights: np.ndarray, target: Sequence[float], iterations: int = 6,
                     tolerance: float = 1.0) -> np.ndarray:
    """Shift colours in CIE Lab so that their weighted mean is `target` (RGB), keeping their spread
    (shading, textures, darker parts); repeated because clipping to the RGB gamut eats part of
    each shift. Returns new colours [n, 3]."""
    import cv2

    from ..metrics import rgb_to_lab

    w = np.asarray(weights, dtype=np.float64)
    w = w / max(float(w.sum()), 1e-12)
    goal = rgb_to_lab(np.asarray(target, dtype=np.float64))
    c = np.asarray(colors, dtype=np.float64).copy()
    for _ in range(iterations):
        lab = rgb_to_lab(c)
        shift = goal - w @ lab
        if np.linalg.norm(shift) < tolerance:
            break
        moved = (lab + shift).astype(np.float32).reshape(-1, 1, 3)
        c = np.clip(cv2.cvtColor(moved, cv2.COLOR_Lab2RGB).reshape(-1, 3).astype(np.float64), 0.0, 1.0)
    return c


def tint_keep_shading(colors: np.ndarray, weights: np.ndarray, target: Sequence[float]) -> np.ndarray:
    """Recolour a real asset: each colour becomes `target` times its luminance over the weighted mean
    luminance, so the weighted mean is about `target` and the texture's light and dark detail stays
    (a Lab shift into a saturated colour clips the other channels and flattens it). Returns [n, 3]."""
    c = np.asarray(colors, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    w = w / max(float(w.sum()), 1e-12)
    lum = c @ np.array([0.2126, 0.7152, 0.0722])
    ratio = lum / max(float(w @ lum), 1e-6)
    return np.clip(np.asarray(target, dtype=np.float64)[None, :] * ratio[:, None], 0.0, 1.0)
