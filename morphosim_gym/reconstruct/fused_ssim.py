"""SSIM loss of the fit as one compiled CPU kernel with a hand-written backward pass.

`losses.ssim_loss` (11-tap Gaussian window, sigma 1.5, zero padding, as the reference
`conv2d` formulation) is most of the fit's non-rendering time when written as torch convolutions:
five depthwise 11x11 convolutions forward and their backward per iteration (17 ms of a 66 ms
iteration at 128 px on two cores, more than the rasteriser's forward pass). Here the window is
applied as two 11-tap passes (it is separable), the five local moments of one channel
in one sweep, and the backward pass follows from the per-pixel derivatives of

    S = (2 mx my + c1) (2 sxy + c2) / ((mx^2 + my^2 + c1) (sxx + syy + c2)),

with sxx = E[x^2] - mx^2 and sxy = E[xy] - mx my: the gradient of mean(S) with respect to the
prediction x is blur(dS/dmx) + 2 x blur(dS/dE[x^2]) + y blur(dS/dE[xy]) (a zero-padded blur with a
symmetric window is its own adjoint). Only the prediction gets a gradient; the target is data.
"""

from __future__ import annotations

import numpy as np
import torch

from ..render.cpu._jit import jit

__all__ = ["fused_ssim_loss", "fused_ssim_applies", "window_taps", "WINDOW_RADIUS", "WINDOW_SIGMA", "SSIM_C1",
           "SSIM_C2"]

WINDOW_RADIUS = 5
WINDOW_SIGMA = 1.5
SSIM_C1, SSIM_C2 = 0.01 ** 2, 0.03 ** 2          # the stabilising constants (images in [0, 1])


def window_taps(dtype: np.dtype) -> np.ndarray:
    """The SSIM window's 1D taps (normalised Gaussian, `WINDOW_SIGMA`, 2 `WINDOW_RADIUS` + 1 taps); the
    2D window is their outer product."""
    x = np.arange(-WINDOW_RADIUS, WINDOW_RADIUS + 1, dtype=np.float64)
    g = np.exp(-(x ** 2) / (2 * WINDOW_SIGMA ** 2))
    return (g / g.sum()).astype(dtype)


_TAPS = {np.dtype(np.float32): window_taps(np.dtype(np.float32)), np.dtype(np.float64): window_taps(np.dtype(np.float64))}


@jit
def _blur_rows(src, dst, g):
    """dst[i, j] = sum_t g[t] src[i, j + t - r] (zero outside), each row of [H, W] arrays. (The
    inner loops index slices by their own counter: an index such as j + t - r, which numba must
    check for wrapping below 0, keeps LLVM from vectorising the loop, 8x slower.)"""
    h, w = src.shape
    r = (g.shape[0] - 1) // 2
    for i in range(h):
        out = dst[i]
        for j in range(w):
            out[j] = 0
        for t in range(g.shape[0]):
            d = t - r
            lo = max(0, -d)
            hi = min(w, w - d)
            gt = g[t]
            part = out[lo:hi]
            shifted = src[i, lo + d:hi + d]
            for j in range(hi - lo):
                part[j] += gt * shifted[j]


@jit
def _blur_cols(src, dst, g):
    """dst[i, j] = sum_t g[t] src[i + t - r, j] (zero outside)."""
    h, w = src.shape
    r = (g.shape[0] - 1) // 2
    for i in range(h):
        for j in range(w):
            dst[i, j] = 0
        for t in range(g.shape[0]):
            k = i + t - r
            if 0 <= k < h:
                gt = g[t]
                for j in range(w):
                    dst[i, j] += gt * src[k, j]


@jit
def _blur(src, dst, tmp, g):
    _blur_rows(src, tmp, g)
    _blur_cols(tmp, dst, g)


@jit
def _blur_product(a, b, dst, prod, tmp, g):
    """dst = blur(a * b) of two [H, W] arrays (`prod`, `tmp`: scratch)."""
    h, w = a.shape
    for i in range(h):
        for j in range(w):
            prod[i, j] = a[i, j] * b[i, j]
    _blur(prod, dst, tmp, g)


@jit
def _terms(moments, c, i, j):
    """(mx, my, 2 mx my + c1, 2 sxy + c2, mx^2 + my^2 + c1, sxx + syy + c2) at one pixel."""
    F = moments.dtype.type
    mx = moments[0, c, i, j]
    my = moments[1, c, i, j]
    a1 = F(2) * mx * my + F(SSIM_C1)
    a2 = F(2) * (moments[4, c, i, j] - mx * my) + F(SSIM_C2)
    b1 = mx * mx + my * my + F(SSIM_C1)
    b2 = moments[2, c, i, j] - mx * mx + moments[3, c, i, j] - my * my + F(SSIM_C2)
    return mx, my, a1, a2, b1, b2


