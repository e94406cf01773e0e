"""`SceneViewer`: the 4D scene viewer in the browser (viser), driven by a `ViewerSession`.

Our CPU renderer draws every image; the browser only shows it. viser serves a three.js page
over a websocket: we set each client's background image to a JPEG rendered from that
client's camera (converted with `camera_from_viewer`), and re-render when the camera moves,
the time changes, an object is shown or hidden, or the scene is edited. Renders run on one
worker thread (`FrameWorker`) that keeps only the latest request per client, so callbacks
return at once and a burst of camera moves costs one render.

Panels: a command box (edits and new prompts, Enter runs them) with the result, the edit
history and Undo; time (slider, play, loop, follow the scene's own camera); objects (one
visibility toggle each); record (a video of the whole clip from the current view); view
(reset, resolution).
"""

from __future__ import annotations

import math
import re
import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ..errors import BackendUnavailableError
from ..extras import install_line
from ..scene import Camera
from .camera import camera_from_viewer, render_size, viewer_view
from .session import Snapshot, ViewerSession, format_log, md_escape, resize_keep_fov
from .lifecycle import ServedViewer
from .worker import FrameWorker

__all__ = ["SceneViewer", "FrameInfo", "import_viser", "PIP_HINT"]

PIP_HINT = install_line("viewer")           # the README's line
MAX_LATENCIES = 1000      # command latencies a viewer keeps


def import_viser() -> Any:
    """The viser module, or `BackendUnavailableError` naming the pip command."""
    try:
        import viser
    except ImportError as exc:
        raise BackendUnavailableError(f"The viewer needs viser, which is not installed; install it with: "
                                      f"{PIP_HINT}") from exc
    return viser


@dataclass(frozen=True)
class FrameInfo:
    """The last frame sent to a client.

    Attributes:
        version: the session version it shows.
        scene_hash: content hash of the scene it shows.
        t: the time it shows.
        image: [H, W, 3] uint8 (what was encoded and sent).
        camera: the camera it was rendered from.
        render_ms: rendering time; send_ms: encoding and queueing time.
        sent_at: `time.perf_counter()` when it was handed to the websocket.
    """

    version: int
    scene_hash: str
    t: float
    image: np.ndarray
    camera: Camera
    render_ms: float
    send_ms: float
    sent_at: float


