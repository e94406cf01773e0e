"""A long viewer session keeps a bounded history: at most `max_undo` undo steps (edits and
replaced scenes together) and `max_log` log entries, and the scenes beyond them are freed."""

import gc
import weakref

import pytest

from morphosim_gym.viewer import ViewerSession

from .conftest import BUS


def _alive(refs):
    gc.collect()
    return sum(r() is not None for r in refs)


def test_many_edits_and_scenes_keep_memory_bounded(small_sim, ball_scene):
    session = ViewerSession(ball_scene, sim=small_sim, max_undo=4, max_log=10)
    refs = [weakref.ref(ball_scene)]
    commands = ["make the ball blue", "make the ball red"] * 6 + [BUS, "make the bus yellow"] * 3
    for text in commands:
        entry = session.submit(text)
        assert entry.ok, entry.message
        refs.append(weakref.ref(session.scene))
        assert session.undo_depth <= 4
    assert len(session.log) == 10 and session.log[-1].text == "make the bus yellow"
    del entry
    # the current scene, the 4 it can go back to, and the test's own ball_scene fixture at most
    assert _alive(refs) <= 4 + 1 + 1
    # the steps kept still undo, newest first; then there is nothing left to undo
    for _ in range(4):
        assert session.undo().ok
    assert not session.can_undo and not session.undo().ok


def test_undo_steps_span_edits_and_replaced_scenes(small_sim, ball_scene):
    session = ViewerSession(ball_scene, sim=small_sim, max_undo=3)
    session.submit("make the ball blue")
    session.submit(BUS)                       # replaces the blue ball (1 step + its 1 edit)
    session.submit("make the bus yellow")
    assert session.undo_depth == 3
    session.submit("make the bus red")        # 2 edits of the bus + the ball itself; its edit is forgotten
    assert session.undo_depth == 3
    assert [session.undo().message for _ in range(3)] == ["undid 'make the bus red'", "undid 'make the bus yellow'",
                                                         "back to the previous scene"]
    assert session.scene.history == ("make the ball blue",) and not session.can_undo


def test_bad_limits_are_refused(small_sim, ball_scene):
    for bad in (0, -1, 2.5, True, "32"):
        with pytest.raises(ValueError, match="max_undo"):
            ViewerSession(ball_scene, sim=small_sim, max_undo=bad)
