"""What every served viewer page shares: a closed flag, context-manager use, and blocking until
Ctrl-C."""

from __future__ import annotations

import threading
from typing import Any


class ServedViewer:
    """Base of the viewers: subclasses call `super().__init__()` first and implement `close()`
    (which checks and sets `self._closed`)."""

    def __init__(self) -> None:
        self._closed = threading.Event()

    def close(self) -> None:  # pragma: no cover - every viewer implements it
        raise NotImplementedError

    def __enter__(self) -> "ServedViewer":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def serve_forever(self) -> None:
        """Block until Ctrl-C, then close."""
        try:
            while not self._closed.wait(0.5):
                pass
        except KeyboardInterrupt:
            pass
        finally:
            self.close()
