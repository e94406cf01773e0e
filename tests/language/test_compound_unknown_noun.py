"""A multi-word unknown noun ("a go kart") is refused like any unknown noun: named, with the nearest candidates."""

import pytest

from morphosim_gym.errors import CommandError
from morphosim_gym.language import parse


@pytest.mark.parametrize("text", ["a go kart moves left", "a red go kart moves left", "the go kart is moving left",
                                  "a kart moves left"])
def test_unknown_compound_noun_lists_the_nearest_candidates(text):
    with pytest.raises(CommandError) as err:
        parse(text)
    msg = str(err.value)
    assert "Could not understand the noun 'kart'" in msg and "Nearest shapes and assets:" in msg
    assert "dart" not in msg          # no typo "repair" of the noun into a verb


def test_verb_typos_are_still_repaired():
    plan = parse("a red ball moevs left")
    assert [o.category for o in plan.objects] == ["ball"] and plan.motions[0].direction_image == (-1.0, 0.0)
