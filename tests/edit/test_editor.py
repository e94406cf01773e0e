"""The scene editor on generated scenes: what edits change, what they leave alone, history, errors."""

import cv2
import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.metrics import delta_e, mean_lab, psnr, rgb_to_lab

SMALL = ms.GenerationConfig(width=96, height=96, num_frames=25, detail=0.6)


@pytest.fixture(scope="module")
def sim():
    return ms.MorphoSim(generation=SMALL, reconstruction="oracle")


@pytest.fixture(scope="module")
def bus(sim):
    return sim.generate("The bus is moving from right to left", seed=0)


def _views(scene):
    cam = scene.camera
    centre = scene.centre()
    return [cam, cam.orbit(20.0, centre), cam.orbit(-30.0, centre)]


def test_recolor_hits_the_colour_and_nothing_else(sim, bus):
    blue = sim.edit(bus, "make the bus blue")
    target = rgb_to_lab(np.array(ms.parse("make the bus blue").edits[0].color.rgb))
    for cam in _views(bus):
        for t in (0.0, bus.duration / 2, bus.duration):
            before, after = ms.render(bus, cam, t), ms.render(blue, cam, t)
            mask = before.instance == bus.object("bus").id
            assert mask.sum() > 20
            assert delta_e(mean_lab(after.rgb, mask), target) < 15
            outside = ~cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
            assert psnr(before.rgb, after.rgb, outside) >= 45


def test_edit_never_mutates_and_undo_is_exact(sim, bus):
    colors = bus.gaussians.colors.copy()
    edited = sim.edit(bus, "make the bus yellow and reverse its motion")
    np.testing.assert_array_equal(bus.gaussians.colors, colors)
    assert edited.history == ("make the bus yellow and reverse its motion",)
    assert edited.undo() is bus
    assert edited.undo().content_hash() == bus.content_hash()
    twice = sim.edit(edited, "make the road darker")
    assert twice.history[-1] == "make the road darker" and twice.undo() is edited


def test_remove_and_extract(sim, bus):
    gone = sim.edit(bus, "delete the bus")
    assert "bus" not in gone.object_names
    for t in (0.0, bus.duration):
        assert not np.any(ms.render(gone, bus.camera, t).instance == bus.object("bus").id)
    only = sim.edit(bus, "extract the bus")
    ids = set(np.unique(ms.render(only, bus.camera, 1.0).instance).tolist())
    assert ids == {-1, bus.object("bus").id}


def _centroids(scene, name):
    oid = scene.object(name).id
    out = []
    for i in range(scene.num_frames):
        inst = ms.render(scene, scene.camera, i / scene.fps).instance
        ys, xs = np.nonzero(inst == oid)
        out.append([xs.mean(), ys.mean()])
    return np.array(out)


def test_reverse_traverses_the_path_backwards(sim, bus):
    rev = sim.edit(bus, "reverse the motion of the bus")
    a, b = _centroids(bus, "bus"), _centroids(rev, "bus")
    err = np.linalg.norm(a[::-1] - b, axis=1).mean()
    assert err < 0.02 * bus.camera.width


def test_redirect_and_speed(sim, bus):
    right = sim.edit(bus, "make the bus move to the right")
    c = _centroids(right, "bus")
    d = c[-1] - c[0]
    assert d[0] / np.linalg.norm(d) > 0.9
    base = _centroids(bus, "bus")
    fast = _centroids(sim.edit(bus, "make the bus twice as fast"), "bus")
    half = len(base) // 2
    # twice as fast: by mid-clip it has covered what it used to cover by the end
    assert np.linalg.norm(fast[half] - base[-1]) < 0.03 * bus.camera.width
    still = _centroids(sim.edit(bus, "stop the bus"), "bus")
    assert np.ptp(still, axis=0).max() < 1.0


def test_redirect_to_where_it_already_goes_says_so(sim, bus):
    """The bus goes left: "move the bus to the left" would change nothing, and says so instead of a silent no-op."""
    with pytest.raises(ms.EditError, match="Nothing to change: bus already moves that way"):
        sim.edit(bus, "move the bus to the left")
    right = sim.edit(bus, "move the bus to the right")
    with pytest.raises(ms.EditError, match="already moves that way"):
        sim.edit(right, "move the bus to the right")


def test_selection_by_meaning(sim, bus):
    assert sim.edit(bus, "make the vehicle yellow").object("bus").color == pytest.approx((1.0, 1.0, 0.0))


def test_target_that_matches_nothing_lists_the_objects(sim, bus):
    with pytest.raises(ms.EditError, match="road.*bus|bus.*road"):
        sim.edit(bus, "delete the giraffe")


def test_ambiguous_target_asks_which_one(sim):
    herd = sim.generate("a sheep and a cow stand on the grass", seed=1)
    with pytest.raises(ms.EditError, match="sheep or cow|cow or sheep"):
        sim.edit(herd, "make the animal red")
    both = sim.edit(herd, "make all the animals red")
    assert both.object("sheep").color == both.object("cow").color == pytest.approx((1.0, 0.0, 0.0))


@pytest.mark.parametrize("text", ["make the bus blurple", "make the bus zero times as fast"])
def test_bad_commands_are_command_errors(sim, bus, text):
    with pytest.raises(ms.CommandError):
        sim.edit(bus, text)


def test_reversing_a_still_object_is_an_edit_error(sim, bus):
    stopped = sim.edit(bus, "stop the bus")
    with pytest.raises(ms.EditError, match="does not move"):
        sim.edit(stopped, "reverse the bus")


def test_compound_prompt_applies_follow_up_edits(sim):
    scene = sim.generate("a red cube moves to the plate; then make the cube blue", seed=0)
    assert scene.object("cube").color == pytest.approx((0.0, 0.0, 1.0))
    assert scene.history == ("make the cube blue",)


def test_colour_picks_among_numbered_objects_of_one_noun(sim):
    """'the blue ball' among 'ball' (red) and 'ball_2' (blue): the colour decides; no colour keeps the first."""
    scene = sim.generate("a red ball moves from left to right next to a blue ball and a red cube", seed=3)
    names = {o.name: o.id for o in scene.objects}
    assert {"ball", "ball_2", "cube"} <= set(names)
    assert [o.name for o in sim.edit(scene, "delete the blue ball").objects if o.category == "ball"] == ["ball"]
    assert [o.name for o in sim.edit(scene, "delete the red ball").objects if o.category == "ball"] == ["ball_2"]
    green = sim.edit(scene, "make the blue ball green")
    assert green.object("ball_2").color != scene.object("ball_2").color
    assert green.object("ball").color == scene.object("ball").color
    assert [o.name for o in sim.edit(scene, "delete the ball").objects if o.category == "ball"] == ["ball_2"]


def test_the_editor_has_a_handler_for_every_edit_kind():
    from morphosim_gym.edit import editor
    from morphosim_gym.language.plan import EDIT_KINDS

    assert set(editor._HANDLERS) == set(EDIT_KINDS.values())
