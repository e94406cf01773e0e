"""What every served viewer page shares: a guarded viser server (see `guard`), its tokened address,
a closed flag, context-manager use, and blocking until Ctrl-C."""

from __future__ import annotations

import threading
from typing import Any

from .guard import ConnectionGuard, start_guarded_viser


class ServedViewer:
    """Base of the viewers: subclasses call `super().__init__()` first, `self._serve(...)` to start
    the web server, and implement `close()` (which checks and sets `self._closed`)."""

    server: Any
    guard: ConnectionGuard

    def __init__(self) -> None:
        self._closed = threading.Event()

    def _serve(self, viser: Any, host: str, port: int, verbose: bool) -> Any:
        """Start viser on `host:port`, answering only the page of `url` (a fresh token per viewer)."""
        self.guard = ConnectionGuard(host=str(host))
        self.server = start_guarded_viser(viser, self.guard, host=host, port=int(port), verbose=verbose)
        return self.server

    @property
    def port(self) -> int:
        """The port the server listens on."""
        return self.server.get_port()

    @property
    def url(self) -> str:
        """The page's address, with this session's token in its path (the only address that works)."""
        return self.guard.url(self.server.get_host(), self.port)

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
