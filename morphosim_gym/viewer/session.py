"""`ViewerSession`: what the viewer shows and how typed commands change it, without any web code.

The session owns the current scene, the time, which objects are hidden and a log of the
commands typed so far. Everything the browser can do goes through its methods, so the
behaviour (command routing, undo, visibility, error display) is tested without a browser:

    session = ViewerSession.from_source("a red ball bounces from right to left")
    session.submit("make the ball blue")      # an edit of the current scene
    session.submit("delete the giraffe")      # fails: logged with its message, scene kept
    session.submit("a bus drives down a road")  # a new scene
    session.undo()                            # back to the blue ball

All methods are thread-safe: the web layer calls them from its callback threads while a
worker thread renders frames from `snapshot()`s.
"""

from __future__ import annotations

import math
import re
import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Optional, Sequence

import numpy as np

from ..errors import CommandError
from ..scene import Camera, Scene4D

__all__ = ["ViewerSession", "LogEntry", "Snapshot", "UNDO_WORDS", "DEFAULT_MAX_UNDO", "DEFAULT_MAX_LOG",
           "resolve_source", "resize_keep_fov", "format_log",
           "md_escape"]

DEFAULT_MAX_UNDO = 32     # undo steps a session keeps (edits and replaced scenes together)
DEFAULT_MAX_LOG = 256     # typed commands it keeps in its log

# Typed commands that mean "undo" rather than a language edit.
UNDO_WORDS = ("undo", "undo that", "undo the last edit", "go back")


@dataclass(frozen=True)
class LogEntry:
    """One typed command and what became of it.

    Attributes:
        text: the command as typed.
        kind: "edit", "generate", "undo" or "error" (the command was rejected).
        ok: whether the scene changed.
        message: what happened, in words (the error message when `ok` is False).
        seconds: time spent applying it (parse + edit or generation), without rendering.
    """

    text: str
    kind: str
    ok: bool
    message: str
    seconds: float = 0.0


@dataclass(frozen=True)
class Snapshot:
    """A consistent view of the session for one frame: the scene, the time, the hidden object ids,
    and `version`, which grows whenever any of them (or the scene's content) changes."""

    scene: Scene4D
    t: float
    hidden: frozenset[int]
    version: int


def resolve_source(source: str) -> Optional[Path]:
    """The scene file a viewer source names, or None if `source` is a prompt.

    A source is a `.msim` file, or a directory holding `scene.msim` (what `morphosim generate
    --out DIR` writes); anything else is read as a prompt. A path-like source (ending in
    `.msim`) that does not exist is an error rather than a prompt.
    """
    path = Path(source).expanduser()
    if path.is_dir():
        candidate = path / "scene.msim"
        if not candidate.is_file():
            raise ValueError(f"Expected a directory with a scene.msim (from `morphosim generate --out DIR`), "
                             f"found none in {str(path)!r}")
        return candidate
    if path.is_file():
        return path
    if source.strip().lower().endswith(".msim"):
        raise ValueError(f"Expected a scene file, found no file at {source!r}")
    return None


