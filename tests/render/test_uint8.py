"""`render.cpu.uint8.to_uint8`: the bytes numpy's clip-scale-round gives, for both float widths."""

import numpy as np
import pytest

from morphosim_gym.render.cpu.uint8 import to_uint8


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("shape", [(84, 84, 3), (2, 5, 7, 3), (0, 3), ()])
def test_to_uint8_is_numpys_rounding_to_the_byte(dtype, shape):
    rng = np.random.default_rng(0)
    x = rng.uniform(-0.2, 1.2, shape).astype(dtype)
    # values at every rounding boundary k / 255 +- 0.5 / 255 and just beside it
    edges = ((np.arange(256) + 0.5) / 255.0).astype(dtype)
    x = x.reshape(-1)
    if x.size:
        x[:min(x.size, 256)] = edges[:min(x.size, 256)]
        x[-min(x.size, 256):] = np.nextafter(edges, dtype(0))[:min(x.size, 256)]
    x = x.reshape(shape)
    got = to_uint8(x)
    assert got.dtype == np.uint8 and got.shape == x.shape
    np.testing.assert_array_equal(got, (np.clip(x, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8))


def test_to_uint8_takes_strided_views_and_other_dtypes():
    x = np.linspace(0, 1, 2 * 6 * 3, dtype=np.float32).reshape(2, 6, 3)[:, ::2]
    np.testing.assert_array_equal(to_uint8(x), (np.clip(x, 0, 1) * 255.0 + 0.5).astype(np.uint8))
    ints = np.array([0, 1, 2])
    np.testing.assert_array_equal(to_uint8(ints), [0, 255, 255])
