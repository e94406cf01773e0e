"""The sky told from the setting by colour: a ground that ends short of the horizon, hills above it."""


import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.priors import default_estimators, prepare_priors
from morphosim_gym.priors.prepare import open_sky, setting_label
from morphosim_gym.priors.skyline import horizon_rows, sky_region

H, W = 64, 64
SKY, GROUND, HILLS = (120, 160, 215), (140, 110, 80), (115, 90, 65)    # hills: a darker shade of the ground


def _frame(sky_rows, hills=None, seed=0, haze=False):
    """[H, W, 3]: a textured sky above `sky_rows` [W] and ground below, optional hills rows [W] between."""
    rng = np.random.default_rng(seed)
    rows = np.arange(H)[:, None]
    f = np.where((rows < sky_rows[None, :])[..., None], SKY, GROUND).astype(np.float64)
    if hills is not None:
        f[(rows >= hills[None, :]) & (rows < sky_rows[None, :])] = HILLS
        f[rows < hills[None, :]] = SKY
    if haze:                                        # far ground paler, as distance does
        f = f + (1.0 - rows / H)[..., None] * 60.0
    return np.clip(f + rng.normal(0, 6, f.shape), 0, 255).astype(np.uint8)


def _iou(a, b):
    return (a & b).sum() / (a | b).sum()


def test_the_sky_below_the_horizon_is_found_where_the_ground_ends():
    x = np.arange(W)
    ends = (26 + 4 * np.sin(x / 9.0)).astype(int)          # the ground ends below the horizon (row 16)
    horizon = np.full(W, 16)
    frame = _frame(ends)
    objects = np.zeros((H, W), bool)
    objects[10:22, 30:40] = True                           # a bird in the sky: never sky
    sky = sky_region(frame, objects, horizon)
    truth = (np.arange(H)[:, None] < ends[None, :]) & ~objects
    assert sky is not None and _iou(sky, truth) > 0.95
    assert not (sky & objects).any()
    assert _iou(np.arange(H)[:, None] < horizon[None, :], truth) < 0.75     # the horizon alone misses it


def test_hills_above_the_horizon_stay_the_setting():
    x = np.arange(W)
    top = (12 + 3 * np.sin(x / 7.0)).astype(int)           # hills from here down to the horizon
    horizon = np.full(W, 20)
    sky = sky_region(_frame(horizon, hills=top), np.zeros((H, W), bool), horizon)
    truth = np.arange(H)[:, None] < top[None, :]
    assert sky is not None and _iou(sky, truth) > 0.9


def test_colour_cannot_tell_when_no_sky_is_seen_or_sky_and_ground_look_alike():
    objects = np.zeros((H, W), bool)
    # looking down: the ground plane fills every row; paler far away, but that is no sky
    assert sky_region(_frame(np.zeros(W, int), haze=True), objects, np.zeros(W, int)) is None
    # an overcast sky the colour of the ground
    f = _frame(np.full(W, 20))
    f[:20] = _frame(np.zeros(W, int), seed=1)[:20]
    assert sky_region(f, objects, np.full(W, 20)) is None


def test_bad_shapes_name_the_problem():
    with pytest.raises(ValueError, match="horizon"):
        sky_region(_frame(np.full(W, 20)), np.zeros((H, W), bool), np.full(W + 1, 20))
    assert list(horizon_rows(np.arange(H)[:, None] >= np.array([3, 70])[None, :])) == [3, H]


@pytest.fixture(scope="module")
def ball_clip():
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=64, height=64, num_frames=9))
    return sim.generate_clip("A small, vibrant red rubber ball is bouncing across the ground", 0)


def _setting_scores(clip, est):
    gt = np.isin(clip.masks, [k for k, n in clip.labels.items() if n == setting_label(clip)])
    got = est.masks == 0
    return (gt & got).sum() / got.sum(), (gt & got).sum() / gt.sum()


def test_a_generated_ground_that_ends_leaves_the_sky_unlabelled_and_without_depth(ball_clip):
    clip = ball_clip
    assert open_sky(clip)
    est = prepare_priors(clip, "estimated")
    precision, recall = _setting_scores(clip, est)
    assert precision > 0.95 and recall > 0.95, (precision, recall)
    assert np.all(est.depth[est.masks < 0] == 0) and np.all(est.depth[est.masks == 0] > 0)
    # the ground plane's whole horizon takes sky for ground (the ground's 8-height reach alone
    # also ends it near where this one ends: `far_heights`)
    old = prepare_priors(clip, "estimated", estimators=default_estimators(clip, skyline=False, far_heights=None))
    assert _setting_scores(clip, old)[0] < 0.9
    assert default_estimators(clip).skyline         # on by default
