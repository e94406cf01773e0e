"""End to end in headless Chromium: the page shows our rendered frames from its own camera, a typed
edit changes the image as asked, a failed edit shows its message and keeps the last good scene,
Undo and a mouse orbit re-render.

Needs Debian's chromium and chromium-driver (installed by `.ci/run`) and selenium (extra `test`).
"""

import math
import time

import numpy as np
import pytest

import morphosim_gym as ms
from morphosim_gym.errors import BackendUnavailableError

pytestmark = pytest.mark.slow

PROMPT = "a red ball bounces from right to left"


@pytest.fixture(scope="module")
def browser_env(small_sim):
    from morphosim_gym.viewer import ViewerSession
    from morphosim_gym.viewer.app import SceneViewer
    from morphosim_gym.viewer.testing import find_chromium, headless_chromium, wait_for

    try:
        find_chromium()
        import selenium  # noqa: F401
    except (BackendUnavailableError, ImportError) as exc:
        pytest.skip(f"no headless browser here: {exc}")
    session = ViewerSession.from_source(PROMPT, sim=small_sim)
    session.warm_up()
    viewer = SceneViewer(session, port=0, verbose=False, long_side=384)
    try:
        with headless_chromium(1280, 800) as driver:
            driver.get(viewer.url)
            wait_for(lambda: viewer.server.get_clients(), 30, message="the page to connect")
            client = next(iter(viewer.server.get_clients().values()))
            yield session, viewer, driver, client
    finally:
        viewer.close()


def _settled_frame(viewer, client, predicate=lambda f: True, timeout=20.0):
    """The last frame sent to the client once it satisfies `predicate` and no render is pending."""
    from morphosim_gym.viewer.testing import wait_for

    def ready():
        viewer.wait_idle(2.0)
        f = viewer.frames.get(client.client_id)
        return f if f is not None and predicate(f) else None

    return wait_for(ready, timeout, message="a frame")


def _shown(driver, frame, timeout=10.0):
    """A screenshot once the page shows `frame` (on most pixels not under the panels), and the mask
    of screen pixels where it does."""
    from morphosim_gym.viewer.testing import frame_on_screen, screenshot, wait_for

    def check():
        shot = screenshot(driver)
        expected = frame_on_screen(frame.image, (shot.shape[1], shot.shape[0]))
        agree = np.abs(shot.astype(int) - expected.astype(int)).mean(-1) < 20
        return (shot, agree) if agree.mean() > 0.5 else None

    return wait_for(check, timeout, interval=0.1, message="the page to show the frame sent")


def _ball_mask(session, frame, size):
    from morphosim_gym.viewer.testing import frame_on_screen

    inst = ms.render(session.scene, frame.camera, frame.t).instance
    return frame_on_screen(inst, size) == session.scene.object("ball").id


def test_page_camera_is_the_scene_camera(browser_env):
    session, viewer, driver, client = browser_env
    gen = session.scene.camera
    viewer._reset_camera(client)                 # (in case another test moved it)
    frame = _settled_frame(viewer, client, lambda f: np.allclose(f.camera.position, gen.position, atol=1e-3))
    # viser's camera, converted, is the generation camera (same pose, same vertical field of view)
    np.testing.assert_allclose(frame.camera.world_to_camera, gen.world_to_camera, atol=1e-3)
    assert frame.camera.fov_y_deg == pytest.approx(gen.fov_y_deg, abs=0.01)
    assert frame.image.shape[1] / frame.image.shape[0] == pytest.approx(client.camera.aspect, rel=0.02)
    assert math.isclose(client.camera.fov, math.radians(gen.fov_y_deg), abs_tol=1e-4)


def test_typed_edit_changes_the_image_as_asked(browser_env, record_property):
    from morphosim_gym.viewer.testing import page_text, type_command, wait_for

    session, viewer, driver, client = browser_env
    gen = session.scene.camera
    viewer._reset_camera(client)
    before = _settled_frame(viewer, client, lambda f: np.allclose(f.camera.position, gen.position, atol=1e-3))
    shot0, visible0 = _shown(driver, before)
    size = (shot0.shape[1], shot0.shape[0])
    ball = _ball_mask(session, before, size) & visible0
    assert ball.sum() > 200, "the ball should be on screen, outside the panels"
    red = shot0[ball].astype(int)
    assert np.mean(red[:, 0] > red[:, 2] + 60) > 0.9                     # a red ball

    # time the round trip in the page: Enter pressed -> the latency line names the edit
    driver.execute_script("""
        window.__mt = {};
        document.addEventListener('keydown', e => {
                if (e.key === 'Enter') window.__mt.enter = performance.now(); }, true);
        new MutationObserver(() => {
            if (!window.__mt.frame && document.body.innerText.includes("Frame of 'make the ball blue' sent"))
                window.__mt.frame = performance.now();
        }).observe(document.body, {subtree: true, childList: true, characterData: true});
    """)
    old_hash = session.scene.content_hash()
    type_command(driver, "make the ball blue")
    wait_for(lambda: "Done" in page_text(driver), 20, message="the page to say the edit was done")
    after = _settled_frame(viewer, client, lambda f: f.scene_hash != old_hash)
    assert session.history == ("make the ball blue",)
    assert "make the ball blue" in page_text(driver)                     # the edit history
    shot1, visible1 = _shown(driver, after)
    blue = shot1[ball & visible1].astype(int)
    assert len(blue) > 200
    assert np.mean(blue[:, 2] > blue[:, 0] + 60) > 0.9                   # the ball is blue now
    rest = visible0 & visible1 & ~_dilate(ball | _ball_mask(session, after, size))
    diff = np.abs(shot1[rest].astype(int) - shot0[rest].astype(int)).mean()
    assert diff < 4, f"pixels away from the ball changed by {diff:.1f} on average"
    times = wait_for(lambda: driver.execute_script("return window.__mt.frame ? window.__mt : null"), 10,
                     message="the latency line")
    record_property("edit_to_frame_in_page_ms", round(times["frame"] - times["enter"], 1))
    record_property("edit_to_frame_server_ms", round(viewer.latencies[-1]["total_ms"], 1))


