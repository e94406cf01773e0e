"""Relations and actions the generator honours (two-stage motions, towards each other, falling) and the
ones the parser refuses by name."""

import numpy as np
import pytest

import morphosim_gym as ms

TINY = ms.GenerationConfig(width=48, height=48, num_frames=9, detail=0.2)


@pytest.fixture(scope="module")
def sim():
    return ms.MorphoSim(generation=TINY, reconstruction="oracle")


def _track(scene, name):
    oid = scene.object(name).id
    return np.array([scene.object_center(oid, t) for t in np.linspace(0, scene.duration, scene.num_frames)])


def test_then_stops_is_a_second_stage(sim):
    """'the ball rolls left then stops': it rolls left over the first half, then stays (was: generate failed)."""
    track = _track(sim.generate("the ball rolls left then stops", seed=0), "ball")
    assert track[4, 0] < track[0, 0] - 0.05
    assert np.allclose(track[4:], track[4], atol=1e-6)
    clip = sim.generate_clip("the ball rolls left then stops", seed=0)   # the clip shows the same
    assert clip.num_frames == 9


def test_then_reverses_and_speeds_up(sim):
    back = _track(sim.generate("the ball rolls left then reverses", seed=0), "ball")
    assert back[4, 0] < back[0, 0] - 0.05 and abs(back[-1, 0] - back[0, 0]) < 1e-6
    fast = _track(sim.generate("the ball rolls left then speeds up", seed=0), "ball")
    steps = np.abs(np.diff(fast[:, 0]))
    assert steps[4] > 1.5 * steps[0]


def test_other_follow_ups_stay_edits(sim):
    scene = sim.generate("a ball rolls left then disappears", seed=0)
    assert "ball" not in scene.object_names and scene.history == ("remove the ball",)


def test_two_stages_at_most_and_only_for_a_moving_object():
    with pytest.raises(ms.CommandError, match="at most two stages"):
        ms.parse("a ball rolls left then stops then reverses")
    with pytest.raises(ms.CommandError, match="does not move before"):
        ms.parse("a cat sits then stops")


def test_two_cars_drive_towards_each_other_and_meet(sim):
    plan = ms.parse("two cars drive towards each other")
    assert [o.name for o in plan.objects] == ["car", "car_2"]
    assert [(m.direction_world, m.end) for m in plan.motions] == [((1.0, 0.0, 0.0), "car_2"), ((-1.0, 0.0, 0.0), "car")]
    scene = sim.generate("two cars drive towards each other", seed=0)
    a, b = _track(scene, "car"), _track(scene, "car_2")
    gap = np.abs(a[:, 0] - b[:, 0])
    assert gap[-1] < 0.5 * gap[0]                                   # they close in on each other
    assert abs(a[0, 1] - b[0, 1]) < 0.5                             # in one lane, not passing in parallel
    ga = scene.gaussians.means[scene.gaussians.object_ids == scene.object("car").id]
    gb = scene.gaussians.means[scene.gaussians.object_ids == scene.object("car_2").id]
    end_a = ga[:, 0].max() + (a[-1, 0] - a[0, 0])
    end_b = gb[:, 0].min() + (b[-1, 0] - b[0, 0])
    assert end_a <= end_b + 0.05                                    # they meet without driving through each other


@pytest.mark.parametrize("text", ["three dogs run towards each other", "two cars drive left towards each other"])
def test_towards_each_other_that_cannot_be_honoured_is_refused(text):
    with pytest.raises(ms.CommandError, match="each other"):
        ms.parse(text)


def test_a_bottle_falls_onto_the_table_without_sinking(sim):
    scene = sim.generate("a green bottle falls off the table", seed=0)
    oid = scene.object("bottle").id
    lows = [scene.at(t).means[scene.gaussians.object_ids == oid][:, 2].min()
            for t in np.linspace(0, scene.duration, scene.num_frames)]
    assert lows[0] > 0.1                                            # it starts in the air
    assert min(lows) > -0.02                                        # and never sinks into the surface
    assert abs(lows[-1] - min(lows)) < 1e-6 and np.all(np.diff(lows) <= 1e-9)    # falls, then rests


@pytest.mark.parametrize("text, words", [("a robot arm picks up a red cup", "picks up a red cup"),
                                         ("a quadruped robot climbs the stairs", "climbs the stairs"),
                                         ("a man throws a ball to the left", "throws a ball")])
def test_actions_on_other_objects_are_refused_by_name(text, words):
    with pytest.raises(ms.CommandError, match=f"Could not honour '{words}'"):
        ms.parse(text)


def test_intransitive_uses_stay_motions():
    assert ms.parse("a cat climbs up").motions[0].direction_world == (0.0, 0.0, 1.0)
    assert ms.parse("an apple drops").motions[0].direction_world == (0.0, 0.0, -1.0)