class SceneViewer(ServedViewer):
    """Serve a session in the browser.

    Args:
        session: the state shown.
        host, port: where to listen (port 0: any free port; see `url`).
        long_side: pixels of the longer side of streamed frames (the canvas's aspect ratio).
        jpeg_quality: JPEG quality of streamed frames.
        record_dir: where recorded videos go.
        record_long_side: longer side of recorded videos, pixels.
        play_fps: frames per second shown while playing.
        verbose: print viser's banner.
    """

    def __init__(self, session: ViewerSession, *, host: str = "127.0.0.1", port: int = 8080, long_side: int = 512,
                 jpeg_quality: int = 85, record_dir: str | Path = "morphosim_recordings", record_long_side: int = 512,
                 play_fps: float = 12.0, verbose: bool = True) -> None:
        viser = import_viser()
        if not isinstance(session, ViewerSession):
            raise ValueError(f"Expected a ViewerSession, found {type(session).__name__}")
        if not 16 <= int(long_side) <= 4096:
            raise ValueError(f"Expected long_side in [16, 4096], found {long_side!r}")
        if not 1 <= int(jpeg_quality) <= 100:
            raise ValueError(f"Expected jpeg_quality in [1, 100], found {jpeg_quality!r}")
        if not (0 < float(play_fps) <= 60):
            raise ValueError(f"Expected play_fps in (0, 60], found {play_fps!r}")
        self.session = session
        self.long_side = int(long_side)
        self.jpeg_quality = int(jpeg_quality)
        self.record_dir = Path(record_dir)
        self.record_long_side = int(record_long_side)
        self.play_fps = float(play_fps)
        # one per command (the newest MAX_LATENCIES): text received -> first frame of the result sent
        self.latencies: deque[dict] = deque(maxlen=MAX_LATENCIES)
        self.frames: dict[int, FrameInfo] = {}
        self._command_lock = threading.Lock()
        self._pending: Optional[dict] = None
        self._pending_lock = threading.Lock()
        super().__init__()
        self._object_boxes: list[Any] = []
        self._object_key: tuple = ()

        self._serve(viser, host, port, verbose)
        self.server.scene.set_up_direction("+z")
        self.server.scene.world_axes.visible = False
        self._frames = FrameWorker(on_error=self._frame_failed)
        self._build_gui()
        self._set_initial_camera()
        self.server.on_client_connect(self._on_connect)
        self.server.on_client_disconnect(lambda client: self._forget(client.client_id))
        session.on_change(self._on_change)
        self._player = threading.Thread(target=self._play_loop, name="morphosim-viewer-play", daemon=True)
        self._player.start()

    # ================================================================ lifecycle
    def close(self) -> None:
        """Stop playing, rendering and serving."""
        if self._closed.is_set():
            return
        self._closed.set()
        self._frames.stop()
        self._player.join(timeout=2.0)
        self.server.stop()

    @property
    def status(self) -> str:
        """The command panel's result line (markdown), as the page shows it."""
        return self._status.content

    @property
    def panel_text(self) -> str:
        """Everything the command panel shows: title, result, latency and history (markdown)."""
        return "\n".join(m.content for m in (self._title, self._status, self._latency, self._history))

    @property
    def object_toggles(self) -> dict[str, bool]:
        """The object list as shown: label -> visible."""
        return {box.label: box.value for box in self._object_boxes}

    def set_time(self, t: float) -> float:
        """Show time `t` (as the time slider does); returns the time set."""
        t = self.session.set_time(t)
        self._time.value = t
        return t

    def run_command(self, text: str, client: Any = None) -> None:
        """Run a command as if typed into the page (by `client`, if given)."""
        self._run_command(text, client)

    def wait_idle(self, timeout: float = 10.0) -> bool:
        """Block until every requested frame has been sent (for tests and benchmarks)."""
        return self._frames.wait_idle(timeout)

    # ================================================================ GUI
    def _build_gui(self) -> None:
        gui = self.server.gui
        gui.configure_theme(control_width="large", show_logo=False, show_share_button=False)
        scene = self.session.scene
        self._title = gui.add_markdown(self._title_text())
        with gui.add_folder("Command"):
            # A multi-line box whose Enter key ends the command: the page sends the box's whole value
            # after every keystroke, so a command is complete when its newline arrives. (A viser form's
            # submit message can overtake the last keystrokes' value update and run a truncated command.)
            self._command = gui.add_text(
                "Command", "", multiline=True,
                hint="An edit ('make the ball blue', 'reverse its motion') or a new scene "
                     "('a bus drives down a road'); Enter runs it.")
            self._buttons = gui.add_button_group("Actions", ("Run", "Undo"))
            self._status = gui.add_markdown("Type an edit (e.g. *make it blue*) or a new scene, then press Enter.")
            self._latency = gui.add_markdown("")
            self._history = gui.add_markdown(self._history_text())
        with gui.add_folder("Time"):
            step = 1.0 / max(4.0 * scene.fps, 1.0)
            self._time = gui.add_slider("Time (s)", min=0.0, max=max(scene.duration, step), step=step,
                                        initial_value=0.0)
            self._play = gui.add_checkbox("Play", False)
            self._loop = gui.add_checkbox("Loop", True)
            self._follow = gui.add_checkbox("Scene camera", False,
                                            hint="Show the scene's own (generation) camera instead of yours")
        self._objects_folder = gui.add_folder("Objects")
        self._rebuild_objects()
        with gui.add_folder("Record", expand_by_default=False):
            self._record_format = gui.add_dropdown("Format", ("mp4", "gif"), initial_value="mp4")
            self._record_button = gui.add_button("Record video", hint="The whole clip from the current view")
            self._record_status = gui.add_markdown("")
        with gui.add_folder("View", expand_by_default=False):
            self._reset_view = gui.add_button("Reset view")
            self._resolution = gui.add_slider("Resolution", min=128, max=1024, step=32, initial_value=self.long_side)

        self._command.on_update(self._on_command_text)
        self._buttons.on_click(self._on_button)
        self._time.on_update(lambda _: self.session.set_time(self._time.value))
        self._follow.on_update(lambda _: self._request_all())
        self._record_button.on_click(lambda event: self._record(event.client))
        self._reset_view.on_click(lambda event: self._reset_camera(event.client) if event.client else None)
        self._resolution.on_update(self._on_resolution)

    def _title_text(self) -> str:
        prompt = self.session.scene.provenance.prompt or "(no prompt)"
        return f"**MorphoSim** — {md_escape(prompt)}"

    def _history_text(self) -> str:
        edits = self.session.history
        lines = ["**Edits**: " + ("none yet" if not edits else "")]
        lines += [f"{i}. {md_escape(e)}" for i, e in enumerate(edits, 1)]
        log = format_log(self.session.log, limit=6)
        if log:
            lines += ["", "**Commands**", log]
        return "\n".join(lines)

    def _rebuild_objects(self) -> None:
        scene = self.session.scene
        key = tuple((o.id, o.name, o.role) for o in scene.objects)
        if key == self._object_key:
            for box, obj in zip(self._object_boxes, scene.objects):
                box.value = self.session.is_visible(obj.id)
            return
        for box in self._object_boxes:
            box.remove()
        self._object_boxes = []
        self._object_key = key
        with self._objects_folder:
            for obj in scene.objects:
                label = obj.name if obj.role == "object" else f"{obj.name} ({obj.role})"
                box = self.server.gui.add_checkbox(label, self.session.is_visible(obj.id),
                                                   hint=f"object id {obj.id}, category {obj.category}")
                box.on_update(lambda _, oid=obj.id, b=box: self.session.set_visible(oid, b.value))
                self._object_boxes.append(box)

    def _refresh_panels(self) -> None:
        """Bring every panel in line with the session after a scene change."""
        scene = self.session.scene
        self._title.content = self._title_text()
        self._history.content = self._history_text()
        step = 1.0 / max(4.0 * scene.fps, 1.0)
        self._time.max = max(scene.duration, step)
        self._time.step = step
        self._time.value = min(self.session.t, scene.duration)
        self._rebuild_objects()

    # ================================================================ commands
    def _on_command_text(self, event: Any) -> None:
        value = self._command.value
        if "\n" not in value:
            return
        text = " ".join(line.strip() for line in value.splitlines() if line.strip())
        self._command.value = text             # the newline is not part of the command
        self._run_command(text, event.client)

    def _on_button(self, event: Any) -> None:
        if event.target.value == "Undo":
            self._run_command("undo", event.client)
        else:
            self._run_command(self._command.value, event.client)

    def _run_command(self, text: str, client: Any = None) -> None:
        """Apply a typed command (on viser's callback thread pool, never the websocket loop)."""
        received = time.perf_counter()
        received_epoch = time.time()
        with self._command_lock:
            before = self.session.scene
            with self._pending_lock:
                self._pending = {"text": text, "received": received, "received_epoch": received_epoch,
                                 "before": before, "edit_ms": None}
            self._latency.content = ""
            if text.strip():
                self._status.content = f"Running: {md_escape(text.strip())} ..."
            entry = self.session.submit(text)
            with self._pending_lock:
                if not entry.ok:
                    self._pending = None
                elif self._pending is not None:
                    self._pending["edit_ms"] = 1000.0 * entry.seconds
                    self._pending["kind"] = entry.kind
            if entry.ok:
                if entry.kind == "generate":
                    self._set_initial_camera()
                    for c in self.server.get_clients().values():
                        self._reset_camera(c)
                self._refresh_panels()
                self._command.value = ""
                self._status.content = f"**Done**: {md_escape(entry.message)}"
            else:
                self._history.content = self._history_text()
                self._status.content = (f"**Error**: could not apply '{md_escape(entry.text)}': "
                                        f"{md_escape(entry.message)}  \nStill showing the last good scene.")
                if client is not None:
                    client.add_notification("Command failed", entry.message, color="red", auto_close_seconds=8.0)

    # ================================================================ frames
    def _on_connect(self, client: Any) -> None:
        client.camera.on_update(lambda _: self._request(client.client_id))
        self._request(client.client_id)

    def _forget(self, client_id: int) -> None:
        self._frames.discard(client_id)
        self.frames.pop(client_id, None)

    def _on_change(self, what: str) -> None:
        if what != "error":
            self._request_all()

    def _on_resolution(self, _: Any) -> None:
        self.long_side = int(self._resolution.value)
        self._request_all()

    def _request_all(self) -> None:
        for cid in list(self.server.get_clients()):
            self._request(cid)

    def _request(self, client_id: int) -> None:
        if not self._closed.is_set():
            self._frames.request(client_id, lambda: self._send_frame(client_id))

    def client_camera(self, client: Any, snap: Optional[Snapshot] = None) -> Camera:
        """The camera a client's next frame is rendered from."""
        snap = snap or self.session.snapshot()
        cam = client.camera
        try:
            wxyz, position, fov, aspect = cam.wxyz, cam.position, cam.fov, cam.aspect
        except (AssertionError, ZeroDivisionError):     # no camera report from the page yet
            wxyz = None
            aspect = 16 / 9
        if not (isinstance(aspect, float) and math.isfinite(aspect) and aspect > 0):
            aspect = 16 / 9
        width, height = render_size(aspect, self.long_side)
        if wxyz is None or self._follow.value:
            return resize_keep_fov(snap.scene.camera_at(snap.t), width, height)
        return camera_from_viewer(wxyz, position, fov, width, height)

    def _send_frame(self, client_id: int) -> None:
        client = self.server.get_clients().get(client_id)
        if client is None:
            return
        snap = self.session.snapshot()
        camera = self.client_camera(client, snap)
        start = time.perf_counter()
        image = self.session.render(camera, snap)
        rendered = time.perf_counter()
        client.scene.set_background_image(image, format="jpeg", jpeg_quality=self.jpeg_quality)
        client.flush()
        sent = time.perf_counter()
        info = FrameInfo(snap.version, snap.scene.content_hash(), snap.t, image, camera,
                         1000.0 * (rendered - start), 1000.0 * (sent - rendered), sent)
        self.frames[client_id] = info
        self._note_latency(snap, info)

    def _note_latency(self, snap: Snapshot, info: FrameInfo) -> None:
        with self._pending_lock:
            p = self._pending
            if p is None or snap.scene is p["before"]:
                return
            self._pending = None
        record = {"text": p["text"], "kind": p.get("kind"),
                  "total_ms": 1000.0 * (info.sent_at - p["received"]),
                  "render_ms": info.render_ms, "send_ms": info.send_ms,
                  "size": [int(info.image.shape[1]), int(info.image.shape[0])],
                  "gaussians": len(snap.scene.gaussians), "received_epoch": p["received_epoch"],
                  "sent_epoch": p["received_epoch"] + (info.sent_at - p["received"])}
        self.latencies.append(record)
        self._latency.content = (f"Frame of '{md_escape(p['text'])}' sent {record['total_ms']:.0f} ms after the "
                                 f"command arrived (render {info.render_ms:.0f} ms at {record['size'][0]}x"
                                 f"{record['size'][1]}, {record['gaussians']} Gaussians)")

    def _frame_failed(self, key: Any, exc: BaseException) -> None:
        self._latency.content = f"**Error**: frame failed: {md_escape(type(exc).__name__)}: {md_escape(str(exc))}"

    # ================================================================ cameras
    def _set_initial_camera(self) -> None:
        view = viewer_view(self.session.scene.camera, self.session.orbit_centre())
        init = self.server.initial_camera
        init.position = tuple(view["position"])
        init.look_at = tuple(view["look_at"])
        init.up = tuple(view["up_direction"])
        init.fov = view["fov"]

    def _reset_camera(self, client: Any) -> None:
        view = viewer_view(self.session.scene.camera_at(self.session.t), self.session.orbit_centre())
        cam = client.camera
        try:
            with client.atomic():
                cam.up_direction = tuple(view["up_direction"])
                cam.position = tuple(view["position"])
                cam.look_at = tuple(view["look_at"])
                cam.fov = view["fov"]
        except AssertionError:          # the page has not reported its camera yet: it starts at the initial view
            pass
        self._request(client.client_id)

    # ================================================================ playback
    def _play_loop(self) -> None:
        period = 1.0 / self.play_fps
        last = time.perf_counter()
        while not self._closed.wait(period):
            now = time.perf_counter()
            dt, last = now - last, now
            if not self._play.value:
                continue
            t = self.session.advance(dt, loop=self._loop.value)
            self._time.value = t
            if not self._loop.value and t >= self.session.scene.duration:
                self._play.value = False

    # ================================================================ recording
    def _record(self, client: Any) -> Optional[Path]:
        fmt = self._record_format.value
        snap = self.session.snapshot()
        if client is not None:
            cam = self.client_camera(client, snap)
        else:
            cam = self.session.default_camera(16, 16)
        width, height = render_size(cam.width / cam.height, self.record_long_side)
        follow = self._follow.value or client is None
        camera = (lambda t: resize_keep_fov(snap.scene.camera_at(t), width, height)) if follow \
            else resize_keep_fov(cam, width, height)
        stamp = time.strftime("%Y%m%d-%H%M%S")
        slug = re.sub(r"[^a-z0-9]+", "-", (snap.scene.provenance.prompt or "scene").lower()).strip("-")[:40] or "scene"
        path = self.record_dir / f"{slug}-{stamp}.{fmt}"
        self._record_button.disabled = True
        try:
            self._record_status.content = "Recording ..."
            last = [0.0]

            def progress(done: int, total: int) -> None:
                now = time.perf_counter()
                if now - last[0] > 0.3 or done == total:
                    last[0] = now
                    self._record_status.content = f"Recording ... {done}/{total}"

            path = self.session.record(path, camera, progress=progress)
        except (ValueError, OSError, RuntimeError) as exc:
            self._record_status.content = f"**Error**: {md_escape(str(exc))}"
            return None
        finally:
            self._record_button.disabled = False
        self._record_status.content = f"**Wrote** {md_escape(str(path))}"
        if client is not None:
            client.send_file_download(path.name, path.read_bytes())
        return path

    def record(self, client: Any = None) -> Optional[Path]:
        """Record a video as the Record button does (from a client's view, or the scene camera)."""
        return self._record(client)
