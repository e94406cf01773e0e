"""The perturbation-axis edit sentences (rules/axis_edits.py) and position words ("the left ball")."""

import pytest

import morphosim_gym as ms
from morphosim_gym.edit.editor import SceneEditor
from morphosim_gym.language.plan import EDIT_KINDS
from morphosim_gym.language.rules.axis_edits import AXIS_READERS
from morphosim_gym.language.rules.dispatch import WordTable
from tests.conftest import make_tiny_scene

# sentence -> (op, fields the plan must have)
SENTENCES = {
    "make the ball twice as big": ("scale", {"factor": 2.0}),
    "make the ball half as big": ("scale", {"factor": 0.5}),
    "make the ball 3 times bigger": ("scale", {"factor": 3.0}),
    "make the ball 1.5 times as big": ("scale", {"factor": 1.5}),
    "enlarge the cube by 2": ("scale", {"factor": 2.0}),
    "shrink the cube": ("scale", {"factor": 0.6}),
    "replace the ball with a cube": ("swap", {"category": "cube", "color": None}),
    "swap the ball for a green box": ("swap", {"category": "box"}),
    "turn the ball into a cube": ("swap", {"category": "cube"}),
    "add a blue cube next to the ball": ("insert", {"category": "cube", "relation": "next_to"}),
    "add a box behind the cube": ("insert", {"category": "box", "relation": "behind"}),
    "put a box in front of the ball": ("insert", {"category": "box", "relation": "in_front"}),
    "put a box between the camera and the ball": ("insert", {"category": "box", "relation": "occluding"}),
    "put a box between the ball and the camera": ("insert", {"category": "box", "relation": "occluding"}),
    "dim the lights": ("light", {"mode": "brightness", "factor": 0.6}),
    "make the lighting brighter": ("light", {"mode": "brightness", "factor": 1.4}),
    "make the light warmer": ("light", {"mode": "temperature", "amount": 0.6}),
    "make the light cooler": ("light", {"mode": "temperature", "amount": -0.6}),
    "light the scene from the left": ("light", {"mode": "direction", "direction_world": (-1.0, 0.0, 0.0)}),
    "make the sky a sunset": ("sky", {"name": "sunset"}),
    "change the sky to night": ("sky", {"name": "night"}),
    "make the ground checkered": ("texture", {"name": "checkered"}),
    "make the ball metallic": ("texture", {"name": "metallic"}),
    "give the cube a striped texture": ("texture", {"name": "striped"}),
    "move the scene to snow": ("setting", {"name": "snow"}),
    "set the scene on the beach": ("setting", {"name": "sand"}),
    "widen the field of view": ("view", {"factor": 1.3}),
    "widen the camera's field of view by 20 percent": ("view", {"factor": 1.2}),
    "narrow the field of view": ("view", {"factor": 0.75}),
    "raise the camera by 1 metre": ("view", {"amount": 1.0}),
    "lower the camera by 20 cm": ("view", {"amount": -0.2}),
    "move the camera up": ("view", {"amount": 0.5}),
    "add sensor noise": ("sensor", {"name": "noise", "amount": 0.5}),
    "add a lot of noise to the images": ("sensor", {"name": "noise", "amount": 0.9}),
    "blur the images": ("sensor", {"name": "blur"}),
    "make the images blurry": ("sensor", {"name": "blur"}),
    "compress the video": ("sensor", {"name": "jpeg"}),
    "delay the ball's motion by 1 second": ("delay", {"seconds": 1.0}),
    "delay the ball by 0.5 seconds": ("delay", {"seconds": 0.5}),
    "make the ball start 2 seconds later": ("delay", {"seconds": 2.0}),
    "make the ball start 1 second earlier": ("delay", {"seconds": -1.0}),
    "advance the cube's motion by 1 second": ("delay", {"seconds": -1.0}),
}


@pytest.fixture(scope="module")
def scene():
    return make_tiny_scene()


@pytest.mark.parametrize("text", list(SENTENCES))
def test_axis_sentence_parses_with_and_without_a_scene(scene, text):
    op, fields = SENTENCES[text]
    for kwargs in ({"scene": scene}, {}):
        plan = ms.parse(text, **kwargs)
        assert plan.mode == "edit" and [e.op for e in plan.edits] == [op], (text, kwargs)
        edit = plan.edits[0]
        for k, v in fields.items():
            got = getattr(edit, k)
            assert (got == pytest.approx(v) if isinstance(v, float) else got == v), (text, k, got)
        assert EDIT_KINDS[op].from_dict(edit.to_dict()) == edit


def test_every_new_kind_has_a_sentence_and_a_handler():
    from morphosim_gym.edit import editor

    assert {op for op, _ in SENTENCES.values()} == set(EDIT_KINDS) - {"recolor", "remove", "extract", "reverse",
                                                                       "redirect", "speed", "stop", "camera"}
    assert set(editor._HANDLERS) == set(EDIT_KINDS.values())
    assert isinstance(AXIS_READERS, WordTable)


@pytest.mark.parametrize("text, op", [("make the ball blue", "recolor"), ("add some blue to the ball", "recolor"),
                                      ("turn the ball red", "recolor"), ("zoom in", "camera"),
                                      ("move the ball to the left", "redirect"), ("make the ball move faster", "speed"),
                                      ("delete the cube", "remove"), ("drop the ball", "remove"),
                                      ("add a touch of red to the cube", "recolor"),
                                      ("move everything to the left", "redirect"), ("make the sky blue", None)])
def test_earlier_edit_sentences_keep_their_meaning(scene, text, op):
    if op is None:                                       # no sky object: still an error, not a sky swap
        with pytest.raises(ms.CommandError):
            ms.parse(text, scene=scene)
        return
    assert [e.op for e in ms.parse(text, scene=scene).edits] == [op]


def test_generation_sentences_are_not_axis_edits():
    plan = ms.parse("a red ball bounces from right to left")
    assert plan.mode == "generate"
    assert ms.parse("a ball rolls left; then make the ball twice as big").then[0].edits[0].op == "scale"


def test_bad_axis_sentences_say_what_is_missing(scene):
    for text, match in [("replace the ball with a", "with a cube"), ("delay the ball", "seconds"),
                        ("light the scene", "where the light comes from"),
                        ("make the light purple-ish", "how the light changes")]:
        with pytest.raises(ms.CommandError, match=match):
            ms.parse(text, scene=scene)


def test_position_words_pick_one_of_several_matches():
    two = SceneEditor().edit(make_tiny_scene(), "replace the cube with a ball")      # balls at x = -1 and x = +1
    left, right = 1, 2
    pick = lambda text: ms.parse(text, scene=two).edits[0].targets[0].object_ids  # noqa: E731
    assert pick("make the left ball blue") == (left,)
    assert pick("make the right ball blue") == (right,)
    assert pick("delete the rightmost ball") == (right,)
    assert pick("reverse the motion of the left ball") == (left,)
    assert pick("make the left red ball blue") == (left,)
    assert pick("make the ball blue") == (left, right)
    assert ms.parse("make the left ball blue", scene=two).edits[0].targets[0].text == "the left ball"
    assert ms.parse("move the ball to the left", scene=two).edits[0].direction_world == (-1.0, 0.0, 0.0)
