"""WordNet reader and "is a kind of" checks (skipped without Debian's wordnet-base)."""

import pytest

from morphosim_gym.errors import CommandError
from morphosim_gym.language import hypernyms, parse, wordnet
from morphosim_gym.language.rules.tokens import is_adverb
from morphosim_gym.language.vocabulary import CATEGORIES

needs_wordnet = pytest.mark.skipif(not wordnet.available(), reason="needs WordNet (apt install wordnet-base)")


def test_missing_files_answer_unknown(monkeypatch, tmp_path):
    monkeypatch.setenv(wordnet.ENV_VAR, str(tmp_path))
    monkeypatch.setattr(wordnet, "_state", {})
    hypernyms.visible_senses.cache_clear()
    try:
        assert not wordnet.available()
        assert wordnet.senses("dog") == []
        assert hypernyms.kind_category("eagle", CATEGORIES) is None
        assert hypernyms.related("eagle", "Bird") is None
    finally:
        hypernyms.visible_senses.cache_clear()


def test_head_word():
    assert hypernyms.head_word("Bowl with fruits") == "bowl"
    assert hypernyms.head_word("Electric guitar") == "guitar"
    assert hypernyms.head_word("TV 16:9") == "tv"
    assert hypernyms.head_word("Beige sofa 2 seats") == "seat"
    assert hypernyms.head_word("") == ""


@needs_wordnet
def test_senses_and_closure():
    dog = wordnet.senses("dog", 1)[0]
    assert "dog" in dog.lemmas and dog.lexfile == "animal"
    assert wordnet.senses("fire hydrant")          # compounds are looked up with underscores
    assert wordnet.senses("florbnax") == []
    up = wordnet.hypernym_closure(dog)
    assert up[dog.offset] == 0 and len(up) > 5


@needs_wordnet
@pytest.mark.parametrize("noun, category", [("eagle", "bird"), ("sedan", "car"), ("puppy", "dog"),
                                            ("armchair", "chair"), ("shark", "fish"), ("nurse", "person")])
def test_kind_category(noun, category):
    assert hypernyms.kind_category(noun, CATEGORIES) == category


@needs_wordnet
@pytest.mark.parametrize("noun", ["tiger", "pear", "goat", "helicopter", "monitor", "zebra"])
def test_not_a_kind_of_any_category(noun):
    # tiger is a big cat, not a cat; a pear is the fruit, not the pear tree; a monitor is not a proctor
    assert hypernyms.kind_category(noun, CATEGORIES) is None


@needs_wordnet
def test_related():
    assert hypernyms.related("seat", "Armchair") is True          # the asset is a kind of the noun
    assert hypernyms.related("couch", "Sofa") is True              # the same sense
    assert hypernyms.related("kettle", "Teapot") is False
    assert hypernyms.related("rake", "Tool") is False              # too general to show a rake
    assert hypernyms.related("florbnax", "Tool") is None


@needs_wordnet
def test_sense_counts_and_hyphenated_compounds():
    assert wordnet.sense_counts("dog")[0] > 0 and len(wordnet.sense_counts("dog")) == len(wordnet.senses("dog"))
    assert wordnet.sense_counts("florbnax") == ()
    assert wordnet.senses("go kart")                  # WordNet's "go-kart"


@needs_wordnet
@pytest.mark.parametrize("word, lexfile, gloss_word", [("turtle", "animal", "reptile"), ("mango", "food", "fruit"),
                                                       ("monitor", "artifact", "display"),
                                                       ("peacock", "animal", "peafowl")])
def test_dominant_sense_beats_wordnet_order(word, lexfile, gloss_word):
    # WordNet lists the turtleneck, the mango tree, the warship and the peacock butterfly first (all
    # untagged or tagged equally often); the dominant sense is the one a person means
    top = hypernyms.ranked_senses(word)[0]
    assert top.lexfile == lexfile and gloss_word in top.gloss


@needs_wordnet
def test_fruit_is_not_its_tree():
    assert hypernyms.kind_category("mango", CATEGORIES) != "tree"


@needs_wordnet
def test_a_candidate_is_read_through_its_dominant_sense():
    # "Peacock" is the bird: it shares nothing meaningful with a spider (not "arthropod" via the butterfly)
    assert hypernyms.shared_kind("spider", text="Peacock") is None
    assert hypernyms.shared_kind("turtle", text="Helmet") is None          # the reptile, not the turtleneck


@needs_wordnet
def test_a_tag_may_name_a_sense_that_is_no_visible_thing():
    # the mythical dragon is an imaginary being in WordNet, the flying lizard its only visible sense:
    # an asset "Dragon" tagged "firedrake" is the mythical one, so a lizard is no kind of it
    assert hypernyms.related("lizard", "Dragon") is True                       # untagged: the flying lizard
    assert hypernyms.related("lizard", "Dragon", tags=("animal", "firedrake")) is False
    assert hypernyms.related("lizard", "Monitor", tags=("monitor lizard",)) is True   # a visible sense named by a tag


@needs_wordnet
def test_ly_nouns_are_not_adverbs():
    assert is_adverb("slowly") and is_adverb("steadily")
    assert not is_adverb("butterfly") and not is_adverb("dragonfly")
    assert parse("a dog runs quickly to the right").motions[0].speed_word == "quickly"
    # the noun reaches grounding (which refuses it: no insect asset), not a parser dead end
    with pytest.raises(CommandError, match="noun 'dragonfly': it is not close to any object category"):
        parse("a dragonfly moves left slowly")