def test_failed_edit_shows_its_message_and_keeps_the_scene(browser_env):
    from morphosim_gym.viewer.testing import page_text, type_command, wait_for

    session, viewer, driver, client = browser_env
    good = session.scene
    frame = _settled_frame(viewer, client)
    type_command(driver, "delete the giraffe")
    text = wait_for(lambda: (t := page_text(driver)) and "Error" in t and t, 20, message="an error message")
    assert "giraffe" in text and "Still showing the last good scene" in text
    assert session.scene is good
    time.sleep(0.3)
    viewer.wait_idle()
    assert viewer.frames[client.client_id].scene_hash == frame.scene_hash
    _shown(driver, viewer.frames[client.client_id])


def test_undo_button_and_orbit(browser_env):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    from morphosim_gym.viewer.testing import wait_for

    session, viewer, driver, client = browser_env
    if not session.can_undo:
        session.submit("make the ball blue")
    depth = len(session.history)
    driver.find_element(By.XPATH, "//button[normalize-space()='Undo']").click()
    wait_for(lambda: len(session.history) == depth - 1, 10, message="undo")
    frame = _settled_frame(viewer, client, lambda f: f.scene_hash == session.scene.content_hash())
    _shown(driver, frame)

    # drag on the canvas (left of the panel): the page orbits its camera and we re-render from it
    canvas = driver.find_element(By.TAG_NAME, "canvas")
    start = frame.camera.position.copy()
    ActionChains(driver).move_to_element_with_offset(canvas, -300, 100).click_and_hold() \
        .move_by_offset(120, 0).move_by_offset(120, 0).release().perform()
    moved = _settled_frame(viewer, client, lambda f: np.linalg.norm(f.camera.position - start) > 0.05)
    centre = session.orbit_centre()
    # an orbit keeps the distance to the look-at point (about; the drag may also zoom a little)
    assert np.linalg.norm(moved.camera.position - centre) == pytest.approx(np.linalg.norm(start - centre), rel=0.1)
    _shown(driver, moved)


def _dilate(mask, r=6):
    import cv2

    return cv2.dilate(mask.astype(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)) > 0


def test_env_episode_in_the_page():
    """`morphosim view --env MorphoSim/Track-v0`: the page shows our third-person frames from its own
    camera while a random policy plays, with the observation, reward and success in the panel."""
    import gymnasium as gym

    from morphosim_gym.viewer.env_app import EnvViewer
    from morphosim_gym.viewer.testing import find_chromium, headless_chromium, page_text, wait_for

    if "MorphoSim/Track-v0" not in gym.registry:
        pytest.skip("MorphoSim/Track-v0 is not registered in this build")
    try:
        find_chromium()
    except BackendUnavailableError as exc:
        pytest.skip(f"no headless browser here: {exc}")
    with EnvViewer("MorphoSim/Track-v0", policy="random", port=0, verbose=False, long_side=320,
                   steps_per_second=10) as viewer, headless_chromium(1280, 800) as driver:
        driver.get(viewer.url)
        wait_for(lambda: viewer.server.get_clients(), 30, message="the page to connect")
        client = next(iter(viewer.server.get_clients().values()))
        step0 = viewer.runner.record.step
        wait_for(lambda: viewer.runner.record.step >= step0 + 5 or viewer.runner.record.episode > 1, 30,
                 message="the policy to play")
        text = wait_for(lambda: (t := page_text(driver)) and "reward:" in t and t, 20, message="the episode panel")
        assert "Track-v0" in text and "success:" in text and "keep the" in text       # the instruction
        assert "what the agent sees" in text
        viewer._play.value = False                                 # hold still to compare the page with our frame
        viewer.wait_idle()
        frame = wait_for(lambda: viewer.frames.get(client.client_id), 20, message="a frame")
        assert frame["camera"] is not None                          # rendered from the page's camera
        _shown(driver, type("F", (), {"image": frame["image"]})())
