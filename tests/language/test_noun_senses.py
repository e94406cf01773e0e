"""Which sense of a noun, and of a candidate's name, counts (issue #19, class 2): senses WordNet's corpus
tags far less often do not count, a fruit is not its tree, a name WordNet knows whole is a kind of its
head, a candidate's tags pick the sense of its name, and a noun-noun phrase is not shown by a sibling."""

import pytest

from morphosim_gym.generate.real_assets import asset_candidates
from morphosim_gym.language import hypernyms, open_vocab, parse, wordnet

pytestmark = pytest.mark.skipif(not wordnet.available(), reason="needs WordNet (apt install wordnet-base)")


def test_a_rarely_tagged_sense_does_not_count():
    assert hypernyms.related("tractor", "truck") is False        # the tractor unit of a truck is tagged 0 : 3
    assert hypernyms.shared_kind("candy", category="rock") is None   # rock candy is not what "rock" means
    assert hypernyms.related("toilet", "Toilet") is True           # two senses tagged 3 : 2 both count


@pytest.mark.parametrize("word", ["peach", "mango", "carrot"])
def test_a_fruit_or_vegetable_is_not_its_plant(word):
    assert hypernyms.ranked_senses(word)[0].lexfile == "food"


def test_a_compound_name_is_a_kind_of_its_head_not_its_modifier():
    assert not open_vocab._appositive("shower", "Shower curtain")
    assert open_vocab._appositive("chandelier", "Chandelier lamp")


def test_a_candidates_tags_pick_the_sense_of_its_name():
    assert hypernyms.related("toilet", "Small lavatory") is True            # lavatory: the toilet room
    assert hypernyms.related("toilet", "Small lavatory", tags=("washbasin",)) is False


@pytest.fixture
def real(monkeypatch):
    monkeypatch.delenv("MORPHOSIM_ASSET_SOURCES", raising=False)
    if not asset_candidates("chair"):
        pytest.skip("needs the Sweet Home 3D furniture (apt install sweethome3d-furniture)")


@pytest.mark.parametrize("text,not_this", [("a shower", "Shower curtain"), ("a toilet", "Small lavatory"),
                                           ("a rice cooker", "Water cooler"), ("a stop sign", "Emergency sign")])
def test_no_checked_match_to_another_thing(real, text, not_this):
    import morphosim_gym.generate.compose  # noqa: F401  (registers the real assets)
    from morphosim_gym.generate.real_assets import asset_index

    o = parse(text).objects[0]
    name = asset_index().get(o.category[len("asset:"):]).name if o.category.startswith("asset:") else o.category
    assert o.grounding == "kind" or name != not_this, (o.category, o.grounding)
