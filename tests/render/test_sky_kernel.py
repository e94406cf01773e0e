"""The compiled sky compositing (`render.cpu.sky`) against the numpy definition (`scene.sky`)."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.render.cpu.sky import atan2_f32, composite_sky_compiled
from morphosim_gym.scene import Camera
from morphosim_gym.scene.sky import SKY_VISIBLE_BELOW, composite_sky, sky_rays


def _case(seed: int, count: int = 6, size: tuple = (40, 30)):
    rng = np.random.default_rng(seed)
    image = rng.random((32, 64, 3), dtype=np.float32)
    cams = [Camera.look_at(eye=rng.normal(size=3) * 3 + (0, 0, 0.1), target=(0, 0, 0.5), width=size[0],
                           height=size[1]) for _ in range(count)]
    rgb = (rng.random((count, size[1], size[0], 3), dtype=np.float32) * 0.3)
    alpha = np.where(rng.random(rgb.shape[:3]) < 0.6, rng.random(rgb.shape[:3]), 1.0).astype(np.float32)
    alpha[0, 0, :4] = (SKY_VISIBLE_BELOW, np.nextafter(np.float32(SKY_VISIBLE_BELOW), np.float32(0)), 0.0, 1.0)
    return rgb, alpha, image, cams


def _composite_in_float64(rgb, alpha, image, cams):
    """`composite_sky`'s definition in float64 from the float32 rays: the truth both are held to."""
    out = rgb.astype(np.float64)
    h, w = image.shape[:2]
    im = image.astype(np.float64)
    for c, cam in enumerate(cams):
        rows, cols = np.nonzero(alpha[c] < SKY_VISIBLE_BELOW)
        d = sky_rays(cam, rows, cols).astype(np.float32).astype(np.float64)
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        u = (0.5 - np.arctan2(d[:, 1], d[:, 0]) / (2 * np.pi)) * w - 0.5
        v = np.clip((0.5 - np.arcsin(np.clip(d[:, 2], -1, 1)) / np.pi) * h - 0.5, 0, h - 1)
        u0, v0 = np.floor(u), np.floor(v)
        fu, fv = (u - u0)[:, None], (v - v0)[:, None]
        u0 = u0.astype(np.int64) % w
        u1, v0 = (u0 + 1) % w, v0.astype(np.int64)
        v1 = np.minimum(v0 + 1, h - 1)
        colour = (im[v0, u0] * (1 - fu) + im[v0, u1] * fu) * (1 - fv) + (im[v1, u0] * (1 - fu) + im[v1, u1] * fu) * fv
        out[c, rows, cols] += (1 - alpha[c, rows, cols, None]) * colour
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_sky_matches_the_numpy_definition(seed):
    rgb, alpha, image, cams = _case(seed)
    want = composite_sky(rgb, alpha, image, cams)
    got = composite_sky_compiled(rgb, alpha, image, cams)
    assert got.dtype == np.float32 and got.shape == want.shape
    # the kernel's polynomial atan2 and numpy's float32 arctan2 / arcsin differ in the last bits of
    # the angle; on this white-noise sky (a full step of colour per texel, the worst case) both are
    # held to the float64 definition, and the kernel is at least as close to it as numpy is
    truth = _composite_in_float64(rgb, alpha, image, cams)
    kernel_err, numpy_err = np.abs(got - truth), np.abs(want - truth)
    assert kernel_err.max() <= 4e-6 and kernel_err.mean() <= numpy_err.mean()
    np.testing.assert_allclose(got, want, rtol=0, atol=3e-5)
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


def test_kernel_atan2_is_as_accurate_as_float32_arctan2():
    rng = np.random.default_rng(4)
    y = rng.normal(size=200_000).astype(np.float32) * np.float32(10.0) ** rng.integers(-3, 4, 200_000)
    x = rng.normal(size=200_000).astype(np.float32)
    edges = np.array([0, 1, -1, 1, -1, 0.5, 2, 1e-30, -1e-30, 3e38], np.float32)
    y = np.concatenate([y, edges, edges, -edges])          # axes, diagonals, octant folds, tiny, huge
    x = np.concatenate([x, edges[::-1], edges, edges[::-1]])
    got = np.empty_like(y)
    atan2_f32(y, x, got)
    exact = np.arctan2(y.astype(np.float64), x.astype(np.float64))
    assert np.abs(got - exact).max() <= 3.5e-7            # numpy's float32 arctan2: 2.5e-7 here
    special = np.array([[0, 1], [0, -1], [1, 0], [-1, 0], [0, 0], [1, 1], [-1, -1]], np.float32)
    out = np.empty(len(special), np.float32)
    atan2_f32(special[:, 0], special[:, 1], out)
    np.testing.assert_allclose(out, np.arctan2(special[:, 0], special[:, 1]), rtol=0, atol=1e-7)