class ViewerSession:
    """The state behind the viewer.

    Args:
        scene: the first scene shown.
        sim: the `MorphoSim` that edits scenes and generates new ones; default
            `MorphoSim(reconstruction="oracle")` (instant scenes from the generator's ground truth).
        seed: seed of scenes generated from typed prompts.
        max_undo: undo steps kept, edits and replaced scenes together (older ones are forgotten:
            the scene `max_undo` steps back loses its parent), so memory stays bounded however
            long the session runs.
        max_log: commands kept in `log` (the newest).
    """

    def __init__(self, scene: Scene4D, sim: Any = None, seed: int = 0, max_undo: int = DEFAULT_MAX_UNDO,
                 max_log: int = DEFAULT_MAX_LOG) -> None:
        if not isinstance(scene, Scene4D):
            raise ValueError(f"Expected a Scene4D, found {type(scene).__name__}")
        for name, value in (("max_undo", max_undo), ("max_log", max_log)):
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 10_000:
                raise ValueError(f"Expected {name} as an integer in [1, 10000], found {value!r}")
        self.max_undo = max_undo
        if sim is None:
            from ..pipeline import MorphoSim

            sim = MorphoSim(reconstruction="oracle")
        self.sim = sim
        self.seed = int(seed)
        self._lock = threading.RLock()
        self._render_lock = threading.Lock()
        self._scene = scene
        self._t = 0.0
        self._hidden: frozenset[int] = frozenset()
        self._version = 0
        self._log: deque[LogEntry] = deque(maxlen=max_log)
        self._replaced: list[Scene4D] = []       # scenes replaced by generate commands, for undo
        self._listeners: list[Callable[[str], None]] = []
        self._trim_undo()

    @classmethod
    def from_source(cls, source: str, sim: Any = None, seed: int = 0, **limits: int) -> "ViewerSession":
        """A session on a scene file (`.msim`, or a `morphosim generate` output directory), or on
        the scene generated from a prompt; `limits`: `max_undo`, `max_log`."""
        if not isinstance(source, str) or not source.strip():
            raise ValueError(f"Expected a scene file or a prompt, found {source!r}")
        path = resolve_source(source)
        if sim is None:
            from ..pipeline import MorphoSim

            sim = MorphoSim(reconstruction="oracle")
        if path is not None:
            from ..scene import load_scene

            return cls(load_scene(path), sim, seed, **limits)
        return cls(sim.generate(source, seed=int(seed)), sim, seed, **limits)

    # ------------------------------------------------------------------ state
    @property
    def scene(self) -> Scene4D:
        """The scene shown now."""
        return self._scene

    @property
    def t(self) -> float:
        """The time shown, seconds in [0, scene.duration]."""
        return self._t

    @property
    def hidden(self) -> frozenset[int]:
        """Ids of the objects not drawn."""
        return self._hidden

    @property
    def version(self) -> int:
        """Grows with every change of scene, time or visibility."""
        return self._version

    @property
    def log(self) -> tuple[LogEntry, ...]:
        """The commands typed so far (the newest `max_log`), in order."""
        with self._lock:
            return tuple(self._log)

    @property
    def last_error(self) -> Optional[str]:
        """The message of the last command if it failed, else None."""
        with self._lock:
            if self._log and not self._log[-1].ok:
                return self._log[-1].message
            return None

    @property
    def can_undo(self) -> bool:
        """Whether `undo()` has something to go back to."""
        with self._lock:
            return self._scene.parent is not None or bool(self._replaced)

    @property
    def history(self) -> tuple[str, ...]:
        """The edits of the current scene since it was generated (`scene.history`)."""
        return self._scene.history

    def snapshot(self) -> Snapshot:
        """Scene, time, hidden ids and version, read together."""
        with self._lock:
            return Snapshot(self._scene, self._t, self._hidden, self._version)

    def on_change(self, listener: Callable[[str], None]) -> Callable[[str], None]:
        """Call `listener(what)` after each change; `what` is "scene", "time" or "visibility".
        Listeners run on the thread that made the change, outside the session's lock."""
        self._listeners.append(listener)
        return listener

    def _changed(self, what: str) -> None:
        for listener in list(self._listeners):
            listener(what)

    # --------------------------------------------------------------- commands
    def submit(self, text: str) -> LogEntry:
        """Apply a typed command: an edit changes the current scene, a scene description generates
        a new one, "undo" undoes. A command that fails is logged with its message and leaves the
        scene as it was; it never raises for bad text."""
        if not isinstance(text, str) or not text.strip():
            return self._record(LogEntry(str(text), "error", False,
                                         "Expected a command (an edit such as 'make the ball blue', or a scene "
                                         "to generate), found empty text"))
        text = text.strip()
        if text.lower().rstrip(".!") in UNDO_WORDS:
            return self.undo(text)
        start = time.perf_counter()
        with self._lock:
            scene = self._scene
        try:
            plan = self.sim.parse(text, scene=scene)
            if plan.mode == "edit":
                new, kind = self.sim.edit(scene, text), "edit"
            else:
                new, kind = self.sim.generate(text, seed=self.seed), "generate"
        except (ValueError, RuntimeError) as exc:   # CommandError, EditError, BackendUnavailableError...
            message = str(exc) or type(exc).__name__
            return self._record(LogEntry(text, "error", False, message, time.perf_counter() - start))
        seconds = time.perf_counter() - start
        with self._lock:
            if self._scene is not scene:      # another command (or undo) changed the scene meanwhile
                return self._record(LogEntry(text, "error", False,
                                             "The scene changed while this command ran; type it again"))
            if kind == "generate":
                self._replaced.append(scene)
                self._hidden = frozenset()
                self._t = 0.0
            self._set_scene(new)
            self._trim_undo()
            entry = self._record(LogEntry(text, kind, True, _describe(kind, seconds, new), seconds), notify=False)
        self._changed("scene")
        return entry

    def undo(self, text: str = "undo") -> LogEntry:
        """Go back to the scene before the last edit (or, after a generated scene, to the scene it
        replaced). With nothing to undo, the log says so and the scene stays."""
        with self._lock:
            if self._scene.parent is not None:
                undone = self._scene.history[-1] if self._scene.history else "the last edit"
                self._set_scene(self._scene.undo())
                message = f"undid '{undone}'"
            elif self._replaced:
                self._set_scene(self._replaced.pop())
                self._hidden = frozenset()
                message = "back to the previous scene"
            else:
                return self._record(LogEntry(text, "error", False, "Nothing to undo: this scene has no edits"))
            entry = self._record(LogEntry(text, "undo", True, message), notify=False)
        self._changed("scene")
        return entry

    def _set_scene(self, scene: Scene4D) -> None:
        self._scene = scene
        ids = {o.id for o in scene.objects}
        self._hidden = frozenset(i for i in self._hidden if i in ids)
        self._t = min(self._t, scene.duration)
        self._version += 1

    def _trim_undo(self) -> None:
        """Keep at most `max_undo` undo steps: the current scene's edits first, then the replaced
        scenes, newest first (each one step plus its own edits)."""
        budget = self.max_undo - _cut_history(self._scene, self.max_undo)
        kept: list[Scene4D] = []
        for scene in reversed(self._replaced):
            if budget <= 0:
                break
            budget -= 1 + _cut_history(scene, budget - 1)
            kept.append(scene)
        self._replaced = kept[::-1]

    @property
    def undo_depth(self) -> int:
        """Undo steps available now (at most `max_undo`)."""
        with self._lock:
            return sum(1 + _history_depth(s) for s in self._replaced) + _history_depth(self._scene)

    def _record(self, entry: LogEntry, notify: bool = True) -> LogEntry:
        with self._lock:
            self._log.append(entry)
        if notify and not entry.ok:
            self._changed("error")
        return entry

    # ------------------------------------------------------------ time, objects
    def set_time(self, t: float) -> float:
        """Show time `t` (clamped to the clip); returns the time set."""
        t = float(t)
        if not math.isfinite(t):
            raise ValueError(f"Expected a finite time in seconds, found {t}")
        with self._lock:
            t = min(max(t, 0.0), self._scene.duration)
            if t == self._t:
                return t
            self._t = t
            self._version += 1
        self._changed("time")
        return t

    def advance(self, dt: float, loop: bool = True) -> float:
        """Move time forward by `dt` seconds (for playback), wrapping to 0 at the end when `loop`,
        else stopping there; returns the new time."""
        with self._lock:
            d = self._scene.duration
            t = self._t + float(dt)
            if d <= 0:
                t = 0.0
            elif t > d:
                t = (t % d) if loop else d
        return self.set_time(t)

    def set_visible(self, object_id: int, visible: bool) -> None:
        """Show or hide an object of the current scene (`ValueError` for an unknown id)."""
        with self._lock:
            ids = {o.id for o in self._scene.objects}
            if object_id not in ids:
                raise ValueError(f"Expected an object id of the scene {sorted(ids)}, found {object_id!r}")
            hidden = set(self._hidden)
            (hidden.discard if visible else hidden.add)(int(object_id))
            if frozenset(hidden) == self._hidden:
                return
            self._hidden = frozenset(hidden)
            self._version += 1
        self._changed("visibility")

    def is_visible(self, object_id: int) -> bool:
        """Whether an object is drawn."""
        return object_id not in self._hidden

    # --------------------------------------------------------------- cameras
    def default_camera(self, width: int, height: int) -> Camera:
        """The scene's generation camera at the current time, at this size (same vertical field of view)."""
        snap = self.snapshot()
        cam = snap.scene.camera_at(snap.t)
        return resize_keep_fov(cam, width, height)

    def orbit_centre(self) -> np.ndarray:
        """[3] where the generation camera looks (a good point to orbit about)."""
        return self._scene.centre()

    # --------------------------------------------------------------- rendering
    def render(self, camera: Camera, snapshot: Optional[Snapshot] = None) -> np.ndarray:
        """[H, W, 3] uint8 frame of a snapshot (default: now) from `camera`, hidden objects left out."""
        snap = snapshot or self.snapshot()
        from ..render import render

        with self._render_lock:        # scenes cache their posed Gaussians: one renderer at a time
            if not snap.hidden:
                out = render(snap.scene, camera, snap.t)
            else:
                g = snap.scene.at(snap.t)
                keep = ~np.isin(g.object_ids, np.fromiter(snap.hidden, dtype=np.int64))
                out = render(g.subset(keep), camera, background=snap.scene.background)
        return out.rgb_uint8()

    def record(self, path: str | Path, camera: Camera | Callable[[float], Camera], fps: Optional[float] = None,
               num_frames: Optional[int] = None, progress: Optional[Callable[[int, int], None]] = None) -> Path:
        """Write a video (.mp4 or .gif) of the whole clip as shown now (hidden objects left out).

        Args:
            path: where to write it.
            camera: a fixed `Camera`, or a function of time giving one (e.g. the scene's camera path).
            fps: frames per second (default the scene's).
            num_frames: frames to write (default one per scene frame).
            progress: called with (frames done, total) after each frame.
        """
        from ..generate.cli import write_video

        snap = self.snapshot()
        fps = float(fps or snap.scene.fps)
        n = int(num_frames or snap.scene.num_frames)
        if n < 1:
            raise ValueError(f"Expected num_frames >= 1, found {n}")
        frames = []
        for i in range(n):
            t = snap.scene.duration * i / max(n - 1, 1)
            cam = camera(t) if callable(camera) else camera
            frames.append(self.render(cam, Snapshot(snap.scene, t, snap.hidden, snap.version)))
            if progress is not None:
                progress(i + 1, n)
        return write_video(frames, Path(path), fps)

    # --------------------------------------------------------------- warm-up
    def warm_up(self, camera: Optional[Camera] = None) -> float:
        """Compile the renderer and load the parser's models before the first user command, so
        that the first edit is as fast as the next ones; returns the seconds it took."""
        start = time.perf_counter()
        self.render(camera or self.default_camera(64, 64))
        # an unknown noun loads the text-embedding model that grounds nouns (seconds, once)
        for text in ("make the zebra blue", "a ball"):
            try:
                self.sim.parse(text, scene=self._scene)
            except CommandError:
                pass
        return time.perf_counter() - start


