"""A JSON-over-HTTP POST that a broken or hostile endpoint cannot stall, flood or crash.

Used by the LLM backend (`llm.chat`). Standard library only (urllib, so proxies from the
environment, redirects and HTTPS work as before).

* One wall-clock `Deadline` covers everything: connecting, sending, the status line, every
  header and body read, and (when the caller shares it) the retries. A socket timeout bounds
  each read only, so a reply trickled one byte at a time would never time out; a watchdog
  thread therefore shuts the request's sockets down when the deadline passes.
* A reply larger than `max_bytes` is refused, from its ``Content-Length`` before reading, or
  as soon as that many bytes have arrived; a reply shorter than its ``Content-Length`` is refused.
* `loads_bounded` parses JSON with bounded nesting, integer length and finite numbers only.

Every failure raises `EndpointError` (a `BackendUnavailableError`) naming what went wrong.
"""

from __future__ import annotations

import http.client
import json
import socket
import threading
import time
import urllib.error
import urllib.request
from typing import Any, Callable, Optional

from ..errors import BackendUnavailableError

__all__ = ["Deadline", "EndpointError", "post_json", "loads_bounded", "MAX_REPLY_BYTES", "MAX_JSON_DEPTH",
           "MAX_INT_DIGITS"]

MAX_REPLY_BYTES = 1 << 20      # 1 MiB: a plan is a few kB
MAX_JSON_DEPTH = 64
MAX_INT_DIGITS = 30
_READ_CHUNK = 1 << 16


class EndpointError(BackendUnavailableError):
    """The endpoint could not be used: unreachable, too slow, an HTTP error, or a malformed reply."""


