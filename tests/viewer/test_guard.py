"""The viewer refuses websockets from other web pages and without the session's token (raw
websockets from this test, as a hostile page open in the user's browser would send them)."""

import urllib.error
import urllib.request
from urllib.parse import urlsplit

import pytest

from morphosim_gym.viewer import ViewerSession
from morphosim_gym.viewer.guard import ConnectionGuard

pytest.importorskip("viser")
websockets_sync = pytest.importorskip("websockets.sync.client")


@pytest.fixture(scope="module")
def served(small_sim, ball_scene, tmp_path_factory):
    from morphosim_gym.viewer.app import SceneViewer

    connected = []
    v = SceneViewer(ViewerSession(ball_scene, sim=small_sim), port=0, verbose=False,
                    record_dir=tmp_path_factory.mktemp("rec"))
    v.server.on_client_connect(lambda client: connected.append(client.client_id))
    yield v, connected
    v.close()


def _protocol():
    import viser

    return f"viser-v{viser.__version__}"


def _open(url, origin):
    return websockets_sync.connect(url, origin=origin, subprotocols=[_protocol()], open_timeout=10)


def _status_of_refusal(url, origin):
    from websockets.exceptions import InvalidStatus

    with pytest.raises(InvalidStatus) as info:
        with _open(url, origin):
            pass
    return info.value.response.status_code


def test_foreign_origins_and_missing_tokens_are_refused(served):
    viewer, connected = served
    port = viewer.port
    token = viewer.guard.token
    good_ws = f"ws://127.0.0.1:{port}/{token}"
    guessed = token[:-1] + ("y" if token.endswith("x") else "x")     # one character off (never the token)
    attacks = [
        (f"ws://127.0.0.1:{port}", "https://evil.example"),          # another site, no token
        (f"ws://127.0.0.1:{port}", f"http://127.0.0.1:{port}"),      # our page's origin, no token (iframe)
        (f"ws://127.0.0.1:{port}/{token}", "https://evil.example"),  # the token leaked, another site
        (f"ws://127.0.0.1:{port}/{token}", f"http://evil.example:{port}"),   # DNS rebinding
        (f"ws://127.0.0.1:{port}/{token}", f"http://127.0.0.1:{port + 1}"),  # another local port
        (f"ws://127.0.0.1:{port}/{token}", "null"),                  # a sandboxed frame or a file:// page
        (f"ws://127.0.0.1:{port}/{guessed}", f"http://127.0.0.1:{port}"),   # a guessed token
        (f"ws://127.0.0.1:{port}/?token={token}", f"http://localhost:{port}"),  # token not in the path
        (good_ws, None),                                              # no Origin at all
    ]
    for url, origin in attacks:
        assert _status_of_refusal(url, origin) == 403, (url, origin)
    assert connected == [] and viewer.server.get_clients() == {}
    assert viewer.guard.refused == len(attacks) and viewer.guard.accepted == 0
    assert viewer.session.log == ()


def test_the_page_origin_with_the_token_is_accepted(served):
    viewer, _ = served
    port, token = viewer.port, viewer.guard.token
    for origin in (f"http://127.0.0.1:{port}", f"http://localhost:{port}"):
        with _open(f"ws://127.0.0.1:{port}/{token}", origin) as ws:
            first = ws.recv(timeout=10)                           # the panels' state streams in
            assert isinstance(first, bytes) and len(first) > 1000
    assert viewer.guard.accepted == 2


def test_the_page_is_served_only_below_the_token(served):
    viewer, _ = served
    url = viewer.url
    parts = urlsplit(url)
    assert parts.path == f"/{viewer.guard.token}/" and len(viewer.guard.token) >= 32
    page = urllib.request.urlopen(url, timeout=10).read().decode()
    assert "<html" in page.lower()
    for path in ("/", "/index.html", f"/{viewer.guard.token[:-2]}/"):
        with pytest.raises(urllib.error.HTTPError) as info:
            urllib.request.urlopen(f"http://127.0.0.1:{viewer.port}{path}", timeout=10)
        assert info.value.code == 403 and b"printed" in info.value.read()


def test_every_viewer_gets_its_own_token():
    a, b = ConnectionGuard(), ConnectionGuard()
    assert a.token != b.token
    assert a.url("0.0.0.0", 8080) == f"http://127.0.0.1:8080/{a.token}/"
    # bound to every interface: a page opened by the machine's address is its own origin, a name is not
    g = ConnectionGuard(host="0.0.0.0")
    assert g.websocket_problem(["http://192.168.1.5:8080"], f"/{g.token}", 8080, "192.168.1.5") is None
    assert g.websocket_problem(["http://attacker.example:8080"], f"/{g.token}", 8080, "192.168.1.5")


def test_an_unknown_viser_is_refused(monkeypatch):
    import viser

    from morphosim_gym.errors import BackendUnavailableError
    from morphosim_gym.viewer.guard import start_guarded_viser

    monkeypatch.setattr(viser, "__version__", "2.0.0")
    with pytest.raises(BackendUnavailableError, match="viser 2.0.0"):
        start_guarded_viser(viser, ConnectionGuard(), host="127.0.0.1", port=0, verbose=False)
