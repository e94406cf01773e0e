"""The compiled sky compositing (`render.cpu.sky`) against the numpy definition (`scene.sky`)."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.render.cpu.sky import composite_sky_compiled
from morphosim_gym.scene import Camera
from morphosim_gym.scene.sky import SKY_VISIBLE_BELOW, composite_sky


def _case(seed: int, count: int = 6, size: tuple = (40, 30)):
    rng = np.random.default_rng(seed)
    image = rng.random((32, 64, 3), dtype=np.float32)
    cams = [Camera.look_at(eye=rng.normal(size=3) * 3 + (0, 0, 0.1), target=(0, 0, 0.5), width=size[0],
                           height=size[1]) for _ in range(count)]
    rgb = (rng.random((count, size[1], size[0], 3), dtype=np.float32) * 0.3)
    alpha = np.where(rng.random(rgb.shape[:3]) < 0.6, rng.random(rgb.shape[:3]), 1.0).astype(np.float32)
    alpha[0, 0, :4] = (SKY_VISIBLE_BELOW, np.nextafter(np.float32(SKY_VISIBLE_BELOW), np.float32(0)), 0.0, 1.0)
    return rgb, alpha, image, cams


@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_sky_matches_the_numpy_definition(seed):
    rgb, alpha, image, cams = _case(seed)
    want = composite_sky(rgb, alpha, image, cams)
    got = composite_sky_compiled(rgb, alpha, image, cams)
    assert got.dtype == np.float32 and got.shape == want.shape
    # the same arithmetic: equal, except where BLAS's fused float64 ray product rounds to another
    # float32 (a last-bit event, rare: allowed on at most 0.1% of the values, within 5e-5)
    np.testing.assert_allclose(got, want, rtol=0, atol=5e-5)
    assert np.mean(got == want) >= 0.999
    covered = alpha >= SKY_VISIBLE_BELOW
    np.testing.assert_array_equal(got[covered], rgb[covered])        # no sky where the Gaussians cover
    assert np.all(got[~covered] >= rgb[~covered])


def test_compiled_sky_is_deterministic_and_leaves_its_inputs():
    rgb, alpha, image, cams = _case(2, count=2)
    before = rgb.copy()
    a = composite_sky_compiled(rgb, alpha, image, cams)
    b = composite_sky_compiled(rgb, alpha, image, cams)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(rgb, before)


def test_compiled_sky_names_bad_shapes():
    rgb, alpha, image, cams = _case(3, count=2)
    with pytest.raises(ValueError, match="Expected rgb"):
        composite_sky_compiled(rgb, alpha[:1], image, cams)
    with pytest.raises(ValueError, match="Expected rgb"):
        composite_sky_compiled(rgb[0], alpha[0], image, cams[:1])
