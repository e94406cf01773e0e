"""An object whose contact is hidden takes its depth from a sibling of the same size (`priors.siblings`)."""

import numpy as np
import pytest

from morphosim_gym.priors import ObjectSize, RGBPriorEstimators
from morphosim_gym.priors.siblings import depths_from_siblings, hidden_share, whole_width
from morphosim_gym.scene import Camera


def _pair(behind_cols=(20, 35), front_cols=(16, 36)):
    """[1, 48, 64] ids: object 1 behind (rows 10-20), object 2 in front right under it (rows 21-34)."""
    m = np.zeros((1, 48, 64), np.int32)
    m[0, 10:21, behind_cols[0]:behind_cols[1]] = 1
    m[0, 21:35, front_cols[0]:front_cols[1]] = 2
    return m


def test_hidden_share_and_whole_width():
    m = _pair()
    behind, front = m[0] == 1, m[0] == 2
    assert hidden_share(behind, front) == 1.0 and hidden_share(front, behind) == 0.0
    assert whole_width(front, behind) == 20 and whole_width(behind, front) == 15
    touching = np.zeros_like(front)
    touching[10:21, 35] = True                         # something right beside its right end
    assert whole_width(behind, touching) is None
    edge = np.zeros_like(front)
    edge[5:9, 0:6] = True                              # at the image border
    assert whole_width(edge, np.zeros_like(edge)) is None


def test_a_hidden_object_takes_its_siblings_depth_times_their_widths():
    m = _pair()
    depths = {1: np.array([9.0]), 2: np.array([3.0])}
    out = depths_from_siblings(m, depths, [[1, 2]])
    assert out[1][0] == pytest.approx(3.0 * 20 / 15) and out[2][0] == 3.0
    # not siblings (another planned object): left as it was
    assert depths_from_siblings(m, depths, [[1], [2]])[1][0] == 9.0
    # never nearer than the sibling hiding it: a wider mask behind stays at the front one's depth
    wide = _pair(behind_cols=(14, 40), front_cols=(20, 34))
    out = depths_from_siblings(wide, {1: np.array([9.0]), 2: np.array([3.0])}, [[1, 2]])
    assert out[1][0] == 3.0
    # its contact mostly free (half of it shows): its own depth stays
    half = _pair(behind_cols=(20, 36), front_cols=(28, 44))
    assert depths_from_siblings(half, {1: np.array([9.0]), 2: np.array([3.0])}, [[1, 2]])[1][0] == 9.0


def test_the_estimators_use_it_for_numbered_instances_only():
    cam = Camera.look_at((0.0, -6.0, 2.0), (0.0, 0.0, 0.5), width=64, height=48, fov_y_deg=50.0)
    m = _pair()
    frames = np.zeros((1, 48, 64, 3), np.uint8)
    size = {"sheep": ObjectSize(1.0, 1.5, "ground")}
    labels = {0: "grass", 1: "sheep 1", 2: "sheep 2"}

    def behind(est, labels) -> float:
        return float(est.depth(frames, cam, masks=m, labels=labels, sizes=size)[0][m[0] == 1][0])

    def front(est) -> float:
        return float(est.depth(frames, cam, masks=m, labels=labels, sizes=size)[0][m[0] == 2][0])

    on, off = RGBPriorEstimators(), RGBPriorEstimators(sibling_scale=False)
    assert behind(on, labels) == pytest.approx(front(on) * 20 / 15, rel=1e-5)
    assert behind(off, labels) > 1.1 * behind(on, labels)     # its few free columns read the far ground
    other = {0: "grass", 1: "sheep", 2: "dog"}                 # two planned objects, not one numbered
    assert behind(on, other) == pytest.approx(behind(off, other))


def test_hidden_frames_without_a_whole_width_go_on_from_the_scaled_ones():
    # frames 0 and 2 scaled from the sibling; in frame 1 a third object beside its end cuts its
    # width: its depth is interpolated in time, not its far contact (a jump within the clip)
    m = np.concatenate([_pair(), _pair(), _pair()])
    m[1, 10:21, 35:38] = 3
    depths = {1: np.array([9.0, 9.0, 9.0]), 2: np.array([3.0, 3.3, 3.6])}
    out = depths_from_siblings(m, depths, [[1, 2]])
    np.testing.assert_allclose(out[1], [3.0 * 20 / 15, 3.3 * 20 / 15, 3.6 * 20 / 15])
