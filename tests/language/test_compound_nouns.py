"""Compound nouns WordNet knows are read whole: no typo repair, no camera verb, no verb reading."""

import pytest

from morphosim_gym.errors import CommandError

from morphosim_gym.language import parse, wordnet

pytestmark = pytest.mark.skipif(not wordnet.available(), reason="needs WordNet (apt install wordnet-base)")


def test_frying_pan_is_neither_a_typo_nor_a_camera_pan():
    try:   # without asset sources nothing may show a pan: then the refusal names the compound's head
        plan = parse("a red frying pan slides right")
    except CommandError as err:
        assert "the noun 'pan'" in str(err) and "flying" not in str(err)
        return
    assert [o.noun for o in plan.objects] == ["pan"] and plan.camera.motion == "fixed"
    assert "flying" not in repr(plan)


def test_a_verb_that_is_a_thing_alone_after_an_article_is_a_noun():
    try:
        nouns = [o.noun for o in parse("a swing").objects]
    except CommandError as err:   # no asset sources: refused as a noun, not "could not understand 'a swing'"
        assert "the noun 'swing'" in str(err)
        return
    assert nouns == ["swing"]


def test_camera_pan_and_typos_still_work():
    assert parse("a ball rolls while the camera pans left").camera.motion == "pan"
    assert parse("a red ball moevs left").motions[0].direction_image == (-1.0, 0.0)