class Deadline:
    """A wall-clock limit of `seconds` from now, shared by every step of a request (and its retries)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = float(seconds)
        self.end = time.monotonic() + self.seconds

    def remaining(self) -> float:
        """Seconds left (negative once passed)."""
        return self.end - time.monotonic()

    @property
    def expired(self) -> bool:
        """Whether the deadline has passed."""
        return self.remaining() <= 0


class _Watchdog:
    """Shuts down every socket opened for one request once the deadline passes, which ends any
    read or write blocked on it."""

    def __init__(self, deadline: Deadline) -> None:
        self.fired = False
        self._sockets: list[socket.socket] = []
        self._lock = threading.Lock()
        self._timer = threading.Timer(max(deadline.remaining(), 0.0), self._fire)
        self._timer.daemon = True
        self._timer.start()

    def track(self, sock: socket.socket) -> socket.socket:
        with self._lock:
            self._sockets.append(sock)
            fired = self.fired
        if fired:
            _shutdown(sock)
        return sock

    def _fire(self) -> None:
        with self._lock:
            self.fired = True
            sockets = list(self._sockets)
        for sock in sockets:
            _shutdown(sock)

    def cancel(self) -> None:
        self._timer.cancel()


def _shutdown(sock: socket.socket) -> None:
    try:
        socket.socket.shutdown(sock, socket.SHUT_RDWR)
    except (OSError, ValueError):      # already closed, or detached into a TLS socket
        pass


def _watched(base: type, watchdog: _Watchdog) -> Callable[..., http.client.HTTPConnection]:
    """An `http.client` connection class whose sockets (plain and TLS) the watchdog can shut down."""

    class Watched(base):  # type: ignore[misc, valid-type]
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            create = self._create_connection
            self._create_connection = lambda *a, **k: watchdog.track(create(*a, **k))

        def connect(self) -> None:
            super().connect()
            watchdog.track(self.sock)

    return Watched


class _HTTPHandler(urllib.request.HTTPHandler):
    def __init__(self, watchdog: _Watchdog) -> None:
        super().__init__()
        self._watchdog = watchdog

    def do_open(self, http_class: Any, req: Any, **kwargs: Any) -> Any:
        return super().do_open(_watched(http_class, self._watchdog), req, **kwargs)


class _HTTPSHandler(urllib.request.HTTPSHandler):
    def __init__(self, watchdog: _Watchdog) -> None:
        super().__init__()
        self._watchdog = watchdog

    def do_open(self, http_class: Any, req: Any, **kwargs: Any) -> Any:
        return super().do_open(_watched(http_class, self._watchdog), req, **kwargs)


def _read_capped(resp: Any, max_bytes: int, url: str) -> bytes:
    """The whole body, refusing more than `max_bytes` or fewer than its Content-Length."""
    header = resp.headers.get("Content-Length")
    expected: Optional[int] = None
    if header is not None:
        if not header.strip().isdigit() or len(header.strip()) > 18:
            raise EndpointError(f"LLM endpoint {url} answered a Content-Length of {header[:40]!r}")
        expected = int(header)
        if expected > max_bytes:
            raise EndpointError(f"LLM endpoint {url} answered {expected} bytes, more than the {max_bytes} allowed")
    chunks, total = [], 0
    while True:
        chunk = resp.read1(_READ_CHUNK)
        if not chunk:
            break
        total += len(chunk)
        if total > max_bytes:
            raise EndpointError(f"LLM endpoint {url} answered more than the {max_bytes} bytes allowed")
        chunks.append(chunk)
    if expected is not None and total != expected:
        raise EndpointError(f"LLM endpoint {url} sent {total} of the {expected} bytes it announced")
    return b"".join(chunks)


def post_json(url: str, payload: Any, headers: dict[str, str], deadline: Deadline,
              max_bytes: int = MAX_REPLY_BYTES) -> Any:
    """POST `payload` as JSON to `url` and return the JSON reply, all within `deadline`.

    Raises:
        EndpointError: no complete, well-formed reply in time (the message says what went wrong).
    """
    if deadline.expired:
        raise EndpointError(f"LLM endpoint {url} was not asked: the {deadline.seconds:g} s allowed had passed")
    body = json.dumps(payload).encode("utf-8")
    request = urllib.request.Request(url, data=body, headers={**headers, "Content-Type": "application/json"},
                                     method="POST")
    watchdog = _Watchdog(deadline)
    opener = urllib.request.build_opener(_HTTPHandler(watchdog), _HTTPSHandler(watchdog))
    try:
        with opener.open(request, timeout=max(deadline.remaining(), 0.001)) as resp:
            raw = _read_capped(resp, max_bytes, url)
    except urllib.error.HTTPError as exc:
        exc.close()
        raise EndpointError(f"LLM endpoint {url} answered HTTP {exc.code}") from None
    except (EndpointError, OSError, http.client.HTTPException, ValueError) as exc:
        raise _transport_error(exc, url, deadline.seconds, watchdog.fired or deadline.expired) from None
    finally:
        watchdog.cancel()
    if watchdog.fired:            # the body ended because the watchdog shut the socket
        raise EndpointError(f"LLM endpoint {url} gave no complete reply within {deadline.seconds:g} s")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise EndpointError(f"LLM endpoint {url} answered bytes that are not UTF-8 text") from None
    try:
        return loads_bounded(text)
    except ValueError as exc:
        raise EndpointError(f"LLM endpoint {url} did not answer usable JSON ({exc})") from None


def _transport_error(exc: Exception, url: str, seconds: float, late: bool) -> EndpointError:
    """What a failure while talking to the endpoint means (`late`: the deadline passed meanwhile,
    and a read it cut off shows up as any of these)."""
    if late:
        return EndpointError(f"LLM endpoint {url} gave no complete reply within {seconds:g} s")
    if isinstance(exc, EndpointError):
        return exc
    if isinstance(exc, http.client.HTTPException) and not isinstance(exc, OSError):
        return EndpointError(f"LLM endpoint {url} did not answer HTTP ({_short(exc)})")
    return EndpointError(f"LLM endpoint {url} is unreachable ({_short(exc)})")


def _short(exc: BaseException, limit: int = 200) -> str:
    text = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
    return text if len(text) <= limit else text[:limit] + "..."


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


def _bounded_int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise ValueError(f"an integer of {len(text.lstrip('-'))} digits (at most {MAX_INT_DIGITS})")
    return int(text)


def _finite_float(text: str) -> float:
    value = float(text)
    if value in (float("inf"), float("-inf")):
        raise ValueError(f"the number {text[:40]} is out of range")
    return value


def _depth(value: Any) -> int:
    """Nesting depth of parsed JSON, without recursion."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, (dict, list)):
            deepest = max(deepest, depth)
            stack.extend((v, depth + 1) for v in (item.values() if isinstance(item, dict) else item))
    return deepest


def loads_bounded(text: str) -> Any:
    """`json.loads` with at most `MAX_JSON_DEPTH` levels of nesting, integers of at most
    `MAX_INT_DIGITS` digits and finite numbers only; `ValueError` naming what was refused.
    (The C parser's own recursion limit stops very deep input first, as a `RecursionError`.)"""
    try:
        value = json.loads(text, parse_int=_bounded_int, parse_float=_finite_float, parse_constant=_refuse_constant)
    except RecursionError:
        raise ValueError(f"nested deeper than {MAX_JSON_DEPTH} levels") from None
    if _depth(value) > MAX_JSON_DEPTH:
        raise ValueError(f"nested deeper than {MAX_JSON_DEPTH} levels")
    return value
