"""Object masks trimmed to the pixels the object covers most of."""

import numpy as np
import pytest

from morphosim_gym.priors.rims import trim_rims

from ._stages import with_and_without

OBJ, SET = np.array([200.0, 40.0, 40.0]), np.array([110.0, 110.0, 100.0])


def _disc_frame(h=48, w=48, r=6.3, centre=(23.4, 24.7), up=8):
    """A red disc on a grey setting, each pixel's colour mixed by how much of it the disc covers
    (rendered `up` times finer and averaged); returns (frame [H, W, 3], coverage [H, W])."""
    yy, xx = np.mgrid[0:h * up, 0:w * up] / up
    inside = ((yy - centre[0]) ** 2 + (xx - centre[1]) ** 2 <= r * r).astype(np.float64)
    cover = inside.reshape(h, up, w, up).mean(axis=(1, 3))
    frame = cover[..., None] * OBJ + (1.0 - cover[..., None]) * SET
    return np.clip(frame, 0, 255).astype(np.uint8), cover


def test_a_mask_that_takes_every_touched_pixel_is_trimmed_to_half_coverage():
    frame, cover = _disc_frame()
    ids = np.where(cover > 0, 1, 0).astype(np.int32)          # motion's mask: every pixel touched
    ids[:3, :3] = 2                                          # another object, not asked for
    before = ids.copy()
    out = trim_rims(frame, ids, [1])
    truth = cover >= 0.5
    got = out == 1
    assert (got & truth).sum() / (got | truth).sum() > 0.98
    assert ((ids == 1) & truth).sum() / ((ids == 1) | truth).sum() < 0.9       # the fat mask was not
    assert np.array_equal(ids, before) and np.all(out[:3, :3] == 2)           # input kept, others kept
    assert set(np.unique(out[(ids == 1) & (out != 1)]).tolist()) <= {0}       # trimmed to the setting


def test_a_rim_against_the_sky_is_trimmed_to_it_where_asked():
    # a disc up in the sky: no setting anywhere, the sky unlabelled (-1); its rim against the sky
    # goes to the sky only where -1 is named a backdrop
    frame, cover = _disc_frame()
    ids = np.where(cover > 0, 1, -1).astype(np.int32)
    assert np.array_equal(trim_rims(frame, ids, [1]), ids)                # no setting: nothing to trim to
    out = trim_rims(frame, ids, [1], backdrops=(-1,))
    truth = cover >= 0.5
    assert ((out == 1) & truth).sum() / ((out == 1) | truth).sum() > 0.98
    assert set(np.unique(out[(ids == 1) & (out != 1)]).tolist()) == {-1}
    # a disc half on the ground (setting 0, below row 24), half against the sky: each rim pixel
    # goes to what lies behind it
    ids2 = np.where(cover > 0, 1, np.where(np.arange(48)[:, None] >= 24, 0, -1)).astype(np.int32)
    out2 = trim_rims(frame, ids2, [1], backdrops=(-1,))
    dropped = (ids2 == 1) & (out2 != 1)
    assert set(np.unique(out2[dropped & (np.arange(48)[:, None] < 22)]).tolist()) == {-1}
    assert set(np.unique(out2[dropped & (np.arange(48)[:, None] > 26)]).tolist()) == {0}
    with pytest.raises(ValueError, match="backdrops that are not objects"):
        trim_rims(frame, ids, [1], backdrops=(1,))


def test_a_rim_that_cannot_be_told_by_colour_stays():
    frame, cover = _disc_frame()
    grey = np.clip(cover[..., None] * (SET + 8.0) + (1.0 - cover[..., None]) * SET, 0, 255).astype(np.uint8)
    ids = np.where(cover > 0, 1, 0).astype(np.int32)
    assert np.array_equal(trim_rims(grey, ids, [1]), ids)


def test_bad_shapes_name_the_problem():
    frame, cover = _disc_frame()
    with pytest.raises(ValueError, match="ids"):
        trim_rims(frame, np.zeros((10, 10), np.int32), [1])


def test_estimated_masks_of_a_generated_clip_lose_their_rim():
    clip, on, off = with_and_without("A car is moving from right to left through a serene sunlit meadow", "rims")

    def precision_recall(out):
        k = next(i for i, n in out.labels.items() if n == "car")
        gt = np.isin(clip.masks, [i for i, n in clip.labels.items() if n == "car"])
        got = out.masks == k
        return (gt & got).sum() / got.sum(), (gt & got).sum() / gt.sum()

    (p0, r0), (p1, r1) = precision_recall(off), precision_recall(on)
    assert p1 > p0 + 0.02 and r1 > 0.93, (p0, r0, p1, r1)


def test_estimated_masks_of_a_bird_in_the_sky_lose_their_rim():
    # no ground seen (a bird up in the sky): the rim against the unlabelled sky is trimmed too
    clip, on, off = with_and_without("a bird flies from left to right across the sky", "rims")
    k = next(i for i, n in on.labels.items() if n == "bird")
    gt = np.isin(clip.masks, [i for i, n in clip.labels.items() if n == "bird"])

    def precision_recall(out):
        got = out.masks == k
        return (gt & got).sum() / got.sum(), (gt & got).sum() / gt.sum()

    (p0, r0), (p1, r1) = precision_recall(off), precision_recall(on)
    assert p1 > p0 + 0.03 and r1 > 0.93, (p0, r0, p1, r1)
