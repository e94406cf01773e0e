"""The rule-based parser: the paper's commands, vocabulary breadth, edits, scenes, and bad input."""

import pytest

import morphosim_gym as ms
from morphosim_gym.colors import COMMON_COLORS, CSS_COLORS, apply_modifier, color_rgb
from morphosim_gym.language.lexicon import SPEED_PHRASES
from morphosim_gym.language.vocabulary import CATEGORIES


def test_paper_compound_example():
    plan = ms.parse("a red cube moves to the plate while the camera circles the table; "
                    "then make the cube blue and reverse its motion")
    assert plan.mode == "generate" and plan.setting == "table"
    assert [(o.name, o.category, o.color.name if o.color else None) for o in plan.objects] == [
        ("cube", "cube", "red"), ("plate", "plate", None)]
    (m,) = plan.motions
    assert (m.target, m.path, m.end, m.direction_world) == ("cube", "straight", "plate", None)
    assert plan.camera.motion == "orbit"
    (edit,) = plan.then
    assert [e.op for e in edit.edits] == ["recolor", "reverse"]
    assert edit.edits[0].color.name == "blue" and edit.edits[1].targets[0].objects == ("cube",)


@pytest.mark.parametrize("text, category, direction", [
    ("The fish swims through the crystal-clear waters from right to left", "fish", (-1.0, 0.0, 0.0)),
    ("The bus is moving from right to left", "bus", (-1.0, 0.0, 0.0)),
    ("A serene boat glides gracefully through tranquil waters from left to right", "boat", (1.0, 0.0, 0.0)),
    ("A car is moving from right to left through a serene sunlit landscape", "car", (-1.0, 0.0, 0.0)),
    ("A small, vibrant red rubber ball is bouncing from right to left", "ball", (-1.0, 0.0, 0.0)),
    ("A sleek black motorcycle is gliding effortlessly from right to left", "motorcycle", (-1.0, 0.0, 0.0)),
])
def test_paper_generate_captions(text, category, direction):
    plan = ms.parse(text)
    assert plan.mode == "generate" and plan.objects[0].category == category
    assert plan.motions[0].direction_world == direction


@pytest.mark.parametrize("text, op, targets", [
    ("Make the color of the fish and seaweed black.", "recolor", ["fish", "seaweed"]),
    ("Make the bus yellow.", "recolor", ["bus"]), ("Extract the boat.", "extract", ["boat"]),
    ("Extract the car.", "extract", ["car"]), ("Delete the ball.", "remove", ["ball"]),
    ("Delete the motorcycle.", "remove", ["motorcycle"]), ("Change the ball's color to blue", "recolor", ["ball"]),
])
def test_paper_edit_captions(text, op, targets):
    plan = ms.parse(text)
    assert plan.mode == "edit" and [e.op for e in plan.edits] == [op]
    assert [t.noun for t in plan.edits[0].targets] == targets


@pytest.mark.parametrize("name", sorted(CSS_COLORS))
def test_every_css_colour_name(name):
    """A bare name is the everyday colour where `COMMON_COLORS` has one, else the CSS value; "css:<name>"
    is always the exact CSS value."""
    want = COMMON_COLORS.get(name, CSS_COLORS[name])
    plan = ms.parse(f"make the ball {name}")
    assert plan.edits[0].color.rgb == want
    plan = ms.parse(f"a {name} cube slides to the left")
    assert plan.objects[0].color.rgb == want
    plan = ms.parse(f"make the ball css:{name}")
    assert plan.edits[0].color.rgb == CSS_COLORS[name] and plan.edits[0].color.name == f"css:{name}"
    plan = ms.parse(f"a css:{name} cube slides to the left")
    assert plan.objects[0].color.rgb == CSS_COLORS[name]


def test_common_colour_names_look_like_their_names():
    """Brown is a brown (red > green > blue, not CSS's dark red), purple has more blue than red, green is not
    CSS's dark green, and a multi-word CSS name can be asked for exactly."""
    r, g, b = color_rgb("brown")
    assert r > g > b and g > 0.3 * r
    assert color_rgb("css:brown") == CSS_COLORS["brown"] == (0.647059, 0.164706, 0.164706)
    r, g, b = color_rgb("purple")
    assert b > r > g
    assert color_rgb("green")[1] > 0.6
    assert color_rgb("beige") != CSS_COLORS["beige"] and min(color_rgb("beige")) < 0.7
    assert ms.parse("make the ball css: dark olive green").edits[0].color.rgb == CSS_COLORS["darkolivegreen"]
    assert ms.parse("a brown dog runs left").objects[0].color.rgb == COMMON_COLORS["brown"]


