"""Plan types: validation with clear errors, JSON both ways, and the frame conventions."""

import json
import math

import pytest

import morphosim_gym as ms
from morphosim_gym.language.plan import (EDIT_KEYS, EDIT_KINDS, EDIT_OPS, CameraOp, CameraSpec, ColorSpec, EditOp,
                                         MotionSpec, ObjectSpec, Plan, RemoveOp, SpeedOp, Target, edit_op,
                                         world_to_image)


def test_json_round_trip_of_a_compound_plan():
    plan = ms.parse("a red cube moves to the plate while the camera circles the table; "
                    "then make the cube blue and reverse its motion")
    d = plan.to_dict()
    json.dumps(d)  # plain JSON types only
    again = Plan.from_dict(json.loads(plan.to_json()))
    assert again == plan
    assert Plan.from_json(plan.to_json(indent=None)).to_dict() == d


@pytest.mark.parametrize("text", ["make the bus yellow and make the car darker", "make it redder",
                                  "a duck swims anticlockwise around the rock", "pan the camera to the left",
                                  "two small green apples roll towards the camera at a crawl"])
def test_round_trip_various(text, scene_factory):
    scene = scene_factory("ground", "ball") if "it" in text.split() else None
    plan = ms.parse(text, scene)
    assert Plan.from_dict(plan.to_dict()) == plan


def test_direction_conventions():
    assert world_to_image((1.0, 0.0, 0.0)) == ((1.0, 0.0), 0.0)      # right
    assert world_to_image((0.0, 0.0, 1.0)) == ((0.0, -1.0), 0.0)     # upwards: image y points down
    assert world_to_image((0.0, -1.0, 0.0)) == ((0.0, 0.0), -1.0)    # towards the camera: along the view axis
    m = ms.parse("a bird flies upwards").motions[0]
    assert m.direction_world == (0.0, 0.0, 1.0) and m.direction_image == (0.0, -1.0)
    m = ms.parse("a dog runs towards the camera").motions[0]
    assert m.direction_world == (0.0, -1.0, 0.0) and m.direction_image == (0.0, 0.0) and m.direction_depth == -1.0
    m = ms.parse("a cube slides to the right and away from the camera").motions[0]
    assert m.direction_image == (1.0, 0.0) and math.isclose(m.direction_depth, 1 / math.sqrt(2), abs_tol=1e-6)
    assert ms.parse("a car drives north").motions[0].direction_world == (0.0, 1.0, 0.0)
    assert ms.parse("a car drives west").motions[0].direction_world == (-1.0, 0.0, 0.0)


def test_from_dict_fills_defaults_and_derived_fields():
    plan = Plan.from_dict({"mode": "generate", "objects": [{"noun": "ball", "category": "ball",
                                                            "color": {"name": "navy"}}],
                           "motions": [{"target": "ball", "direction_world": [0, 0, 2]}]})
    assert plan.objects[0].name == "ball" and plan.objects[0].color.rgb == pytest.approx((0, 0, 0.501961))
    assert plan.motions[0].direction_world == (0.0, 0.0, 1.0)
    assert plan.camera == CameraSpec() and plan.setting == "ground"


@pytest.mark.parametrize("bad, key", [
    ({"mode": "simulate"}, "plan.mode"),
    ({"mode": "generate", "objects": [{"noun": "x", "category": "giraffe"}]}, "plan.objects[0].category"),
    ({"mode": "generate", "objects": [{"noun": "ball", "category": "ball", "count": 0}]}, "plan.objects[0].count"),
    ({"mode": "generate", "objects": [{"noun": "ball", "category": "ball"}], "motions": [{"target": "ball",
                                                                                         "path": "teleport"}]},
     "plan.motions[0].path"),
    ({"mode": "generate", "objects": [{"noun": "ball", "category": "ball"}],
      "motions": [{"target": "ball", "end": "plate"}]}, "plate"),
    ({"mode": "generate", "objects": [{"noun": "ball", "category": "ball"}], "colour": "red"}, "plan.colour"),
    ({"mode": "edit", "edits": [{"op": "speed", "targets": ["ball"], "factor": 0}]}, "plan.edits[0].factor"),
    ({"mode": "edit", "edits": [{"op": "speed", "targets": ["ball"], "factor": -2}]}, "plan.edits[0].factor"),
    ({"mode": "edit", "edits": [{"op": "recolor", "targets": ["ball"]}]}, "plan.edits[0].mode"),
    ({"mode": "edit", "edits": [{"op": "recolor", "targets": ["ball"], "mode": "assign",
                                 "color": {"name": "blurple"}}]}, "plan.edits[0].color.name"),
    ({"mode": "edit", "edits": []}, "plan.edits"),
    ({"mode": "generate", "objects": [{"noun": "ball", "category": "ball"}],
      "camera": {"motion": "pan", "direction": "clockwise"}}, "plan.camera.direction"),
])
def test_invalid_plans_name_the_key(bad, key):
    with pytest.raises(ms.CommandError) as e:
        Plan.from_dict(bad)
    assert key in str(e.value)
    assert isinstance(e.value, ValueError)


