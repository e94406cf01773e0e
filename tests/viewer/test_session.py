"""The viewer's state machine without a browser: command routing, undo, visibility, errors, time,
recording, sources."""

import threading

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.viewer import ViewerSession, resolve_source
from morphosim_gym.viewer.session import format_log, md_escape, resize_keep_fov

from .conftest import BALL, BUS


def _read_video(path):
    import imageio.v2 as imageio

    if str(path).endswith(".gif"):
        return imageio.mimread(path)
    return [f for f in imageio.get_reader(path, format="FFMPEG")]   # (list() asks an endless reader its length)


def _instance(session, camera):
    snap = session.snapshot()
    return ms.render(snap.scene, camera, snap.t).instance


def test_an_edit_changes_the_current_scene_and_its_history(session, ball_scene):
    entry = session.submit("make the ball blue")
    assert entry.ok and entry.kind == "edit" and "ms" in entry.message
    assert session.scene is not ball_scene and session.scene.parent is ball_scene
    assert session.history == ("make the ball blue",)
    ball = session.scene.object("ball")
    sel = session.scene.gaussians.object_ids == ball.id
    colours = session.scene.gaussians.colors[sel].mean(0)
    assert colours[2] > colours[0]                       # blue now
    assert session.can_undo and session.last_error is None


def test_a_scene_description_generates_a_new_scene(session, ball_scene):
    session.submit("make the ball blue")
    session.set_time(1.0)
    session.set_visible(0, False)
    entry = session.submit(BUS)
    assert entry.ok and entry.kind == "generate"
    assert session.scene.object_names == ["road", "bus"]
    assert session.scene.provenance.prompt == BUS
    assert session.history == ()
    assert session.t == 0.0 and session.hidden == frozenset()     # a new scene starts fresh
    # undo goes back to the replaced scene, with its edit, then to the original
    assert session.undo().ok and session.history == ("make the ball blue",)
    assert session.undo().ok and session.scene is ball_scene
    entry = session.undo()
    assert not entry.ok and "Nothing to undo" in entry.message and session.scene is ball_scene


def test_typed_undo_is_the_undo_button(session, ball_scene):
    session.submit("make the ball blue")
    session.submit("reverse its motion")
    assert session.history == ("make the ball blue", "reverse its motion")
    entry = session.submit("Undo")
    assert entry.ok and entry.kind == "undo" and "reverse its motion" in entry.message
    assert session.history == ("make the ball blue",)
    session.undo()
    assert session.scene is ball_scene and not session.can_undo


@pytest.mark.parametrize("text,expect", [
    ("delete the giraffe", "giraffe"),                 # target not in the scene
    ("make the ball", "ball"),                         # an edit with nothing to do
    ("qwerty uiop", "Could not understand"),           # not a command
    ("", "empty"),
    ("   ", "empty"),
])
def test_a_failed_command_shows_its_message_and_keeps_the_last_good_scene(session, ball_scene, text, expect):
    session.submit("make the ball blue")
    good, version = session.scene, session.version
    entry = session.submit(text)
    assert not entry.ok and entry.kind == "error"
    assert expect in entry.message
    assert session.last_error == entry.message
    assert session.scene is good and session.version == version
    assert session.history == ("make the ball blue",)
    # the next good command clears the error
    assert session.submit("make the ball green").ok and session.last_error is None


def test_errors_are_the_editors_own_messages(session, small_sim, ball_scene):
    with pytest.raises(ms.EditError) as info:
        small_sim.edit(ball_scene, "delete the giraffe")
    assert session.submit("delete the giraffe").message == str(info.value)


def test_visibility_toggles_leave_objects_out_of_the_frame(session):
    cam = session.default_camera(64, 64)
    ball = session.scene.object("ball").id
    inst = _instance(session, cam)
    assert (inst == ball).sum() > 20
    shown = session.render(cam)
    session.set_visible(ball, False)
    assert not session.is_visible(ball) and session.hidden == {ball}
    hidden = session.render(cam)
    changed = np.abs(hidden.astype(int) - shown.astype(int)).sum(-1) > 30
    assert changed[inst == ball].mean() > 0.8            # the ball's pixels changed
    assert changed[inst != ball].mean() < 0.05           # (almost) nothing else did
    session.set_visible(ball, True)
    np.testing.assert_array_equal(session.render(cam), shown)
    with pytest.raises(ValueError, match="object id"):
        session.set_visible(99, False)


def test_hidden_ids_follow_the_scene(session):
    ball = session.scene.object("ball").id
    session.set_visible(ball, False)
    session.submit("make the ball blue")
    assert session.hidden == {ball}                      # still hidden after an edit
    session.set_visible(ball, True)
    session.submit("delete the ball")
    assert "ball" not in session.scene.object_names and session.hidden == frozenset()
    session.undo()
    assert "ball" in session.scene.object_names


def test_time_is_clamped_and_playback_wraps(session):
    d = session.scene.duration
    assert session.set_time(-1.0) == 0.0
    assert session.set_time(d + 5) == d
    with pytest.raises(ValueError):
        session.set_time(float("nan"))
    session.set_time(d - 0.1)
    assert session.advance(0.3) == pytest.approx(0.2)
    session.set_time(d - 0.1)
    assert session.advance(0.3, loop=False) == d