def test_colour_modifiers_are_deterministic_and_in_range():
    assert color_rgb("light red") == apply_modifier(CSS_COLORS["red"], "light") == (1.0, 0.5, 0.5)
    assert color_rgb("dark red") == CSS_COLORS["darkred"]  # a CSS compound wins
    assert color_rgb("pale red") == (1.0, 0.7, 0.7)
    assert color_rgb("bright navy") == (0.0, 0.0, 1.0)
    for name, rgb in CSS_COLORS.items():
        for mod in ("light", "dark", "pale", "bright"):
            assert all(0.0 <= c <= 1.0 for c in apply_modifier(rgb, mod))
    assert ms.parse("a light blue boat sails left").objects[0].color.name == "lightblue"
    assert ms.parse("a pale red mug slides left").objects[0].color.name == "pale red"


def test_speed_table_is_ordered():
    def speed(t):
        return ms.parse(f"a car drives to the left {t}").motions[0].speed
    assert speed("at a crawl") < speed("very slowly") < speed("slowly") < speed("") < speed("quickly") \
        < speed("very fast")
    assert all(v > 0 for v in SPEED_PHRASES.values())


@pytest.mark.parametrize("text, vec", [
    ("from left to right", (1.0, 0.0, 0.0)), ("right to left", (-1.0, 0.0, 0.0)), ("upwards", (0.0, 0.0, 1.0)),
    ("downwards", (0.0, 0.0, -1.0)), ("towards the camera", (0.0, -1.0, 0.0)), ("away from the camera", (0.0, 1.0, 0.0)),
    ("north", (0.0, 1.0, 0.0)), ("south", (0.0, -1.0, 0.0)), ("eastward", (1.0, 0.0, 0.0)), ("westwards", (-1.0, 0.0, 0.0)),
    ("to the left", (-1.0, 0.0, 0.0)), ("from the left", (1.0, 0.0, 0.0)),
])
def test_directions(text, vec):
    assert ms.parse(f"a ball moves {text}").motions[0].direction_world == vec


def test_paths_counts_sizes_landmarks():
    m = ms.parse("a dog runs clockwise around the tree").motions[0]
    assert (m.path, m.clockwise, m.around) == ("circle", True, "tree")
    assert ms.parse("a duck swims counterclockwise in a circle").motions[0].clockwise is False
    assert ms.parse("a car zigzags to the left").motions[0].path == "zigzag"
    assert ms.parse("a cat sits still").motions[0].path == "stop"
    assert ms.parse("a cat paces back and forth").motions[0].path == "oscillate"
    plan = ms.parse("two big red balls bounce to the right")
    o = plan.objects[0]
    assert (o.count, o.size, o.scale, o.color.name) == (2, "big", 1.5, "red")
    assert ms.parse("a herd of elephants walks left").objects[0].count == 3
    plan = ms.parse("a mug moves from the box to the bowl")
    assert [o.name for o in plan.objects] == ["mug", "box", "bowl"]
    assert (plan.motions[0].start, plan.motions[0].end) == ("box", "bowl")
    assert plan.motion_of("box") is None  # landmarks are static objects


def test_table_is_a_setting_as_a_place_and_an_object_as_a_thing():
    assert [o.name for o in ms.parse("a cube slides across the table").objects] == ["cube"]
    assert ms.parse("a cube slides across the table").setting == "table"
    assert [o.name for o in ms.parse("a cat jumps onto the table").objects] == ["cat", "table"]
    assert [o.name for o in ms.parse("a red table slides to the left").objects] == ["table"]


def test_setting_inference():
    assert ms.parse("a fish swims left").setting == "water"
    assert ms.parse("a fish swims left").setting_source == "inferred"
    assert ms.parse("a ball rolls left").setting == "ground"
    assert ms.parse("a car drives left on the beach").setting_source == "text"


def test_camera():
    cam = ms.parse("a dog runs left while the camera slowly pans right").camera
    assert (cam.motion, cam.direction, cam.speed) == ("pan", "right", 0.5)
    assert ms.parse("a ball rolls left as the camera zooms in").camera.direction == "in"
    cam = ms.parse("a cat walks left and the camera circles the cat").camera
    assert (cam.motion, cam.target) == ("orbit", "cat")
    assert ms.parse("a boat sails with a static camera").camera.motion == "fixed"