def test_dataclasses_are_frozen_and_validated():
    with pytest.raises(ms.CommandError):
        ColorSpec("red", (1.5, 0, 0))
    with pytest.raises(ms.CommandError):
        MotionSpec("ball", direction_world=(0, 0, 0))
    with pytest.raises(ms.CommandError):
        CameraOp(targets=(Target("it", "ball"),), camera=CameraSpec("orbit"))
    with pytest.raises(ms.CommandError):
        edit_op("camera", targets=(Target("it", "ball"),), camera=CameraSpec("orbit"))
    o = ObjectSpec("ball", "ball", "ball")
    with pytest.raises(Exception):
        o.count = 3  # type: ignore[misc]


def test_recolor_parameters_for_the_editor():
    e = ms.parse("make the ball yellow").edits[0]
    assert (e.mode, e.color.rgb) == ("assign", (1.0, 1.0, 0.0))
    e = ms.parse("make the ball redder").edits[0]
    assert e.mode == "additive" and e.delta == (0.3, 0.0, 0.0)
    e = ms.parse("make the ball less blue").edits[0]
    assert e.mode == "additive" and e.delta == (0.0, 0.0, -0.3)
    e = ms.parse("make the ball darker").edits[0]
    assert e.mode == "multiplicative" and e.factor_rgb == (0.6, 0.6, 0.6)
    e = ms.parse("make the ball half as bright").edits[0]
    assert e.factor_rgb == (0.5, 0.5, 0.5)


def test_one_edit_kind_per_op_name():
    assert tuple(EDIT_KINDS) == EDIT_OPS
    for name, kind in EDIT_KINDS.items():
        assert kind.op == name and issubclass(kind, EditOp)
    with pytest.raises(ms.CommandError, match="EditOp is the base"):
        EditOp(targets=(Target("ball", "ball"),))
    with pytest.raises(ms.CommandError, match="edit.op"):
        edit_op("teleport", targets=(Target("ball", "ball"),))


def test_an_edit_kind_checks_only_its_own_fields():
    t = (Target("ball", "ball"),)
    assert isinstance(edit_op("remove", targets=t, path=None, factor=None), RemoveOp)
    with pytest.raises(ms.CommandError, match="edit.path to be null for op 'remove'"):
        edit_op("remove", targets=t, path="circle")
    with pytest.raises(ms.CommandError, match=r"plan.edits\[0\].mode to be null for op .speed."):
        Plan.from_dict({"mode": "edit", "edits": [{"op": "speed", "targets": ["ball"], "factor": 2,
                                                    "mode": "assign"}]})
    with pytest.raises(ms.CommandError, match="exactly one of factor and speed"):
        SpeedOp(targets=t)
    assert not hasattr(RemoveOp(targets=t), "factor")


def test_every_edit_kind_writes_the_same_dict_layout():
    plan = ms.parse("make the ball blue and reverse its motion, then move it left and make it twice as fast; "
                    "then pan left; then delete the ball")
    for e in plan.all_edits():
        d = e.to_dict()
        assert tuple(d) == EDIT_KEYS and d["op"] == e.op
        assert EditOp.from_dict(d) == e
    assert isinstance(plan.then[-2].edits[0], CameraOp)