def test_frames_follow_time(session):
    cam = session.default_camera(64, 64)
    session.set_time(0.0)
    a = session.render(cam)
    session.set_time(session.scene.duration)
    assert np.abs(session.render(cam).astype(int) - a.astype(int)).max() > 50   # the ball moved


def test_listeners_hear_every_change_and_versions_grow(session):
    heard = []
    session.on_change(heard.append)
    v0 = session.version
    session.set_time(0.5)
    session.set_time(0.5)                  # no change: no event
    session.set_visible(0, False)
    session.submit("make the ball blue")
    session.submit("delete the giraffe")
    session.undo()
    assert heard == ["time", "visibility", "scene", "error", "scene"]
    assert session.version == v0 + 4
    snap = session.snapshot()
    assert (snap.scene, snap.t, snap.hidden, snap.version) == (session.scene, 0.5, {0}, session.version)


def test_default_camera_keeps_the_generation_view(session):
    gen = session.scene.camera
    cam = session.default_camera(160, 90)
    assert (cam.width, cam.height) == (160, 90)
    assert cam.fov_y_deg == pytest.approx(gen.fov_y_deg)
    np.testing.assert_allclose(cam.world_to_camera, gen.world_to_camera)
    assert cam.fx == pytest.approx(cam.fy)              # square pixels at any aspect ratio
    wide = resize_keep_fov(gen, 200, 100)
    assert wide.fov_y_deg == pytest.approx(gen.fov_y_deg) and wide.fov_x_deg > gen.fov_x_deg


@pytest.mark.parametrize("suffix", ["gif", "mp4"])
def test_record_writes_the_whole_clip_as_shown(session, tmp_path, suffix):
    ball = session.scene.object("ball").id
    if suffix == "mp4":          # (a gif drops repeated frames, and without the ball nothing moves)
        session.set_visible(ball, False)
    cam = session.default_camera(48, 32)
    calls = []
    path = session.record(tmp_path / f"clip.{suffix}", cam, progress=lambda i, n: calls.append((i, n)))
    frames = _read_video(path)
    n = session.scene.num_frames
    assert len(frames) == n and calls[-1] == (n, n)
    assert frames[0].shape[:2] == (32, 48)
    # the video shows what the viewer shows (for the mp4: without the ball)
    session.set_time(0.0)
    expected = session.render(cam)
    got = np.asarray(frames[0])[..., :3].astype(int)
    assert np.abs(got - expected.astype(int)).mean() < 8      # codec loss only
    path2 = session.record(tmp_path / "cam.mp4", session.scene.camera_at, num_frames=3)
    assert len(_read_video(path2)) == 3
    with pytest.raises(ValueError, match="mp4 or .gif"):
        session.record(tmp_path / "clip.avi", cam)


def test_sources_scene_files_directories_and_prompts(tmp_path, small_sim, ball_scene):
    ms.save_scene(ball_scene, tmp_path / "scene.msim")
    assert resolve_source(str(tmp_path)) == tmp_path / "scene.msim"
    assert resolve_source(str(tmp_path / "scene.msim")) == tmp_path / "scene.msim"
    assert resolve_source(BALL) is None
    with pytest.raises(ValueError, match="no file"):
        resolve_source(str(tmp_path / "missing.msim"))
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="scene.msim"):
        resolve_source(str(tmp_path / "empty"))
    loaded = ViewerSession.from_source(str(tmp_path), sim=small_sim)
    assert loaded.scene.content_hash() == ball_scene.content_hash()
    generated = ViewerSession.from_source(BALL, sim=small_sim)
    assert generated.scene.content_hash() == ball_scene.content_hash()
    with pytest.raises(ms.CommandError):
        ViewerSession.from_source("make it blue", sim=small_sim)      # an edit is not a scene
    with pytest.raises(ValueError, match="Scene4D"):
        ViewerSession("not a scene", sim=small_sim)


def test_a_saved_edited_scene_can_be_undone_in_the_viewer(tmp_path, small_sim, ball_scene):
    edited = small_sim.edit(ball_scene, "make the ball blue")
    ms.save_scene(edited, tmp_path / "edited.msim")
    session = ViewerSession.from_source(str(tmp_path / "edited.msim"), sim=small_sim)
    assert session.history == ("make the ball blue",)
    if session.scene.parent is not None:                # the file keeps its undo history
        assert session.undo().ok and session.history == ()


def test_renders_and_commands_from_several_threads(session):
    cam = session.default_camera(48, 48)
    errors = []

    def renderer():
        try:
            for _ in range(20):
                session.render(cam)
        except Exception as exc:            # pragma: no cover - the failure is reported below
            errors.append(exc)

    threads = [threading.Thread(target=renderer) for _ in range(2)]
    for th in threads:
        th.start()
    for text in ("make the ball blue", "reverse its motion", "undo", "delete the ball", "undo"):
        session.submit(text)
        session.advance(0.1)
    for th in threads:
        th.join()
    assert not errors
    assert session.history == ("make the ball blue",)


def test_log_formatting_escapes_markdown():
    assert md_escape("a*b_[c]") == r"a\*b\_\[c\]"
    from morphosim_gym.viewer import LogEntry

    text = format_log([LogEntry("make the *ball* blue", "edit", True, "edited in 3 ms"),
                       LogEntry("x", "error", False, "bad `x`")])
    assert text.splitlines() == [r"- ok: make the \*ball\* blue - edited in 3 ms", r"- **error**: x - bad \`x\`"]
