"""Image metrics against known values."""

import numpy as np
import pytest

from morphosim_gym.metrics import delta_e, iou, mean_lab, psnr, rgb_to_lab, ssim


def test_psnr_known_value_and_mask():
    a = np.zeros((8, 8, 3))
    b = a + 0.1
    assert psnr(a, b) == pytest.approx(20.0)
    assert psnr(a, a) == float("inf")
    m = np.zeros((8, 8), bool)
    m[0, 0] = True
    c = a.copy()
    c[1:] = 1.0
    assert psnr(a, c, mask=m) == float("inf")
    with pytest.raises(ValueError, match="shape"):
        psnr(a, np.zeros((4, 4, 3)))


def test_ssim_identity_and_degradation():
    rng = np.random.default_rng(0)
    img = rng.random((32, 32, 3))
    assert ssim(img, img) == pytest.approx(1.0)
    light = ssim(img, np.clip(img + rng.normal(0, 0.05, img.shape), 0, 1))
    heavy = ssim(img, np.clip(img + rng.normal(0, 0.3, img.shape), 0, 1))
    assert 1.0 > light > heavy


def test_lab_reference_colours():
    np.testing.assert_allclose(rgb_to_lab(np.array([1.0, 1.0, 1.0])), [100, 0, 0], atol=0.5)
    np.testing.assert_allclose(rgb_to_lab(np.array([1.0, 0.0, 0.0])), [53.2, 80.1, 67.2], atol=0.6)
    img = np.zeros((4, 4, 3))
    img[:2] = [1, 0, 0]
    m = np.zeros((4, 4), bool)
    m[:2] = True
    assert delta_e(mean_lab(img, m), rgb_to_lab(np.array([1.0, 0, 0]))) < 0.5


def test_iou():
    a = np.zeros((4, 4), bool)
    b = a.copy()
    a[:2] = True
    b[1:3] = True
    assert iou(a, b) == pytest.approx(4 / 12)
    assert iou(np.zeros(3, bool), np.zeros(3, bool)) == 1.0
