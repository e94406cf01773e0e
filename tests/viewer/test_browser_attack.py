"""In headless Chromium: a page of another origin (another local port, as any site would be) tries
to open the viewer's websocket, with and without the token, and is refused; the viewer's own page
still connects."""

import http.server
import json
import threading

import pytest

from morphosim_gym.errors import BackendUnavailableError
from morphosim_gym.viewer import ViewerSession

pytestmark = pytest.mark.slow

ATTACK = """<!doctype html><html><body><script>
const results = {};
function attempt(name, url) {
  const ws = new WebSocket(url, ["%(protocol)s"]);
  ws.onopen = () => { results[name] = "open"; ws.send("x"); finish(); };
  ws.onerror = () => { results[name] = results[name] || "refused"; finish(); };
}
function finish() { if (Object.keys(results).length === 2) document.title = JSON.stringify(results); }
attempt("no token", "ws://127.0.0.1:%(port)d/");
attempt("leaked token", "ws://127.0.0.1:%(port)d/%(token)s");
</script></body></html>"""


def test_a_foreign_page_cannot_connect(small_sim, ball_scene, tmp_path):
    import viser

    from morphosim_gym.viewer.app import SceneViewer
    from morphosim_gym.viewer.testing import find_chromium, headless_chromium, wait_for

    try:
        find_chromium()
        import selenium  # noqa: F401
    except (BackendUnavailableError, ImportError) as exc:
        pytest.skip(f"no headless browser here: {exc}")
    viewer = SceneViewer(ViewerSession(ball_scene, sim=small_sim), port=0, verbose=False, record_dir=tmp_path)
    page = (ATTACK % {"protocol": f"viser-v{viser.__version__}", "port": viewer.port,
                      "token": viewer.guard.token}).encode()

    class Attacker(http.server.BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(page)))
            self.end_headers()
            self.wfile.write(page)

        def log_message(self, *args):
            pass

    site = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Attacker)
    threading.Thread(target=site.serve_forever, daemon=True).start()
    try:
        with headless_chromium(800, 600) as driver:
            driver.get(f"http://127.0.0.1:{site.server_address[1]}/")
            title = wait_for(lambda: driver.title.startswith("{") and driver.title, 20, message="the attack to end")
            assert json.loads(title) == {"no token": "refused", "leaked token": "refused"}
            assert viewer.guard.refused == 2 and viewer.server.get_clients() == {}
            driver.get(viewer.url)                       # the viewer's own page still works
            wait_for(lambda: viewer.server.get_clients(), 30, message="the page to connect")
            assert viewer.guard.accepted >= 1
    finally:
        site.shutdown()
        viewer.close()
    assert viewer.session.log == ()
