"""Headless Chromium for the viewer's browser test and benchmark (selenium + Debian's chromium and
chromium-driver: `apt-get install chromium chromium-driver`, `pip install selenium`).

    with headless_chromium() as driver:
        driver.get(viewer.url)
        image = screenshot(driver)            # [H, W, 3] uint8, what the page shows
"""

from __future__ import annotations

import shutil
import tempfile
import time
from contextlib import contextmanager
from typing import Any, Callable, Iterator

import numpy as np

from ..errors import BackendUnavailableError

__all__ = ["find_chromium", "headless_chromium", "screenshot", "wait_for", "CHROMIUM_FLAGS", "command_box",
           "type_command", "page_text", "frame_on_screen", "INSTALL_HINT"]

INSTALL_HINT = "apt-get install -y chromium chromium-driver && pip install selenium"

# Flags that work in a sandbox-less container with no network but loopback: without the
# background-networking ones Chromium's own connections are refused and slow everything down.
# WebGL (three.js draws our frames as the scene background) runs on SwiftShader.
CHROMIUM_FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--disable-quic",
    "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-dev-shm-usage", "--hide-scrollbars",
)


def find_chromium() -> tuple[str, str]:
    """(chromium binary, chromedriver binary), or `BackendUnavailableError` naming the install command."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if browser is None or driver is None:
        raise BackendUnavailableError(f"Expected chromium and chromedriver on PATH, found browser={browser!r}, "
                                      f"driver={driver!r}; install them with: {INSTALL_HINT}")
    return browser, driver


@contextmanager
def headless_chromium(width: int = 1280, height: int = 800) -> Iterator[Any]:
    """A selenium Chrome driver on a fresh profile, quit (and its profile removed) on exit."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError as exc:
        raise BackendUnavailableError(f"The browser test needs selenium; install it with: {INSTALL_HINT}") from exc
    browser, driver_path = find_chromium()
    profile = tempfile.mkdtemp(prefix="morphosim-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = browser
    for flag in CHROMIUM_FLAGS:
        opts.add_argument(flag)
    opts.add_argument(f"--window-size={int(width)},{int(height)}")
    opts.add_argument(f"--user-data-dir={profile}")
    driver = webdriver.Chrome(service=Service(driver_path), options=opts)
    try:
        driver.set_page_load_timeout(60)
        yield driver
    finally:
        try:
            driver.quit()
        finally:
            shutil.rmtree(profile, ignore_errors=True)


def screenshot(driver: Any) -> np.ndarray:
    """[H, W, 3] uint8 RGB of the page's viewport."""
    import cv2

    png = np.frombuffer(driver.get_screenshot_as_png(), dtype=np.uint8)
    bgr = cv2.imdecode(png, cv2.IMREAD_COLOR)
    return np.ascontiguousarray(bgr[..., ::-1])


def wait_for(predicate: Callable[[], Any], timeout: float = 10.0, interval: float = 0.02,
             message: str = "condition") -> Any:
    """Poll `predicate` until it returns something truthy (returned); `TimeoutError` naming `message`."""
    end = time.perf_counter() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.perf_counter() > end:
            raise TimeoutError(f"Expected {message} within {timeout:g} s, found it still false")
        time.sleep(interval)


def command_box(driver: Any) -> Any:
    """The viewer's command text box."""
    from selenium.webdriver.common.by import By

    return driver.find_element(By.XPATH, "//label[normalize-space()='Command']/following::textarea[1]")


def type_command(driver: Any, text: str) -> None:
    """Type a command into the viewer's box and press Enter."""
    from selenium.webdriver.common.keys import Keys

    box = command_box(driver)
    box.click()
    box.send_keys(Keys.CONTROL, "a")
    box.send_keys(Keys.DELETE)
    box.send_keys(text + Keys.ENTER)


def page_text(driver: Any) -> str:
    """All visible text of the page."""
    from selenium.webdriver.common.by import By

    return driver.find_element(By.TAG_NAME, "body").text


def frame_on_screen(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """An RGB frame (bilinear) or a label map (nearest) scaled to the screen's (width, height), as the
    page stretches a frame over its canvas."""
    import cv2

    rgb = image.dtype == np.uint8 and image.ndim == 3
    if not rgb:
        image = image.astype(np.float32)
    out = cv2.resize(image, tuple(int(v) for v in size), interpolation=cv2.INTER_LINEAR if rgb else cv2.INTER_NEAREST)
    return out if rgb else out.astype(np.int32)
