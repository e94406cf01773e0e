"""`FrameWorker`: one background thread that runs render jobs, coalescing bursts.

The web server's callbacks (camera moves, slider drags, edits) only *request* a frame: they
hand the worker a job under a key (one key per browser client) and return at once, so the
websocket loop never waits for a render. While a job waits, a newer request with the same
key replaces it, so a burst of camera moves costs one render of the latest pose rather than
one per move.
"""

from __future__ import annotations

import logging
import threading
import traceback
from collections import OrderedDict
from typing import Callable, Hashable, Optional

__all__ = ["FrameWorker"]

_log = logging.getLogger(__name__)


class FrameWorker:
    """Runs jobs on one thread, in request order, keeping only the newest pending job per key.

    Args:
        name: the thread's name.
        on_error: called with (key, exception) when a job raises (default: log it); the worker
            keeps running.
    """

    def __init__(self, name: str = "morphosim-viewer-frames",
                 on_error: Optional[Callable[[Hashable, BaseException], None]] = None) -> None:
        self._pending: "OrderedDict[Hashable, Callable[[], None]]" = OrderedDict()
        self._cond = threading.Condition()
        self._stop = False
        self._busy = False
        self._on_error = on_error
        self.requested = 0      # requests received
        self.completed = 0      # jobs run (requests - completed - pending = coalesced away)
        self.failed = 0
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def request(self, key: Hashable, job: Callable[[], None]) -> None:
        """Queue `job` under `key`, replacing a job with the same key that has not started yet."""
        with self._cond:
            if self._stop:
                return
            self.requested += 1
            self._pending[key] = job          # a replaced job keeps its place in the queue
            self._cond.notify()

    def discard(self, key: Hashable) -> None:
        """Drop the pending job of `key`, if any (e.g. its client left)."""
        with self._cond:
            self._pending.pop(key, None)

    @property
    def coalesced(self) -> int:
        """Requests replaced by a newer one before they ran."""
        with self._cond:
            return self.requested - self.completed - self.failed - len(self._pending) - int(self._busy)

    def wait_idle(self, timeout: float = 10.0) -> bool:
        """Block until no job is pending or running; False on timeout."""
        with self._cond:
            return self._cond.wait_for(lambda: not self._pending and not self._busy, timeout)

    def stop(self, timeout: float = 5.0) -> None:
        """Finish the running job, drop pending ones and end the thread."""
        with self._cond:
            self._stop = True
            self._pending.clear()
            self._cond.notify_all()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)

    @property
    def alive(self) -> bool:
        """Whether the thread runs."""
        return self._thread.is_alive()

    def _run(self) -> None:
        while True:
            with self._cond:
                self._cond.wait_for(lambda: self._pending or self._stop)
                if self._stop:
                    self._cond.notify_all()
                    return
                key, job = self._pending.popitem(last=False)
                self._busy = True
            try:
                job()
            except BaseException as exc:  # a failed frame must not end the viewer
                with self._cond:
                    self.failed += 1
                if self._on_error is not None:
                    try:
                        self._on_error(key, exc)
                    except Exception:
                        _log.error("viewer: error handler failed:\n%s", traceback.format_exc())
                else:
                    _log.error("viewer: frame job %r failed:\n%s", key, traceback.format_exc())
            else:
                with self._cond:
                    self.completed += 1
            finally:
                with self._cond:
                    self._busy = False
                    self._cond.notify_all()
