"""Nouns the parser used to misread (issue #19, class 1): a thing WordNet knows in a noun's place is
no typo, compounds are read whole, a compound is not its head's vocabulary category when it names
another thing, and "a desk" is a thing, not the table setting."""

import pytest

from morphosim_gym.errors import CommandError
from morphosim_gym.language import parse, wordnet

pytestmark = pytest.mark.skipif(not wordnet.available(), reason="needs WordNet (apt install wordnet-base)")


def _nouns(text: str) -> list[str]:
    """The plan's object nouns; without asset sources a refusal must name the noun (not a misreading)."""
    try:
        return [o.noun for o in parse(text).objects]
    except CommandError as err:
        msg = str(err)
        assert "Could not understand the noun" in msg, msg
        return [msg.split("the noun '", 1)[1].split("'", 1)[0]]


@pytest.mark.parametrize("text,noun", [("a freezer", "freezer"), ("a plunger", "plunger"), ("two red mopeds", "moped")])
def test_a_thing_in_a_nouns_place_is_no_typo(text, noun):
    assert _nouns(text) == [noun]          # not "a freeze", "a plunge", "moved"


def test_typos_elsewhere_are_still_repaired():
    plan = parse("make the cube bleu")     # "bleu" is a cheese, but here it is the colour
    assert plan.edits[0].color.name == "blue"


@pytest.mark.parametrize("text,noun", [("a parking meter", "meter"), ("an old parking meter", "meter"), ("a stop sign", "sign"),
                                       ("a red stop sign on the road", "sign")])
def test_a_verb_before_a_noun_is_part_of_the_noun(text, noun):
    assert _nouns(text) == [noun]


def test_a_compound_is_not_its_first_words_setting_or_colour():
    try:
        plan = parse("an ice cream")
    except CommandError as err:
        assert "the noun 'cream'" in str(err)
        return
    assert [o.noun for o in plan.objects] == ["cream"] and plan.setting != "snow"
    assert plan.objects[0].color is None


def test_a_compound_naming_another_thing_is_not_its_heads_category():
    try:
        cats = [o.category for o in parse("a hot dog").objects]
    except CommandError:
        cats = []
    assert "dog" not in cats
    assert [o.category for o in parse("a sheep dog runs left").objects] == ["dog"]   # a kind of dog stays one
    assert [o.category for o in parse("a school bus drives left").objects] == ["bus"]


def test_a_desk_is_a_thing_and_the_desk_still_a_setting():
    plan = parse("a desk")
    assert [(o.noun, o.category) for o in plan.objects] == [("desk", "table")]
    plan = parse("a cube on a desk")
    assert [o.category for o in plan.objects] == ["cube"] and plan.setting == "table"