def _history_depth(scene: Scene4D) -> int:
    """How many times `scene` can be undone."""
    depth = 0
    while scene.parent is not None:
        scene, depth = scene.parent, depth + 1
    return depth


def _cut_history(scene: Scene4D, depth: int) -> int:
    """Forget the edits of `scene` older than `depth` steps (the scene `depth` edits back loses its
    parent, so the older scenes can be freed); returns the steps kept."""
    for kept in range(max(depth, 0)):
        if scene.parent is None:
            return kept
        scene = scene.parent
    scene.parent = None
    return max(depth, 0)


def resize_keep_fov(camera: Camera, width: int, height: int) -> Camera:
    """`camera` at another size and aspect ratio with the same vertical field of view and pose."""
    fx, fy, cx, cy = Camera.intrinsics_from_fov(width, height, camera.fov_y_deg)
    return Camera(width, height, fx, fy, cx, cy, camera.world_to_camera, camera.near)


def _describe(kind: str, seconds: float, scene: Scene4D) -> str:
    if kind == "generate":
        return f"new scene: {', '.join(scene.object_names)} ({scene.duration:g} s), made in {seconds:.2f} s"
    return f"edited in {1000 * seconds:.0f} ms"


def md_escape(text: str) -> str:
    """Text shown literally in markdown."""
    return re.sub(r"([\\`*_{}\[\]<>()#+\-!|~])", r"\\\1", str(text))


def format_log(entries: Sequence[LogEntry], limit: int = 8) -> str:
    """The last `limit` log entries as markdown lines (newest last)."""
    lines = []
    for e in list(entries)[-limit:]:
        mark = "ok" if e.ok else "**error**"
        lines.append(f"- {mark}: {md_escape(e.text)} - {md_escape(e.message)}")
    return "\n".join(lines)
