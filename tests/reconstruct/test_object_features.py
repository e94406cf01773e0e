"""Prototype latents for Gaussians added after the fit: they must decode as their object's name."""

from __future__ import annotations

import numpy as np
import pytest

from morphosim_gym.language import embeddings
from morphosim_gym.reconstruct.object_features import name_margins, object_prototypes
from morphosim_gym.scene import FeatureDecoder, Gaussians, SceneObject

OBJECTS = (SceneObject(0, "road", "road", role="background"), SceneObject(1, "person", "person"))


def _decoder() -> FeatureDecoder:
    d = embeddings.embedding_dim()
    return FeatureDecoder("semantic", [np.eye(d)], [np.zeros(d)], normalize=True)   # latents are embeddings


def _blended_person() -> Gaussians:
    """Road Gaussians, and person Gaussians of which most learned a road-heavy blend (a small mover
    over a large street) and a few read clearly as the person."""
    road, person = embeddings.embed(["road", "person"])
    n_road, n_blend, n_clear = 40, 57, 3
    feats = np.vstack([np.tile(road, (n_road, 1)), np.tile(0.75 * road + 0.25 * person, (n_blend, 1)),
                       np.tile(person, (n_clear, 1))])
    n = len(feats)
    return Gaussians(means=np.zeros((n, 3)), quats=np.tile([1.0, 0, 0, 0], (n, 1)), scales=np.full((n, 3), 0.01),
                     opacities=np.full(n, 0.9), colors=np.full((n, 3), 0.5), features=feats,
                     object_ids=[0] * n_road + [1] * (n_blend + n_clear))


def test_the_prototype_reads_as_its_object_where_the_mean_reads_as_the_setting():
    g, dec = _blended_person(), _decoder()
    names = [o.name for o in OBJECTS]
    mean = np.asarray(g.features)[np.asarray(g.object_ids) == 1].mean(axis=0)
    assert name_margins(dec, mean[None], names)[0, 1] < 0                 # the blend decodes as "road"
    protos = object_prototypes(g, OBJECTS, dec)
    margins = name_margins(dec, np.stack([protos[0], protos[1]]), names)
    assert margins[0, 0] > 0 and margins[1, 1] > 0


def test_without_a_decoder_the_prototype_is_the_mean_and_without_features_there_is_none():
    g = _blended_person()
    protos = object_prototypes(g, OBJECTS, None)
    np.testing.assert_allclose(protos[1], np.asarray(g.features)[np.asarray(g.object_ids) == 1].mean(axis=0),
                               rtol=1e-5)
    assert object_prototypes(g.replace(features=None), OBJECTS, _decoder()) == {}


def test_a_share_outside_0_1_is_refused():
    with pytest.raises(ValueError, match="share"):
        object_prototypes(_blended_person(), OBJECTS, _decoder(), share=0.0)


def test_when_no_latent_reads_as_the_object_the_prototype_is_steered_until_it_does():
    """A fast mover the fit never drew: every latent, its own included, decodes as the road, in the
    semantic channel and in the instance channel. The prototype is steered through the frozen
    decoders until it reads as the person and as the person's instance code."""
    from morphosim_gym.reconstruct.object_features import code_margins
    from morphosim_gym.scene import instance_codes

    d = embeddings.embedding_dim()
    k = 16
    sem = FeatureDecoder("semantic", [np.vstack([np.eye(d), np.zeros((k, d))])], [np.zeros(d)], normalize=True)
    inst = FeatureDecoder("instance", [np.vstack([np.zeros((d, k)), np.eye(k)])], [np.zeros(k)], normalize=True)
    road, person = embeddings.embed(["road", "person"])
    blend = 0.8 * road + 0.2 * person
    code_road = instance_codes([0])[0]
    feats = np.vstack([np.tile(np.concatenate([road, code_road]), (30, 1)),
                       np.tile(np.concatenate([blend, code_road]), (20, 1))])
    n = len(feats)
    g = Gaussians(means=np.zeros((n, 3)), quats=np.tile([1.0, 0, 0, 0], (n, 1)), scales=np.full((n, 3), 0.01),
                  opacities=np.full(n, 0.9), colors=np.full((n, 3), 0.5), features=feats, object_ids=[0] * 30 + [1] * 20)
    names = [o.name for o in OBJECTS]
    assert name_margins(sem, feats, names)[:, 1].max() < 0                 # nothing reads as the person
    protos = object_prototypes(g, OBJECTS, sem, instance=inst)
    assert name_margins(sem, protos[1][None], names)[0, 1] > 0
    assert code_margins(inst, protos[1][None], [0, 1])[0, 1] > 0
    assert name_margins(sem, protos[0][None], names)[0, 0] > 0             # the road's own stays the road's
