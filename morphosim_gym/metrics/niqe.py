"""NIQE, the "completely blind" natural image quality evaluator (Mittal et al., 2013), in NumPy.

The image's local statistics are compared with those of pristine natural images: mean-
subtracted, contrast-normalised (MSCN) luminance is cut into blocks at two scales; each block
gives 18 numbers per scale (generalised-Gaussian fits of the MSCN values and of their products
with the four neighbours); the multivariate Gaussian of these 36-vectors over the image's blocks
is compared with the pristine one by

    NIQE = sqrt((mu_p - mu_i)^T pinv((Sigma_p + Sigma_i) / 2) (mu_p - mu_i))

Lower is better. The pristine model (`mu_p` 1x36, `Sigma_p` 36x36) is the published one, as
shipped in BasicSR's source distribution (see `data/NOTICE`); it is read from the package data,
never downloaded. Scores follow the MATLAB reference closely but not to the last digit (the
half-scale image is made by an antialiased bicubic resize written here).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np
from scipy.special import gamma

__all__ = ["niqe", "niqe_features", "mscn", "aggd_fit", "pristine_model", "BLOCK"]

BLOCK = 96                       # block size at full scale, pixels (48 at half scale)
_DATA = Path(__file__).resolve().parent / "data" / "niqe_pris_params.npz"
_ALPHAS = np.arange(0.2, 10.0, 0.001)
_RHO = gamma(2.0 / _ALPHAS) ** 2 / (gamma(1.0 / _ALPHAS) * gamma(3.0 / _ALPHAS))


@lru_cache(maxsize=1)
def pristine_model() -> tuple[np.ndarray, np.ndarray]:
    """(mean [36], covariance [36, 36]) of the pristine natural-scene features."""
    with np.load(_DATA) as d:
        return d["mu_pris_param"].reshape(36).astype(np.float64), d["cov_pris_param"].astype(np.float64)


def _gaussian_window(size: int = 7, sigma: float = 7.0 / 6.0) -> np.ndarray:
    r = np.arange(size, dtype=np.float64) - (size - 1) / 2.0
    g = np.exp(-(r[:, None] ** 2 + r[None, :] ** 2) / (2.0 * sigma * sigma))
    return g / g.sum()


def mscn(luma: np.ndarray) -> np.ndarray:
    """Mean-subtracted contrast-normalised coefficients of a [H, W] luminance image in [0, 255]."""
    w = _gaussian_window()
    mu = cv2.filter2D(luma, cv2.CV_64F, w, borderType=cv2.BORDER_REPLICATE)
    var = cv2.filter2D(luma * luma, cv2.CV_64F, w, borderType=cv2.BORDER_REPLICATE) - mu * mu
    return (luma - mu) / (np.sqrt(np.abs(var)) + 1.0)


def aggd_fit(x: np.ndarray) -> tuple[float, float, float]:
    """(shape alpha, left scale beta_l, right scale beta_r) of an asymmetric generalised Gaussian,
    by moment matching over a grid of shapes."""
    x = np.asarray(x, dtype=np.float64).ravel()
    left, right = x[x < 0], x[x > 0]
    sl = float(np.sqrt(np.mean(left ** 2))) if left.size else 0.0
    sr = float(np.sqrt(np.mean(right ** 2))) if right.size else 0.0
    if sl == 0.0 or sr == 0.0:
        return float("nan"), float("nan"), float("nan")
    g = sl / sr
    r_hat = float(np.mean(np.abs(x))) ** 2 / float(np.mean(x * x))
    big_r = r_hat * (g ** 3 + 1.0) * (g + 1.0) / (g * g + 1.0) ** 2
    alpha = float(_ALPHAS[int(np.argmin((_RHO - big_r) ** 2))])
    k = np.sqrt(gamma(1.0 / alpha) / gamma(3.0 / alpha))
    return alpha, sl * k, sr * k


def _block_features(block: np.ndarray) -> list[float]:
    alpha, bl, br = aggd_fit(block)
    feats = [alpha, (bl + br) / 2.0]
    for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
        pair = block * np.roll(block, (-dy, -dx), axis=(0, 1))
        a, bl, br = aggd_fit(pair)
        mean = (br - bl) * gamma(2.0 / a) / gamma(1.0 / a) if np.isfinite(a) else float("nan")
        feats += [a, mean, bl, br]                       # NIQE keeps the scales (BRISQUE squares them)
    return feats


def _cubic(x: np.ndarray) -> np.ndarray:
    ax = np.abs(x)
    return ((1.5 * ax ** 3 - 2.5 * ax ** 2 + 1.0) * (ax <= 1)
            + (-0.5 * ax ** 3 + 2.5 * ax ** 2 - 4.0 * ax + 2.0) * ((ax > 1) & (ax <= 2)))


def _half_matrix(n: int) -> np.ndarray:
    """[n // 2, n] antialiased bicubic downsampling by 2 (MATLAB imresize's kernel, edges replicated)."""
    m = n // 2
    out = np.zeros((m, n))
    for i in range(m):
        centre = 2.0 * i + 0.5                      # output pixel centre in input pixel coordinates
        taps = np.arange(int(np.floor(centre - 4)), int(np.ceil(centre + 4)) + 1)
        w = 0.5 * _cubic(0.5 * (taps - centre))
        np.add.at(out[i], np.clip(taps, 0, n - 1), w / w.sum())
    return out


def niqe_features(luma: np.ndarray) -> np.ndarray:
    """[blocks, 36] features of a [H, W] luminance image in [0, 255] (two scales, 18 each)."""
    h, w = (luma.shape[0] // BLOCK) * BLOCK, (luma.shape[1] // BLOCK) * BLOCK
    if h == 0 or w == 0:
        raise ValueError(f"Expected an image of at least {BLOCK}x{BLOCK} pixels for NIQE, found {luma.shape[:2]}")
    img = luma[:h, :w].astype(np.float64)
    scales = []
    for s in range(2):
        b = BLOCK >> s
        m = mscn(img)
        rows = [_block_features(m[y:y + b, x:x + b]) for y in range(0, img.shape[0] - b + 1, b)
                for x in range(0, img.shape[1] - b + 1, b)]
        scales.append(np.array(rows))
        img = _half_matrix(img.shape[0]) @ img @ _half_matrix(img.shape[1]).T
    return np.concatenate(scales, axis=1)


def _luma(image: np.ndarray) -> np.ndarray:
    """ITU-R BT.601 luma (the Y of YCbCr, as MATLAB's rgb2ycbcr) in [16, 235] of an RGB image, rounded
    to integers as the reference computes it from 8-bit images."""
    a = np.asarray(image)
    if a.dtype == np.uint8:
        a = a.astype(np.float64) / 255.0
    else:
        a = a.astype(np.float64)
    if a.ndim == 2:
        return np.round(a * 255.0)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(f"Expected an image [H, W] or [H, W, 3], found shape {a.shape}")
    return np.round(16.0 + a[..., :3] @ np.array([65.481, 128.553, 24.966]))    # 8-bit Y, as MATLAB's uint8 path


def niqe(image: np.ndarray) -> float:
    """NIQE of an image ([H, W, 3] RGB uint8 or float in [0, 1], or [H, W] grey; at least 96x96);
    lower is better."""
    feats = niqe_features(_luma(image))
    mu_p, cov_p = pristine_model()
    feats = feats[np.all(np.isfinite(feats), axis=1)]
    if len(feats) == 0:
        return float("nan")                         # a flat image: no statistics to compare
    mu = feats.mean(axis=0)
    cov = np.cov(feats, rowvar=False) if len(feats) > 1 else np.zeros((36, 36))
    d = mu_p - mu
    return float(np.sqrt(d @ np.linalg.pinv((cov_p + cov) / 2.0) @ d))