@jit
def _forward(x, y, g, moments, tmp, prod):
    """x, y [C, H, W]; fills moments [5, C, H, W] (mx, my, E[x^2], E[y^2], E[xy]); returns sum of S."""
    c_all, h, w = x.shape
    total = 0.0
    for c in range(c_all):
        _blur(x[c], moments[0, c], tmp, g)
        _blur(y[c], moments[1, c], tmp, g)
        _blur_product(x[c], x[c], moments[2, c], prod, tmp, g)
        _blur_product(y[c], y[c], moments[3, c], prod, tmp, g)
        _blur_product(x[c], y[c], moments[4, c], prod, tmp, g)
        for i in range(h):
            for j in range(w):
                mx, my, a1, a2, b1, b2 = _terms(moments, c, i, j)
                total += (a1 * a2) / (b1 * b2)
    return total


@jit
def _backward(x, y, g, moments, scale, grad, tmp, d_mx, d_exx, d_exy, blurred):
    """grad [C, H, W] = scale * d sum(S) / dx, from the forward pass's moments."""
    c_all, h, w = x.shape
    F = x.dtype.type
    k = F(scale)
    for c in range(c_all):
        for i in range(h):
            for j in range(w):
                mx, my, a1, a2, b1, b2 = _terms(moments, c, i, j)
                # no division by a1 or a2: a2 = 2 sxy + c2 is 0 where the covariance is -c2 / 2
                # (it was, once, in a fit: s / a2 gave 0 / 0 and the fit's parameters turned NaN)
                q = k / (b1 * b2)
                s = q * a1 * a2
                d_mx[i, j] = F(2) * my * q * (a2 - a1) + F(2) * mx * s * (F(1) / b2 - F(1) / b1)
                d_exx[i, j] = -s / b2
                d_exy[i, j] = F(2) * q * a1
        _blur(d_mx, grad[c], tmp, g)
        _blur(d_exx, blurred, tmp, g)
        for i in range(h):
            for j in range(w):
                grad[c, i, j] += F(2) * x[c, i, j] * blurred[i, j]
        _blur(d_exy, blurred, tmp, g)
        for i in range(h):
            for j in range(w):
                grad[c, i, j] += y[c, i, j] * blurred[i, j]


def _chw(t: torch.Tensor) -> np.ndarray:
    return np.ascontiguousarray(t.detach().permute(2, 0, 1).numpy())


class _FusedSSIM(torch.autograd.Function):
    @staticmethod
    def forward(ctx, pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
        x, y = _chw(pred), _chw(target)
        c, h, w = x.shape
        g = _TAPS[x.dtype]
        moments = np.empty((5, c, h, w), x.dtype)
        total = _forward(x, y, g, moments, np.empty((h, w), x.dtype), np.empty((h, w), x.dtype))
        ctx.arrays = (x, y, moments)
        return torch.tensor(1.0 - total / (c * h * w), dtype=pred.dtype)

    @staticmethod
    def backward(ctx, grad_out: torch.Tensor):
        x, y, moments = ctx.arrays
        c, h, w = x.shape
        grad = np.empty_like(x)
        scratch = [np.empty((h, w), x.dtype) for _ in range(5)]
        _backward(x, y, _TAPS[x.dtype], moments, -float(grad_out) / (c * h * w), grad, *scratch)
        return torch.from_numpy(grad).permute(1, 2, 0), None


def fused_ssim_applies(pred: torch.Tensor, target: torch.Tensor) -> bool:
    """Whether `fused_ssim_loss` takes these [H, W, C] images: CPU float32 or float64 tensors of one
    shape and dtype, the target without a gradient."""
    return (pred.device.type == "cpu" and target.device.type == "cpu" and pred.dtype == target.dtype
            and pred.dtype in (torch.float32, torch.float64) and pred.shape == target.shape and pred.dim() == 3
            and not target.requires_grad)


def fused_ssim_loss(pred: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """1 - SSIM of two [H, W, C] CPU images (`fused_ssim_applies`), differentiable in `pred`."""
    if not fused_ssim_applies(pred, target):
        raise ValueError(f"Expected two CPU float [H, W, C] images of one shape and dtype, the target without a "
                         f"gradient, found {tuple(pred.shape)} {pred.dtype} {pred.device} and {tuple(target.shape)} "
                         f"{target.dtype} {target.device}")
    return _FusedSSIM.apply(pred, target)
