"""The threshold search's scorer: the candidate that agrees with the 2D evidence wins."""

import numpy as np

from morphosim_gym.edit.select import MaskAgreementScorer


def _maps():
    target = np.zeros((2, 16, 16), bool)
    target[:, 4:12, 4:12] = True                         # 64 pixels
    exact = target.astype(np.float32)
    too_small = np.zeros_like(exact)
    too_small[:, 6:10, 6:10] = 1.0                       # 16 of them
    too_big = np.ones_like(exact)                        # everything
    return np.stack([too_small, exact, too_big], axis=-1), target


def test_the_candidate_matching_the_evidence_scores_best():
    soft, target = _maps()
    scores = MaskAgreementScorer()(soft, target)
    assert scores.shape == (3,)
    assert int(np.argmax(scores)) == 1
    assert abs(scores[1] - 1.0) < 1e-6 and abs(scores[0] - 0.25) < 1e-6 and abs(scores[2] - 0.25) < 1e-6


def test_an_unstable_selection_is_charged():
    soft, target = _maps()
    flicker = soft[..., 1:2].copy()
    flicker[1] = 0.0                                     # gone in the second view
    both = np.concatenate([soft[..., 1:2], flicker], axis=-1)
    s = MaskAgreementScorer(consistency_weight=0.2)(both, target)
    assert s[0] > s[1] + 0.5
