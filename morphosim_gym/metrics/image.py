"""Full-reference image metrics (numpy): PSNR, SSIM, CIE Lab colour difference, mask IoU."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["psnr", "ssim", "rgb_to_lab", "mean_lab", "delta_e", "iou"]


def _float(img: np.ndarray) -> np.ndarray:
    a = np.asarray(img)
    if a.dtype == np.uint8:
        return a.astype(np.float64) / 255.0
    return a.astype(np.float64)


def psnr(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None, peak: float = 1.0) -> float:
    """Peak signal-to-noise ratio in dB of two images ([H, W, C] floats in [0, 1] or uint8), over
    `mask` [H, W] pixels if given; inf for identical images."""
    x, y = _float(a), _float(b)
    if x.shape != y.shape:
        raise ValueError(f"Expected images of one shape, found {x.shape} and {y.shape}")
    err = (x - y) ** 2
    if mask is not None:
        m = np.asarray(mask, bool)
        if not m.any():
            raise ValueError("Expected a mask with at least one pixel, found an empty mask")
        err = err[m]
    mse = float(err.mean())
    return float("inf") if mse == 0 else 10.0 * np.log10(peak ** 2 / mse)


def ssim(a: np.ndarray, b: np.ndarray) -> float:
    """Structural similarity (Gaussian window 11, sigma 1.5; mean over channels) of two images."""
    x, y = _float(a), _float(b)
    if x.shape != y.shape:
        raise ValueError(f"Expected images of one shape, found {x.shape} and {y.shape}")
    if x.ndim == 2:
        x, y = x[..., None], y[..., None]
    c1, c2 = 0.01 ** 2, 0.03 ** 2

    def blur(z: np.ndarray) -> np.ndarray:
        return cv2.GaussianBlur(z, (11, 11), 1.5, borderType=cv2.BORDER_REFLECT)

    vals = []
    for c in range(x.shape[-1]):
        p, q = x[..., c], y[..., c]
        mp, mq = blur(p), blur(q)
        vp = blur(p * p) - mp * mp
        vq = blur(q * q) - mq * mq
        cov = blur(p * q) - mp * mq
        s = ((2 * mp * mq + c1) * (2 * cov + c2)) / ((mp * mp + mq * mq + c1) * (vp + vq + c2))
        vals.append(s.mean())
    return float(np.mean(vals))


def rgb_to_lab(rgb: np.ndarray) -> np.ndarray:
    """CIE Lab (D65; L in [0, 100]) of sRGB colours [..., 3] in [0, 1] (or uint8)."""
    x = _float(rgb).astype(np.float32)
    shape = x.shape
    lab = cv2.cvtColor(x.reshape(-1, 1, 3), cv2.COLOR_RGB2Lab)
    return lab.reshape(shape).astype(np.float64)


def mean_lab(image: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Mean Lab colour of the masked pixels of an image."""
    m = np.asarray(mask, bool)
    if not m.any():
        raise ValueError("Expected a mask with at least one pixel, found an empty mask")
    return rgb_to_lab(_float(image)[m]).mean(axis=0)


def delta_e(lab_a: np.ndarray, lab_b: np.ndarray) -> float:
    """CIE76 colour difference of two Lab colours."""
    return float(np.linalg.norm(np.asarray(lab_a, dtype=np.float64) - np.asarray(lab_b, dtype=np.float64)))


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two boolean masks (1.0 when both are empty)."""
    x, y = np.asarray(a, bool), np.asarray(b, bool)
    union = np.logical_or(x, y).sum()
    return 1.0 if union == 0 else float(np.logical_and(x, y).sum() / union)
