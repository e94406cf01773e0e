"""A multi-word unknown noun ("a go kart") is refused like any unknown noun: named, with the nearest candidates."""

import pytest

from morphosim_gym.errors import CommandError
from morphosim_gym.language import parse, wordnet


# WordNet knows "go-kart" (a motor vehicle), so at the default level "kind" it gets a stand-in of
# its kind (`test_compound_known_to_wordnet_stands_in`); at "checked" nothing shows it, so it is refused.
@pytest.mark.parametrize("text,level", [("a go kart moves left", "checked"), ("a red go kart moves left", "checked"),
                                        ("the go kart is moving left", "checked"), ("a kart moves left", None)])
def test_unknown_compound_noun_lists_the_nearest_candidates(text, level):
    with pytest.raises(CommandError) as err:
        parse(text, grounding=level)
    msg = str(err.value)
    assert "Could not understand the noun 'kart'" in msg and "Nearest shapes and assets:" in msg
    assert "dart" not in msg          # no typo "repair" of the noun into a verb


def test_verb_typos_are_still_repaired():
    plan = parse("a red ball moevs left")
    assert [o.category for o in plan.objects] == ["ball"] and plan.motions[0].direction_image == (-1.0, 0.0)


@pytest.mark.skipif(not wordnet.available(), reason="needs WordNet (apt install wordnet-base)")
def test_compound_known_to_wordnet_stands_in():
    """"go kart" is WordNet's hyphenated "go-kart": at the level "kind" a stand-in, never a typo."""
    obj = parse("a go kart moves left", grounding="kind").objects[0]
    assert obj.noun == "kart" and obj.grounding == "kind"
