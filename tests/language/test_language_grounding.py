"""Grounding with the real all-MiniLM-L6-v2 model, and the shared embedding service."""

import threading

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.language import embeddings, wordnet
from morphosim_gym.language.grounding import GROUNDING_FLOOR, ground_noun, using_level


@pytest.mark.parametrize("noun, category", [("sedan", "car"), ("puppy", "dog"), ("kitten", "cat"),
                                            ("parrot", "bird"), ("stallion", "horse"), ("teacup", "cup"),
                                            ("helicopter", "airplane"), ("vehicle", "car")])
def test_unknown_nouns_ground_to_the_nearest_category(minilm, noun, category):
    with using_level("nearest"):
        g = ground_noun(noun)
    assert (g.category, g.method) == (category, "embedding")
    assert g.similarity >= GROUNDING_FLOOR
    # the default level ("kind") agrees; a helicopter is not an airplane, so with WordNet it is a
    # stand-in of the same kind (an aircraft) rather than a checked match
    g = ground_noun(noun)
    kind = "kind" if noun == "helicopter" and wordnet.available() else "embedding"
    assert (g.category, g.method) == (category, kind)
    assert g.similarity >= GROUNDING_FLOOR


def test_vocabulary_nouns_do_not_need_the_model():
    g = ground_noun("lorry")
    assert (g.category, g.method, g.similarity) == ("truck", "vocabulary", None)


def test_grounded_objects_keep_the_noun_as_written(minilm):
    plan = ms.parse("a red sedan drives to the left; then make the car blue")
    o = plan.objects[0]
    assert (o.name, o.noun, o.category, o.grounding) == ("sedan", "sedan", "car", "embedding")
    assert 0 < o.similarity <= 1
    assert plan.then[0].edits[0].targets[0].objects == ("sedan",)


@pytest.mark.parametrize("noun", ["zxqv", "happiness", "democracy", "qwerty"])
def test_below_the_floor_is_a_clear_error(minilm, noun):
    with pytest.raises(ms.CommandError) as e:
        ground_noun(noun)
    msg = str(e.value)
    assert noun in msg and "Known categories" in msg and "elephant" in msg
    with pytest.raises(ms.CommandError, match="Known categories"):
        ms.parse(f"a {noun} moves to the left")


def test_edit_targets_by_meaning(minilm, scene_factory):
    scene = scene_factory("road", "bus", "person", "tree")
    assert ms.parse("make the vehicle blue", scene).edits[0].targets[0].objects == ("bus",)
    assert ms.parse("paint the pedestrian red", scene).edits[0].targets[0].objects == ("person",)


def test_embedding_api(minilm):
    assert embeddings.embedding_dim() == 384
    v = embeddings.embed(["a red car", "the vehicle", "a puppy"])
    assert v.shape == (3, 384) and v.dtype == np.float32
    assert np.allclose(np.linalg.norm(v, axis=1), 1.0, atol=1e-5)
    assert embeddings.embed([]).shape == (0, 384)
    one = embeddings.embed_one("a red car")
    assert np.array_equal(one, v[0])  # cached and order-independent
    sim = embeddings.similarity(["a car"], ["an automobile", "a banana"])
    assert sim.shape == (1, 2) and sim[0, 0] > sim[0, 1]
    with pytest.raises(TypeError):
        embeddings.embed("not a list")  # type: ignore[arg-type]


def test_embedding_cache_is_thread_safe_and_deterministic(minilm):
    phrases = [f"a small object number {i}" for i in range(12)]
    ref = {p: embeddings.embed_one(p).copy() for p in phrases}
    embeddings.clear_cache()
    out: dict[int, np.ndarray] = {}

    def work(k: int) -> None:
        out[k] = embeddings.embed(phrases[k % 3::2])

    threads = [threading.Thread(target=work, args=(k,)) for k in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, arr in out.items():
        for row, p in zip(arr, phrases[k % 3::2]):
            assert np.array_equal(row, ref[p])  # bit-identical whatever the batch or thread
    assert embeddings.cache_size() >= 6
