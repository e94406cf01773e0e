"""Sky panoramas: ray directions -> equirectangular colours; real HDR files when installed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from morphosim_gym.assets import AssetError, Sky, load_sky
from morphosim_gym.assets.sky import directions_to_uv, tone_map

FOREST = Path("/usr/share/blender/datafiles/studiolights/world/forest.exr")


def test_directions_follow_the_equirectangular_convention():
    uv = directions_to_uv(np.array([[1.0, 0, 0], [0, -2.0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]]))
    np.testing.assert_allclose(uv, [[0.5, 0.5], [0.75, 0.5], [0.25, 0.5], [0.5, 1.0], [0.5, 0.0]], atol=1e-12)


def test_sky_color_reads_the_right_pixels():
    image = np.zeros((4, 8, 3), dtype=np.float32)
    image[0] = (0.1, 0.2, 1.0)              # the top row: straight up
    image[-1] = (0.3, 0.2, 0.1)             # the bottom row: straight down
    image[1:3, 3:5] = (1.0, 0.0, 0.0)       # the centre: towards +x
    sky = Sky(image)
    got = sky.sky_color(np.array([[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0]]))
    np.testing.assert_allclose(got, [[0.1, 0.2, 1.0], [0.3, 0.2, 0.1], [1.0, 0.0, 0.0]], atol=1e-6)
    assert got.dtype == np.float32
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        sky.sky_color(np.zeros((3, 2)))


def test_tone_map_range():
    out = tone_map(np.array([[[0.0, 1.0, 1e6]]]))
    assert out.dtype == np.float32 and out.min() >= 0 and out.max() <= 1
    assert out[0, 0, 0] == 0 and out[0, 0, 2] > 0.99


@pytest.mark.skipif(not FOREST.exists(), reason="Debian blender-data's studio-light worlds are not installed")
def test_real_panorama():
    sky = load_sky(FOREST)
    assert sky.image.shape == (512, 1024, 3) and sky.image.dtype == np.float32
    assert 0 <= sky.image.min() and sky.image.max() <= 1
    up, down = sky.sky_color(np.array([[0, 0, 1.0], [0, 0, -1.0]]))
    assert up.mean() > down.mean() + 0.3     # bright sky above, dark gravel below


def test_unreadable_panorama_names_the_file(tmp_path):
    (tmp_path / "bad.exr").write_bytes(b"not an exr")
    with pytest.raises(AssetError, match="bad.exr"):
        load_sky(tmp_path / "bad.exr")


def test_background_behind_a_camera():
    from morphosim_gym.scene import Camera

    image = np.zeros((8, 16, 3), dtype=np.float32)
    image[:4] = (0.2, 0.4, 0.9)                     # the upper half of the sphere
    image[4:] = (0.3, 0.25, 0.2)                    # the lower half
    sky = Sky(image)
    up = Camera.look_at(eye=(0, 0, 0), target=(0, 0, 1), width=8, height=6, fov_y_deg=40, up=(0, 1, 0))
    np.testing.assert_allclose(sky.background(up), np.broadcast_to((0.2, 0.4, 0.9), (6, 8, 3)), atol=1e-6)
    level = Camera.look_at(eye=(0, 0, 0), target=(1, 0, 0), width=8, height=6, fov_y_deg=40)
    bg = sky.background(level)
    assert bg.shape == (6, 8, 3)
    np.testing.assert_allclose(bg[0], np.broadcast_to((0.2, 0.4, 0.9), (8, 3)), atol=1e-6)   # top row: sky
    np.testing.assert_allclose(bg[-1], np.broadcast_to((0.3, 0.25, 0.2), (8, 3)), atol=1e-6)  # bottom: ground