def test_edit_ops():
    def op(t, scene=None):
        return ms.parse(t, scene).edits
    assert op("speed up the car")[0].factor == 2.0
    assert op("make the car half as fast")[0].factor == 0.5
    assert op("make the car move slowly")[0].speed == 0.5
    assert op("make the dog three times slower")[0].factor == pytest.approx(1 / 3, abs=1e-6)
    e = op("move the ball towards the camera")[0]
    assert (e.op, e.direction_world, e.direction_image) == ("redirect", (0.0, -1.0, 0.0), (0.0, 0.0))
    assert op("make the ball circle the tree")[0].around == "tree"
    assert [e.op for e in op("stop the dog and make the cat red")] == ["stop", "recolor"]
    e = op("orbit the camera clockwise slowly")[0]
    assert (e.op, e.camera.motion, e.camera.direction, e.camera.speed) == ("camera", "orbit", "clockwise", 0.5)


def test_pronouns_resolve_to_the_last_named_object():
    plan = ms.parse("a dog runs to the left; then make it red")
    assert plan.then[0].edits[0].targets[0].objects == ("dog",)
    plan = ms.parse("a red cube moves to the plate. make the cube blue and reverse its motion")
    assert plan.then[0].edits[1].targets[0].objects == ("cube",)
    plan = ms.parse("make the bus yellow and reverse its motion")
    assert plan.edits[1].targets[0].noun == "bus"


def test_scene_resolution(scene_factory, minilm):
    scene = scene_factory("road", "bus", "person", "tree")
    t = ms.parse("make the bus yellow", scene).edits[0].targets[0]
    assert (t.objects, t.object_ids, t.category) == (("bus",), (1,), "bus")
    assert ms.parse("make the vehicle blue", scene).edits[0].targets[0].objects == ("bus",)
    assert ms.parse("delete everything", scene).edits[0].targets[0].objects == ("bus", "person", "tree")
    assert ms.parse("make the road white", scene).edits[0].targets[0].objects == ("road",)
    fish = scene_factory("water", "fish", "seaweed")
    assert [t.objects for t in ms.parse("Make the color of the fish and seaweed black.", fish).edits[0].targets] == [
        ("fish",), ("seaweed",)]
    with pytest.raises(ms.CommandError, match="bus"):  # the message lists the scene's objects
        ms.parse("delete the horse", scene)
    with pytest.raises(ms.CommandError, match="name one"):
        ms.parse("make it blue", scene)
    one = scene_factory("ground", "ball")
    assert ms.parse("make it blue", one).edits[0].targets[0].objects == ("ball",)


def test_edit_without_scene():
    plan = ms.parse("make the bus yellow")  # inspectable without a scene
    assert plan.edits[0].targets[0].objects == () and plan.edits[0].targets[0].category == "bus"
    with pytest.raises(ms.CommandError, match="no scene"):
        ms.parse("make the bus yellow", require_scene=True)
    # a compound command's own generate part is the scene
    assert ms.parse("a bus drives left; then make the bus yellow", require_scene=True).then


@pytest.mark.parametrize("text, words", [
    ("", "empty"), ("   \t ", "empty"), ("asdf qwer zxcv", "understand"),
    ("make the bus blurple", "blurple"), ("a ball moves from left to left", "same place"),
    ("a ball rolls leftward to the right", "contradict"), ("a rock rises downwards", "contradict"),
    ("make it blue", "refers to"), ("reverse its motion", "refers to"),
    ("make the car zero times as fast", "> 0"), ("make the ball 100% slower", "> 0"),
    ("a hundred balls bounce", "between 1 and"), ("make the ball 0 times as big", "> 0"), ("delete", "what to edit"),
    ("x" * 5000, "at most"),
])
def test_bad_input_raises_command_error(text, words):
    with pytest.raises(ms.CommandError) as e:
        ms.parse(text)
    assert isinstance(e.value, ValueError)
    assert words in str(e.value)


def test_error_messages_say_what_would_work():
    with pytest.raises(ms.CommandError) as e:
        ms.parse("make the bus blurple")
    assert "CSS" in str(e.value) and "make the bus yellow" in str(e.value)
    with pytest.raises(ms.CommandError) as e:
        ms.parse("asdf qwer zxcv")
    assert "a red ball bounces" in str(e.value)


def test_non_string_input():
    with pytest.raises(ms.CommandError):
        ms.parse(None)  # type: ignore[arg-type]


def test_vocabulary_categories_all_parse():
    for name, cat in CATEGORIES.items():
        plan = ms.parse(f"a {name} moves to the left")
        assert plan.objects[0].category == name, name
        if cat.plural != name:
            assert ms.parse(f"two {cat.plural} move to the left").objects[0].count == 2


@pytest.mark.parametrize("text, keep", [("delete everything except the bus", "bus"),
                                        ("remove everything but the red car", "red car")])
def test_delete_everything_except_points_to_extract(text, keep):
    with pytest.raises(ms.CommandError, match=f"say 'extract the {keep}'"):
        ms.parse(text)
