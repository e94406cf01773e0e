"""Bilinear texture lookup at UV coordinates (OBJ/glTF convention: u right, v up, tiled)."""

from __future__ import annotations

import numpy as np

__all__ = ["sample_texture"]


def sample_texture(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Colours of `image` at `uv`, bilinearly interpolated, with the texture repeated outside [0, 1].

    Args:
        image: RGB, row 0 at the top (v = 1): float in [0, 1], or uint8 (read as value / 255). [H, W, 3]
        uv: texture coordinates. [N, 2]

    Returns:
        float32 RGB. [N, 3]

    Examples:
        >>> img = np.zeros((2, 2, 3)); img[1, 0] = 1          # bottom-left texel white
        >>> sample_texture(img, np.array([[0.25, 0.25]])).tolist()
        [[1.0, 1.0, 1.0]]
    """
    h, w = image.shape[:2]
    uv = np.nan_to_num(np.asarray(uv, dtype=np.float64))
    u = np.mod(uv[:, 0], 1.0)
    v = np.mod(uv[:, 1], 1.0)
    x = u * w - 0.5                   # texel centres at (i + 0.5) / w
    y = (1.0 - v) * h - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    x0 = x0.astype(np.int64)
    y0 = y0.astype(np.int64)
    x1, y1 = np.mod(x0 + 1, w), np.clip(y0 + 1, 0, h - 1)
    x0, y0 = np.mod(x0, w), np.clip(y0, 0, h - 1)
    norm = 1.0 / 255.0 if image.dtype == np.uint8 else 1.0

    def texel(yy: np.ndarray, xx: np.ndarray) -> np.ndarray:
        return image[yy, xx].astype(np.float64) * norm

    top = texel(y0, x0) * (1 - fx) + texel(y0, x1) * fx
    bottom = texel(y1, x0) * (1 - fx) + texel(y1, x1) * fx
    return (top * (1 - fy) + bottom * fy).astype(np.float32)
