"""Mask-based encoders keep a frame as an index map and a table (not a dense per-pixel map), and
the distillation reads the same targets either way."""

import numpy as np
import pytest
import torch

import morphosim_gym as ms
from morphosim_gym.reconstruct.features import (FeatureConfig, InstanceCodeEncoder, LabelEmbeddingEncoder,
                                                _FrameTarget, distill_features)
from morphosim_gym.reconstruct.initialize import initialize
from morphosim_gym.scene import instance_codes


@pytest.fixture(scope="module")
def clip():
    sim = ms.MorphoSim(generation=ms.GenerationConfig(width=40, height=32, num_frames=5, detail=0.5),
                       reconstruction="oracle")
    c = sim.generate_clip("two sheep walk across the field from left to right", seed=0)
    assert (c.masks[0] < 0).any() and len(np.unique(c.masks[0])) >= 3       # sky, grass, sheep
    return c


def _painted(masks: np.ndarray, vectors: dict, dim: int) -> np.ndarray:
    """The plain reference: each instance's pixels painted with its vector, zeros elsewhere."""
    out = np.zeros(masks.shape + (dim,), np.float32)
    for inst, vec in vectors.items():
        out[masks == inst] = vec
    return out


def test_the_semantic_encoder_is_each_labels_embedding(clip):
    from morphosim_gym.language import embeddings

    enc = LabelEmbeddingEncoder()
    index, table, valid = enc.encode_indexed(clip, 0)
    assert table.shape == (len(clip.labels) + 1, enc.dim) and index.shape == clip.masks[0].shape
    names = sorted(clip.labels)
    ref = _painted(clip.masks[0], dict(zip(names, embeddings.embed([clip.labels[i] for i in names]))), enc.dim)
    np.testing.assert_array_equal(table[index], ref)
    feat, valid2 = enc.encode(clip, 0)
    np.testing.assert_array_equal(feat, ref)
    assert (valid == (clip.masks[0] >= 0)).all() and (valid2 == valid).all()
    assert not feat[clip.masks[0] < 0].any()      # the sky (no instance): zeros


def test_one_semantic_encoder_follows_each_clips_labels(clip):
    """An encoder used for a second clip whose ids name other things gives that clip's labels."""
    from dataclasses import replace

    enc = LabelEmbeddingEncoder()
    first, _ = enc.encode(clip, 0)
    ids = sorted(clip.labels)
    swapped = replace(clip, labels={i: clip.labels[j] for i, j in zip(ids, ids[::-1])})
    second, _ = enc.encode(swapped, 0)
    fresh, _ = LabelEmbeddingEncoder().encode(swapped, 0)
    np.testing.assert_array_equal(second, fresh)
    assert not np.array_equal(first, second)


def test_the_instance_encoder_is_each_ids_code(clip):
    enc = InstanceCodeEncoder()
    index, table, valid = enc.encode_indexed(clip, 0)
    ids = [int(i) for i in np.unique(clip.masks[0]) if i >= 0]
    ref = _painted(clip.masks[0], dict(zip(ids, instance_codes(ids, enc.dim))), enc.dim)
    np.testing.assert_array_equal(table[index], ref)
    np.testing.assert_array_equal(enc.encode(clip, 0)[0], ref)
    assert table.shape[0] == len(ids) + 1          # one row per instance and the zero row, not one per pixel


def test_a_frame_target_reads_pixels_at_reduced_resolution(clip):
    rows, cols = np.array([0, 5, 31]), np.array([2, 2, 39, 10])
    enc = LabelEmbeddingEncoder()
    dense, valid = enc.encode(clip, 0)
    target = _FrameTarget.encode(enc, clip, 0, rows, cols)
    want = dense[rows[:, None], cols[None, :]].reshape(-1, enc.dim)
    np.testing.assert_array_equal(target.at(np.arange(len(want))), want)
    np.testing.assert_array_equal(target.valid, valid[rows[:, None], cols[None, :]])
    t = target.as_torch()
    np.testing.assert_array_equal(t.at(torch.tensor([4, 0])).numpy(), want[[4, 0]])


class _Dense:
    """An encoder that hides `encode_indexed` (the distillation then keeps its dense maps)."""

    def __init__(self, inner) -> None:
        self._inner = inner
        self.name, self.dim, self.normalize = inner.name, inner.dim, inner.normalize

    def encode(self, clip, frame):
        return self._inner.encode(clip, frame)


def test_indexed_and_dense_targets_distill_the_same_field(clip):
    cfg = FeatureConfig(iterations=12, pixels=64, progress=False)
    out = []
    for wrap in (lambda e: e, _Dense):
        model = initialize(clip, seed=0).model
        encoders = [wrap(LabelEmbeddingEncoder()), wrap(InstanceCodeEncoder())]
        _, log = distill_features(model, clip, cfg, seed=0, encoders=encoders)
        out.append((model.features.detach().numpy().copy(), log["loss"]))
    np.testing.assert_array_equal(out[0][0], out[1][0])
    assert out[0][1] == out[1][1]
