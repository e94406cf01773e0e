"""FeatureDecoder: decoding and the similarity shortcut that never forms the decoded vectors."""

import numpy as np
import pytest

from morphosim_gym.scene import FeatureDecoder


def _decoder(layers, normalize, seed=0):
    rng = np.random.default_rng(seed)
    dims = list(zip(layers[:-1], layers[1:]))
    return FeatureDecoder("semantic", [rng.normal(size=d) for d in dims], [rng.normal(size=d[1]) for d in dims],
                          normalize=normalize)


@pytest.mark.parametrize("layers", [(8, 5), (8, 16, 12), (8, 16, 16, 12)])
@pytest.mark.parametrize("normalize", [True, False])
def test_similarity_equals_decoding_then_dot_products(layers, normalize):
    dec = _decoder(layers, normalize)
    rng = np.random.default_rng(1)
    x = rng.normal(size=(500, layers[0])).astype(np.float32)
    targets = rng.normal(size=(3, layers[-1]))
    decoded = dec(x)
    if normalize:
        np.testing.assert_allclose(np.linalg.norm(decoded, axis=1), 1.0, rtol=1e-5)
    np.testing.assert_allclose(dec.similarity(x, targets), decoded @ targets.T.astype(np.float32), rtol=1e-4, atol=1e-4)
    # leading dimensions are kept, as for decoding
    assert dec.similarity(x.reshape(50, 10, -1), targets).shape == (50, 10, 3)


def test_similarity_rejects_targets_of_the_wrong_width():
    dec = _decoder((8, 16, 12), True)
    with pytest.raises(ValueError, match=r"targets \[P, 12\]"):
        dec.similarity(np.zeros((4, 8), np.float32), np.zeros((3, 11)))
    with pytest.raises(ValueError, match="last dimension 8"):
        dec.similarity(np.zeros((4, 7), np.float32), np.zeros((3, 12)))
