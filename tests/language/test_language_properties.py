"""Property tests: any text gives a valid, JSON-round-tripping Plan or a CommandError, nothing else."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import morphosim_gym as ms
from morphosim_gym.colors import CSS_COLORS
from morphosim_gym.language.lexicon import DIRECTION_WORDS, SIZE_WORDS, VERBS
from morphosim_gym.language.plan import Plan
from morphosim_gym.language.rules import EDIT_VERBS
from morphosim_gym.language.vocabulary import CATEGORIES, SETTING_WORDS



class _Obj:
    def __init__(self, i: int, name: str) -> None:
        self.id, self.name, self.category = i, name, name
        self.role = "background" if name in ("ground", "water") else "object"


class FakeScene:
    def __init__(self, *names: str) -> None:
        self.objects = [_Obj(i, n) for i, n in enumerate(names)]

WORDS = sorted(
    set(CATEGORIES) | {c.plural for c in CATEGORIES.values()} | set(list(CSS_COLORS)[::7]) | set(list(VERBS)[::5])
    | set(DIRECTION_WORDS) | set(SIZE_WORDS) | set(list(EDIT_VERBS)) | set(list(SETTING_WORDS)[::3])
    | {"a", "an", "the", "two", "three", "0", "-2", "1.5", "100", "twice", "half", "as", "fast", "slowly", "quickly",
       "from", "to", "towards", "away", "camera", "while", "then", "and", ",", ".", ";", "it", "its", "them", "of",
       "color", "colour", "clockwise", "around", "circle", "zigzag", "light", "dark", "pale", "bright", "more",
       "less", "redder", "darker", "times", "percent", "%", "'s", "not", "all", "everything", "scene", "please",
       "should", "be", "is", "now", "left", "right", "up", "down", "north", "in", "place", "back", "forth", "x",
       "qwzx", "blorp", "very", "at", "crawl", "speed", "slow", "top", "bottom", "side", "?", "!", "'"}
)

token_soup = st.lists(st.sampled_from(WORDS), min_size=0, max_size=14).map(" ".join)
scenes = st.one_of(st.none(), st.lists(st.sampled_from(["ground", "water", "ball", "bus", "car", "fish", "seaweed",
                                                        "dog", "tree", "cube", "plate"]),
                                       min_size=1, max_size=5, unique=True).map(lambda xs: FakeScene(*xs)))

SETTINGS = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def check(text: str, scene=None, require_scene: bool = False) -> None:
    try:
        plan = ms.parse(text, scene, require_scene=require_scene)
    except ms.CommandError as exc:
        assert str(exc)  # a message for people
        return
    assert isinstance(plan, Plan) and plan.mode in ("generate", "edit")
    assert Plan.from_dict(plan.to_dict()) == plan
    assert Plan.from_json(plan.to_json()) == plan
    if scene is not None and plan.mode == "edit":
        names = {o.name for o in scene.objects}
        for e in plan.all_edits():
            for t in e.targets:
                assert set(t.objects) <= names


@SETTINGS
@given(st.text(max_size=80))
def test_arbitrary_text(text):
    check(text)


@SETTINGS
@given(token_soup, scenes, st.booleans())
def test_adversarial_word_soup(text, scene, require_scene):
    check(text, scene, require_scene)


@SETTINGS
@given(st.sampled_from(["a red ball bounces from right to left", "make the bus yellow", "delete the ball",
                        "a dog runs to the tree while the camera orbits; then make it blue"]),
       st.lists(st.sampled_from(WORDS), max_size=4), st.integers(0, 12))
def test_mutated_good_commands(base, extra, at):
    words = base.split()
    at = min(at, len(words))
    check(" ".join(words[:at] + extra + words[at:]))


@SETTINGS
@given(st.text(alphabet=st.characters(codec="utf-8"), max_size=40), st.sampled_from(["", " ", "\n", ";", "then"]))
def test_unicode_and_separators(text, sep):
    check(sep + text + sep + "make it red")
