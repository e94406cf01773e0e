"""The fit's compiled SSIM loss against the torch-convolution formulation: value and gradient."""

from pathlib import Path

import numpy as np
import pytest
import torch

from morphosim_gym.reconstruct.fused_ssim import SSIM_C2, fused_ssim_applies, fused_ssim_loss, window_taps
from morphosim_gym.reconstruct.losses import conv_ssim_loss, ssim_loss


def _pair(h: int, w: int, dtype=torch.float64, seed: int = 0) -> tuple[torch.Tensor, torch.Tensor]:
    """A structured target (smooth gradients, an edge) and a prediction near it."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w] / max(h, w)
    target = np.stack([xx, yy, (xx + yy > 0.7).astype(float)], -1) * 0.8 + 0.1
    pred = np.clip(target + rng.normal(0, 0.08, target.shape), 0, 1)
    return torch.tensor(pred, dtype=dtype), torch.tensor(target, dtype=dtype)


@pytest.mark.parametrize("h,w", [(32, 32), (23, 37), (7, 9)])
def test_value_and_gradient_match_the_convolutions(h, w):
    pred, target = _pair(h, w)
    a = pred.clone().requires_grad_(True)
    b = pred.clone().requires_grad_(True)
    fused, conv = fused_ssim_loss(a, target), conv_ssim_loss(b, target)
    fused.backward()
    conv.backward()
    assert abs(fused.item() - conv.item()) < 1e-12
    assert torch.allclose(a.grad, b.grad, rtol=1e-9, atol=1e-14)
    assert a.grad.abs().max() > 1e-4                   # a gradient that says something


def test_float32_agrees_to_rounding():
    """float32 against the float64 value and gradient (the convolutions in float32 are 8e-6 off
    here; the fused kernel 2e-6)."""
    pred, target = _pair(64, 48, seed=1)
    ref = pred.clone().requires_grad_(True)
    (3.0 * conv_ssim_loss(ref, target)).backward()
    a = pred.float().requires_grad_(True)
    fused = fused_ssim_loss(a, target.float())
    (3.0 * fused).backward()                           # an upstream gradient other than 1
    assert fused.dtype == a.grad.dtype == torch.float32
    assert abs(fused.item() - conv_ssim_loss(pred, target).item()) < 5e-6
    assert (a.grad.double() - ref.grad).abs().max() < 1e-4 * ref.grad.abs().max()


def test_gradcheck():
    pred, target = _pair(9, 11, seed=2)
    assert torch.autograd.gradcheck(lambda x: fused_ssim_loss(x, target), (pred.clone().requires_grad_(True),))


def test_identical_images_cost_nothing():
    _, target = _pair(16, 16)
    a = target.clone().requires_grad_(True)
    loss = fused_ssim_loss(a, target)
    loss.backward()
    assert abs(loss.item()) < 1e-12 and a.grad.abs().max() < 1e-12


def test_ssim_loss_takes_the_fused_kernel_on_cpu_and_the_convolutions_otherwise():
    pred, target = _pair(20, 20)
    a = pred.clone().requires_grad_(True)
    assert ssim_loss(a, target).grad_fn.name().endswith("_FusedSSIMBackward")
    b = target.clone().requires_grad_(True)           # a target with a gradient: only the convolutions give it one
    ssim_loss(a, b).backward()
    assert b.grad is not None and b.grad.abs().max() > 0
    assert not fused_ssim_applies(a, b)
    assert not fused_ssim_applies(pred.float(), target)                  # mixed dtypes


def test_bad_input_is_named():
    pred, target = _pair(8, 8)
    with pytest.raises(ValueError, match=r"Expected two CPU float \[H, W, C\] images"):
        fused_ssim_loss(pred, target[:, :4])
    with pytest.raises(ValueError, match="images of one shape"):
        fused_ssim_loss(pred[..., 0], target[..., 0])


def test_the_window_is_the_standard_ssim_gaussian():
    """11 taps, sigma 1.5, normalised (both formulations read these taps)."""
    from morphosim_gym.reconstruct.fused_ssim import window_taps

    x = np.arange(-5, 6)
    want = np.exp(-(x ** 2) / (2 * 1.5 ** 2))
    assert np.allclose(window_taps(np.dtype(np.float64)), want / want.sum(), rtol=1e-14)
    assert window_taps(np.dtype(np.float32)).dtype == np.float32


def test_a_covariance_of_minus_half_c2_gives_a_finite_gradient():
    """A 23 px crop of a fit's render and frame (the example ball under corrupted priors) where the
    kernel's a2 = 2 sxy + c2 is exactly 0 at the centre pixel: the backward pass divided by a2
    there, 0 / 0 spread NaN over the 11 x 11 window, and the fit's parameters turned NaN."""
    data = np.load(Path(__file__).parent / "data" / "ssim_zero_covariance.npz")
    pred, target = torch.from_numpy(data["pred"]), torch.from_numpy(data["target"])
    a = pred.clone().requires_grad_(True)
    fused_ssim_loss(a, target).backward()
    assert torch.isfinite(a.grad).all()
    ref = pred.double().requires_grad_(True)
    conv_ssim_loss(ref, target.double()).backward()
    assert (a.grad.double() - ref.grad).abs().max() < 1e-4 * ref.grad.abs().max()
    # the crop still holds the case: the centre's covariance term is -c2 / 2 to float32 rounding
    x, y = data["pred"][6:17, 6:17, 0].astype(np.float64), data["target"][6:17, 6:17, 0].astype(np.float64)
    w = np.outer(window_taps(np.dtype(np.float64)), window_taps(np.dtype(np.float64)))
    sxy = (w * x * y).sum() - (w * x).sum() * (w * y).sum()
    assert abs(2 * sxy + SSIM_C2) < 1e-6
