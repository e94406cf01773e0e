"""Make the README gallery: screenshots and GIFs of the viewer in headless Chromium, and clips
rendered by our renderer, all produced by this project.

    python examples/gallery/make_gallery.py --out examples/gallery

Needs the viewer extra and Debian's chromium + chromium-driver (`pip install -e ".[test]"`,
`apt-get install chromium chromium-driver`). The env screenshot is made where the envs are
installed (MorphoSim/Track-v0).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

import morphosim_gym as ms
from morphosim_gym.generate.cli import write_video

BUS = "The bus is moving from right to left"
FISH = "The fish swims through the crystal-clear waters from right to left"
PAGE_EDITS = ("make the bus yellow", "move the bus to the right", "delete the bus", "undo")


def _quiet_page(driver, close: bool = True) -> None:
    """Close the page's notifications (e.g. 'software WebGL') and move the mouse off the panel (its
    hints) so that neither covers the view."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    if close:
        driver.execute_script(
            "document.querySelectorAll('.mantine-Notification-closeButton').forEach(b => b.click());")
    ActionChains(driver).move_to_element_with_offset(driver.find_element(By.TAG_NAME, "canvas"), -500, -250) \
        .perform()
    time.sleep(0.4)


def _save_jpg(image: np.ndarray, path: Path, width: int = 960) -> Path:
    h, w = image.shape[:2]
    if w > width:
        image = cv2.resize(image, (width, round(h * width / w)), interpolation=cv2.INTER_AREA)
    cv2.imwrite(str(path), image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 85])
    return path


def _label(frame: np.ndarray, text: str) -> np.ndarray:
    out = frame.copy()
    cv2.rectangle(out, (0, 0), (out.shape[1], 16), (0, 0, 0), -1)
    cv2.putText(out, text, (4, 12), cv2.FONT_HERSHEY_SIMPLEX, 0.38, (255, 255, 255), 1, cv2.LINE_AA)
    return out


def page_gallery(out: Path) -> None:
    """The scene viewer in Chromium: a scene, typed edits (a GIF of the page), an error, an orbit."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    from morphosim_gym.viewer import ViewerSession
    from morphosim_gym.viewer.app import SceneViewer
    from morphosim_gym.viewer.testing import headless_chromium, page_text, screenshot, type_command, wait_for

    sim = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=2.0))
    session = ViewerSession.from_source(BUS, sim=sim)
    session.warm_up()
    viewer = SceneViewer(session, port=0, verbose=False, long_side=640)
    viewer.set_time(2.5)
    frames = []
    try:
        with headless_chromium(1280, 800) as driver:
            driver.get(viewer.url)
            wait_for(lambda: viewer.server.get_clients(), 30, message="the page")
            time.sleep(3.0)
            _quiet_page(driver)
            viewer.wait_idle()
            time.sleep(0.5)
            shot = screenshot(driver)
            _save_jpg(shot, out / "viewer.jpg")
            frames.append(shot)
            for text in PAGE_EDITS:
                n = len(session.log)
                type_command(driver, text)
                wait_for(lambda: len(session.log) > n, 20, message=text)
                _quiet_page(driver)
                viewer.wait_idle()
                time.sleep(0.6)
                frames.append(screenshot(driver))
            # orbit with the mouse
            canvas = driver.find_element(By.TAG_NAME, "canvas")
            for _ in range(3):
                ActionChains(driver).move_to_element_with_offset(canvas, -300, 50).click_and_hold() \
                    .move_by_offset(-90, 0).release().perform()
                time.sleep(0.4)
                viewer.wait_idle()
                time.sleep(0.4)
                frames.append(screenshot(driver))
            _save_jpg(frames[-1], out / "viewer_orbit.jpg")
            type_command(driver, "delete the giraffe")
            wait_for(lambda: "Error" in page_text(driver), 20, message="the error")
            _quiet_page(driver, close=False)
            time.sleep(0.5)
            _save_jpg(screenshot(driver), out / "viewer_error.jpg")
    finally:
        viewer.close()
    small = [cv2.resize(f, (640, round(f.shape[0] * 640 / f.shape[1])), interpolation=cv2.INTER_AREA) for f in frames]
    write_video(small, out / "viewer_edits.gif", fps=0.8)
    print(f"wrote {out}/viewer.jpg, viewer_orbit.jpg, viewer_error.jpg, viewer_edits.gif "
          f"(latency of the typed edits: {[round(r['total_ms']) for r in viewer.latencies]} ms)")


def render_gallery(out: Path, size: int = 160) -> None:
    """Clips from our renderer: an edit side by side with the original, and an orbit under water."""
    sim = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(width=size, height=size))
    bus = sim.generate(BUS)
    yellow = sim.edit(bus, "make the bus yellow")
    back = sim.edit(yellow, "reverse its motion")
    frames = []
    for i in range(0, bus.num_frames, 2):
        t = i / bus.fps
        row = [_label(ms.render(s, s.camera_at(t), t).rgb_uint8(), name)
               for s, name in ((bus, BUS.lower()[:28]), (yellow, "make the bus yellow"), (back, "reverse its motion"))]
        frames.append(np.concatenate(row, axis=1))
    write_video(frames, out / "edits.gif", fps=bus.fps / 2)

    fish = sim.generate(FISH)
    centre = fish.centre()
    frames = []
    n = 32
    for i in range(n):
        t = fish.duration * i / (n - 1)
        cam = fish.camera_at(t).orbit(-60 + 120 * i / (n - 1), centre, pitch_deg=10)
        frames.append(ms.render(fish, cam, t).rgb_uint8())
    write_video(frames, out / "orbit.gif", fps=8)
    print(f"wrote {out}/edits.gif, orbit.gif")


def env_gallery(out: Path) -> None:
    """The env viewer on MorphoSim/Track-v0 with the random policy."""
    import gymnasium as gym

    from morphosim_gym.viewer.env_app import EnvViewer
    from morphosim_gym.viewer.testing import headless_chromium, wait_for

    if "MorphoSim/Track-v0" not in gym.registry:
        print("MorphoSim/Track-v0 is not registered here: no env screenshot")
        return
    from morphosim_gym.viewer.testing import screenshot

    with EnvViewer("MorphoSim/Track-v0", policy="random", seed=2, port=0, verbose=False, long_side=640,
                   steps_per_second=10) as viewer, headless_chromium(1280, 800) as driver:
        driver.get(viewer.url)
        wait_for(lambda: viewer.server.get_clients(), 30, message="the page")
        time.sleep(2.0)
        _quiet_page(driver)
        wait_for(lambda: viewer.runner.record.step >= 25, 60, message="25 steps")
        viewer._play.value = False
        viewer.wait_idle()
        time.sleep(0.8)
        _save_jpg(screenshot(driver), out / "env_track.jpg")
    print(f"wrote {out}/env_track.jpg")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="examples/gallery")
    ap.add_argument("--only", choices=["page", "render", "env"], default=None)
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.only in (None, "render"):
        render_gallery(out)
    if args.only in (None, "page"):
        page_gallery(out)
    if args.only in (None, "env"):
        env_gallery(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
