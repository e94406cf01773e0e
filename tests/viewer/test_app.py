"""The viser app without a browser (panels follow the session; commands typed into the box run on
Enter; recording) and the `morphosim view` command line."""

import os
import subprocess
import sys
import urllib.request

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.errors import BackendUnavailableError
from morphosim_gym.viewer import ViewerSession

from tests.processes import wait_for_line

from .conftest import BUS


@pytest.fixture
def viewer(small_sim, ball_scene, tmp_path):
    from morphosim_gym.viewer.app import SceneViewer

    v = SceneViewer(ViewerSession(ball_scene, sim=small_sim), port=0, verbose=False, record_dir=tmp_path)
    yield v
    v.close()


def test_panels_follow_commands(viewer):
    assert viewer.object_toggles == {"ground (background)": True, "ball": True}
    viewer.run_command("make the ball blue")
    assert viewer.status.startswith("**Done**")
    assert "1. make the ball blue" in viewer.panel_text
    viewer.run_command("delete the ball")
    assert viewer.object_toggles == {"ground (background)": True}
    viewer.run_command("undo")
    assert viewer.object_toggles == {"ground (background)": True, "ball": True}
    viewer.run_command(BUS)
    assert set(viewer.object_toggles) == {"road (background)", "bus"}
    assert "a bus drives down a road" in viewer.panel_text              # the title names the prompt
    assert viewer._time.max == pytest.approx(viewer.session.scene.duration)


def test_a_failed_command_is_shown_and_the_scene_kept(viewer):
    viewer.run_command("make the ball blue")
    good = viewer.session.scene
    viewer.run_command("delete the giraffe")
    assert viewer.status.startswith("**Error**") and "giraffe" in viewer.status
    assert "Still showing the last good scene" in viewer.status
    assert viewer.session.scene is good
    assert "1. make the ball blue" in viewer.panel_text


def test_enter_in_the_box_runs_the_command(viewer):
    box = viewer._command
    box.value = "make the ball"                # typing: nothing runs yet
    assert viewer.session.log == ()
    box.value = "make the ball\ngreen"         # a line break is Enter: what was typed runs, on one line
    assert [e.text for e in viewer.session.log] == ["make the ball green"]
    assert viewer.session.history == ("make the ball green",)
    assert box.value == ""                     # cleared after a command that worked


def test_visibility_toggles_reach_the_session(viewer):
    ball = viewer.session.scene.object("ball").id
    box = viewer._object_boxes[1]
    box.value = False
    assert viewer.session.hidden == {ball}
    box.value = True
    assert viewer.session.hidden == frozenset()


def test_record_without_a_page_uses_the_scene_camera(viewer, tmp_path):
    path = viewer.record()
    assert path is not None and path.parent == tmp_path and path.suffix == ".mp4" and path.stat().st_size > 0
    assert path.name.startswith("a-red-ball-bounces")
    assert "**Wrote**" in viewer._record_status.content


def test_missing_viser_names_the_pip_command(monkeypatch):
    from morphosim_gym.viewer import app

    monkeypatch.setitem(sys.modules, "viser", None)
    with pytest.raises(BackendUnavailableError, match=r'install it with: pip install -e "\.\[viewer\]"$'):
        app.import_viser()


def test_bad_viewer_arguments(small_sim, ball_scene):
    from morphosim_gym.viewer.app import SceneViewer

    session = ViewerSession(ball_scene, sim=small_sim)
    with pytest.raises(ValueError, match="long_side"):
        SceneViewer(session, port=0, verbose=False, long_side=4)
    with pytest.raises(ValueError, match="ViewerSession"):
        SceneViewer(ball_scene, port=0, verbose=False)


# ----------------------------------------------------------------------------- command line
def test_cli_arguments_are_checked(capsys):
    from morphosim_gym.cli import main

    assert main(["view"]) == 2
    assert "Expected a scene file" in capsys.readouterr().err
    assert main(["view", "a red ball", "--env-option", "detail=1"]) == 2
    assert "only with --env" in capsys.readouterr().err
    assert main(["view", "--env", "MorphoSim/Nothing-v0"]) == 2
    assert "registered env id" in capsys.readouterr().err
    assert main(["view", "--env", "MorphoSim/Nothing-v0", "--env-option", "detail"]) == 2
    assert "KEY=VALUE" in capsys.readouterr().err
    assert main(["view", "missing.msim"]) == 2
    assert "no file" in capsys.readouterr().err


def test_cli_env_world_options_become_the_env_sim():
    from morphosim_gym.envs.config import DEFAULT_SIM_CONFIG
    from morphosim_gym.viewer.cli import _env_sim

    assert _env_sim(None, "oracle") == DEFAULT_SIM_CONFIG
    assert _env_sim(1.0, "fit") == ms.SimConfig(reconstruction="fit", generation=ms.GenerationConfig(detail=1.0))


def test_cli_serves_a_scene_file(tmp_path, ball_scene):
    ms.save_scene(ball_scene, tmp_path / "scene.msim")
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "morphosim_gym.cli", "view", str(tmp_path), "--port", "0",
                             "--quiet", "--record-dir", str(tmp_path / "rec")],
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    try:
        found, lines = wait_for_line(proc, r" at (http://\S+)", 300)
        assert found, "".join(lines)
        url = found.group(1)
        assert "ground, ball" in lines[-1]
        page = urllib.request.urlopen(url, timeout=10).read().decode()
        assert "<html" in page.lower()
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


class _PageCamera:
    """What viser's CameraHandle offers: the pose and field of view the page reported."""

    def __init__(self, camera, aspect):
        from morphosim_gym.viewer import viewer_pose

        self.wxyz, self.position = viewer_pose(camera)
        self.fov, self.aspect = np.radians(camera.fov_y_deg), aspect


class _SilentCamera:
    """A page that has not reported its camera yet (viser asserts on reads)."""

    @property
    def wxyz(self):
        raise AssertionError


def test_frames_are_rendered_from_the_page_camera(viewer):
    from morphosim_gym.viewer import render_size

    session = viewer.session
    orbit = session.scene.camera.orbit(40.0, session.orbit_centre())
    client = type("Client", (), {"camera": _PageCamera(orbit, 2.0)})()
    cam = viewer.client_camera(client)
    assert (cam.width, cam.height) == render_size(2.0, viewer.long_side)
    np.testing.assert_allclose(cam.world_to_camera, orbit.world_to_camera, atol=1e-9)
    assert cam.fov_y_deg == pytest.approx(orbit.fov_y_deg)
    viewer._follow.value = True                  # "Scene camera": the scene's own camera at the time shown
    assert viewer.set_time(1.0) == 1.0 and viewer._time.value == 1.0
    np.testing.assert_allclose(viewer.client_camera(client).world_to_camera,
                               session.scene.camera_at(1.0).world_to_camera)
    viewer._follow.value = False
    silent = type("Client", (), {"camera": _SilentCamera()})()
    cam = viewer.client_camera(silent)            # until the page reports: the scene camera, 16:9
    np.testing.assert_allclose(cam.world_to_camera, session.scene.camera.world_to_camera)
    assert (cam.width, cam.height) == render_size(16 / 9, viewer.long_side)
