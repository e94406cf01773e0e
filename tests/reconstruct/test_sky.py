"""The sky of a fitted scene, estimated from the pixels its priors leave empty."""

import numpy as np
import pytest

from morphosim_gym.metrics import psnr
from morphosim_gym.reconstruct.sky import estimate_sky, pull_push
from morphosim_gym.scene.camera import Camera
from morphosim_gym.scene.sky import sky_background


def _panorama(h: int = 64) -> np.ndarray:
    """A smooth test sky: colours that change with azimuth and elevation (no two directions alike)."""
    v, u = np.meshgrid(np.linspace(0, 1, h), np.linspace(0, 1, 2 * h), indexing="ij")
    return np.stack([0.5 + 0.4 * np.sin(2 * np.pi * u), 0.2 + 0.7 * v, 0.5 + 0.3 * np.cos(6 * np.pi * u) * v],
                    -1).astype(np.float32)


def _cameras(yaws, size=48):
    """Cameras at the origin, level, looking along the given yaws (degrees) from +x."""
    cams = []
    for yaw in yaws:
        a = np.radians(yaw)
        target = np.array([np.cos(a), np.sin(a), 0.1])
        cams.append(Camera.look_at(np.zeros(3), target, width=size, height=size, fov_y_deg=60.0))
    return cams


def test_the_sky_seen_by_the_frames_is_what_the_estimate_shows_again():
    truth = _panorama()
    cams = _cameras([0.0, 20.0, 40.0])
    frames = np.stack([sky_background(truth, c) for c in cams])
    mask = np.ones(frames.shape[:3], bool)
    sky = estimate_sky(frames, cams, mask)
    assert sky.shape[1] == 2 * sky.shape[0] and sky.dtype == np.float32
    for c, f in zip(cams, frames):
        assert psnr(sky_background(sky, c), f) > 38.0
    # between the input views (a novel view), the sky is the same sky
    novel = _cameras([30.0])[0]
    assert psnr(sky_background(sky, novel), sky_background(truth, novel)) > 36.0


def test_only_the_masked_pixels_make_the_sky():
    truth = _panorama()
    cams = _cameras([0.0])
    frames = np.stack([sky_background(truth, c) for c in cams])
    mask = np.zeros(frames.shape[:3], bool)
    mask[:, :20] = True                      # the upper rows are sky; below, something else is drawn
    frames[:, 20:] = (1.0, 0.0, 0.0)
    sky = estimate_sky(frames, cams, mask)
    seen = sky_background(sky, cams[0])
    assert psnr(seen[:18], frames[0, :18]) > 36.0
    assert np.abs(seen[24:] - (1.0, 0.0, 0.0)).max(axis=-1).min() > 0.3    # no red below the horizon


def test_pull_push_keeps_what_was_seen_and_fills_the_rest_from_it():
    weighted = np.zeros((8, 16, 3))
    weight = np.zeros((8, 16))
    weighted[2, 3], weight[2, 3] = (0.2, 0.4, 0.6), 1.0
    weighted[5, 12], weight[5, 12] = (0.9, 0.1, 0.1), 1.0
    out = pull_push(weighted, weight)
    assert np.allclose(out[2, 3], (0.2, 0.4, 0.6)) and np.allclose(out[5, 12], (0.9, 0.1, 0.1))
    assert np.all(np.isfinite(out)) and out.min() >= 0.1 - 1e-9 and out.max() <= 0.9 + 1e-9
    # an unseen texel takes more of its nearer seen texel's colour
    assert out[2, 1, 2] > out[5, 15, 2] and out[5, 15, 0] > out[2, 1, 0]


def test_bad_input_is_named():
    cams = _cameras([0.0])
    frames = np.zeros((1, 48, 48, 3), np.uint8)
    with pytest.raises(ValueError, match="sky mask of shape"):
        estimate_sky(frames, cams, np.ones((1, 48, 40), bool))
    with pytest.raises(ValueError, match="one camera per frame"):
        estimate_sky(frames, cams * 2, np.ones((1, 48, 48), bool))
    with pytest.raises(ValueError, match="no"):
        estimate_sky(frames, cams, np.zeros((1, 48, 48), bool))
    with pytest.raises(ValueError, match=r"frames \[T, H, W, 3\]"):
        estimate_sky(frames[..., 0], cams, np.ones((1, 48, 48), bool))
