"""Who may talk to a served viewer: a page of the viewer's own address that holds the session's token.

viser 1.1 serves its page and its websocket on one port and takes a websocket from any
origin, so a web page open in another tab of the user's browser could connect to a running
viewer, type commands and read every frame. A `ConnectionGuard` answers HTTP 403 to a
websocket upgrade, before any message is handled, unless

* its ``Origin`` is the viewer's own page: ``http://localhost:PORT``, ``http://127.0.0.1:PORT``,
  ``http://[::1]:PORT``, the host the server was bound to, or the address the connection came
  in on (a page opened by IP from another machine when bound to 0.0.0.0), and
* its path carries the session's random token.

The page lives at ``/<token>/`` (anything else gets a 403 page that says so). viser's page
derives its websocket address from its own path, so it presents the token with no change to
viser's client; a foreign page does not know the token, and cannot make its ``Origin`` ours.

viser builds its websocket server inside ``WebsockServer._background_worker``, with no hook for
requests. `start_guarded_viser` wraps ``websockets.asyncio.server.serve``, as viser's module
calls it, for the length of one ``ViserServer(...)`` construction, putting the guard in front
of viser's own HTTP handler, and refuses to serve if the wrap did not take (another viser).
"""

from __future__ import annotations

import dataclasses
import hmac
import http
import secrets
import threading
from dataclasses import dataclass, field
from typing import Any, Callable, Optional
from urllib.parse import urlsplit

from ..errors import BackendUnavailableError

__all__ = ["ConnectionGuard", "start_guarded_viser", "SUPPORTED_VISER"]

#: viser versions whose websocket setup `start_guarded_viser` knows (pyproject pins viser<1.2)
SUPPORTED_VISER = "1.1."
_VISER_HANDLER = "viser_http_server"       # the name of viser's page handler passed to serve()
_WILDCARD_HOSTS = ("", "0.0.0.0", "::")
_LOOPBACK_HOSTS = ("localhost", "127.0.0.1", "::1")
_PATCH_LOCK = threading.Lock()

PAGE_REFUSED = ("This MorphoSim viewer is only shown at the address that `morphosim view` printed: it carries "
                "the session's token.\n")


@dataclass
class ConnectionGuard:
    """The session's token and the checks made on every request.

    Attributes:
        host: the host the server was bound to.
        token: the random secret the page's path and the websocket's path must carry.
        accepted, refused: websocket upgrades let through and turned away.
    """

    host: str = "127.0.0.1"
    token: str = field(default_factory=lambda: secrets.token_urlsafe(24))
    accepted: int = 0
    refused: int = 0

    def page_path(self) -> str:
        """The path of the viewer's page (the printed URL is the server's address + this)."""
        return f"/{self.token}/"

    def url(self, host: str, port: int) -> str:
        """The page's address on `host:port` (a wildcard bind shows as 127.0.0.1)."""
        host = "127.0.0.1" if host in _WILDCARD_HOSTS else host
        host = f"[{host}]" if ":" in host else host
        return f"http://{host}:{int(port)}{self.page_path()}"

    # ----------------------------------------------------------------- checks
    def _strip_token(self, path: str) -> Optional[str]:
        """The path below the token (``/`` for the page itself), or None if `path` lacks the token."""
        path = path.partition("?")[0]
        head, _, rest = path.lstrip("/").partition("/")
        if not hmac.compare_digest(head.encode(), self.token.encode()):
            return None
        return "/" + rest

    def allowed_hosts(self, local_host: Optional[str] = None) -> set[str]:
        """Host names a websocket's ``Origin`` may name (`local_host`: the address it came in on)."""
        hosts = set(_LOOPBACK_HOSTS)
        if self.host not in _WILDCARD_HOSTS:
            hosts.add(self.host.lower())
        if local_host:
            hosts.add(local_host.lower().removeprefix("::ffff:"))
        return hosts

    def websocket_problem(self, origins: list[str], path: str, port: int, local_host: Optional[str]) -> Optional[str]:
        """Why a websocket upgrade is refused, or None to accept it."""
        if len(origins) != 1:
            return f"expected one Origin header, found {len(origins)}"
        try:
            parts = urlsplit(origins[0].strip())
            origin_port = parts.port or 80
        except ValueError:
            parts, origin_port = None, None
        if (parts is None or parts.scheme != "http" or origin_port != int(port)
                or parts.hostname not in self.allowed_hosts(local_host) or parts.path not in ("", "/")):
            return f"origin {origins[0][:100]!r} is not this viewer's page"
        below = self._strip_token(path)
        if below not in ("/", ""):
            return "the path does not carry this session's token"
        return None

    # ------------------------------------------------------------- the hook
    def process_request(self, page_handler: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
        """A websockets ``process_request`` that checks websocket upgrades and serves the page
        (`page_handler`, viser's) only below the token."""

        def guarded(connection: Any, request: Any) -> Any:
            if request.headers.get_all("Upgrade") and "websocket" in request.headers.get_all("Upgrade")[0].lower():
                local = connection.local_address
                problem = self.websocket_problem(request.headers.get_all("Origin"), request.path,
                                                 int(local[1]), str(local[0]))
                if problem is not None:
                    self.refused += 1
                    return connection.respond(http.HTTPStatus.FORBIDDEN, f"Refused: {problem}.\n")
                self.accepted += 1
                return None
            below = self._strip_token(request.path)
            if below is None:
                return connection.respond(http.HTTPStatus.FORBIDDEN, PAGE_REFUSED)
            return page_handler(connection, dataclasses.replace(request, path=below))

        return guarded


def _check_version(viser: Any) -> None:
    version = str(getattr(viser, "__version__", "unknown"))
    if not version.startswith(SUPPORTED_VISER):
        raise BackendUnavailableError(f"The viewer guards its websocket for viser {SUPPORTED_VISER}x only, found "
                                      f"viser {version}; install it with: pip install \"viser>=1.1.1,<1.2\"")


def start_guarded_viser(viser: Any, guard: ConnectionGuard, *, host: str, port: int, verbose: bool) -> Any:
    """``viser.ViserServer(host, port, verbose)`` whose page and websocket answer only as `guard` allows.

    Raises:
        BackendUnavailableError: a viser whose websocket setup is not the one this wraps.
    """
    _check_version(viser)
    from viser.infra import _infra

    module = _infra.websockets.asyncio.server
    original = module.serve
    wrapped: list[bool] = []

    def guarded_serve(handler: Any, *args: Any, process_request: Any = None, **kwargs: Any) -> Any:
        if getattr(process_request, "__name__", None) == _VISER_HANDLER:
            process_request = guard.process_request(process_request)
            wrapped.append(True)
        return original(handler, *args, process_request=process_request, **kwargs)

    with _PATCH_LOCK:                  # viser calls serve() on its thread before the constructor returns
        module.serve = guarded_serve
        try:
            server = viser.ViserServer(host=host, port=int(port), verbose=verbose)
        finally:
            module.serve = original
    if not wrapped:
        server.stop()
        raise BackendUnavailableError(f"Could not guard the websocket of viser {viser.__version__} (its server "
                                      f"setup changed); install it with: pip install \"viser>=1.1.1,<1.2\"")
    return server
