"""Viewer latency: from a typed edit to the updated image, for a ~50k-Gaussian scene.

Two clocks, both per edit:
  server: the command's text arrives at the server -> the new frame is handed to the websocket
          (parse + edit + render + JPEG encode + send);
  page:   Enter pressed in headless Chromium -> the page has received the new frame (the latency
          line sent right after the frame has appeared in its DOM; includes the page's 50 ms
          input throttle and the websocket round trip).

    python benchmarks/viewer.py                       # table + JSON (out/bench/viewer.json)
    python benchmarks/viewer.py --no-browser          # server clock only, frames to a stand-in client

Prints the machine's load average next to the numbers (other jobs share this machine).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

EDITS = ("make the bus yellow", "make the bus red", "reverse its motion", "make it twice as fast",
         "move the bus to the right", "make the bus green", "delete the bus", "undo")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--prompt", default="a red bus drives from left to right on a street")
    ap.add_argument("--detail", type=float, default=4.1, help="Gaussian budget multiplier (4.1: ~50k Gaussians)")
    ap.add_argument("--rounds", type=int, default=3, help="passes over the edit list")
    ap.add_argument("--resolution", type=int, default=512, help="longer side of streamed frames")
    ap.add_argument("--window", default="1280x800", help="browser window size")
    ap.add_argument("--no-browser", action="store_true")
    ap.add_argument("--out", default="out/bench/viewer.json")
    args = ap.parse_args()

    import morphosim_gym as ms
    from morphosim_gym.viewer import ViewerSession
    from morphosim_gym.viewer.app import SceneViewer

    sim = ms.MorphoSim(reconstruction="oracle", generation=ms.GenerationConfig(detail=args.detail))
    session = ViewerSession.from_source(args.prompt, sim=sim)
    warm = session.warm_up()
    n = len(session.scene.gaussians)
    print(f"scene: {session.scene.object_names}, {n} Gaussians; warm-up {warm:.1f} s")
    viewer = SceneViewer(session, port=0, verbose=False, long_side=args.resolution)
    rows = []
    try:
        if args.no_browser:
            rows = _server_only(viewer, args)
        else:
            rows = _with_browser(viewer, args)
    finally:
        viewer.close()

    server = [r["server_ms"] for r in rows]
    page = [r["page_ms"] for r in rows if r.get("page_ms") is not None]
    render = [r["render_ms"] for r in rows]
    edit = [r["edit_ms"] for r in rows]
    print(f"\n{'edit':32s} {'edit ms':>8s} {'render ms':>9s} {'server ms':>9s} {'page ms':>8s} "
          f"{'to server':>9s} {'to page':>8s}")
    for r in rows:
        extra = [r.get(k) for k in ("page_ms", "page_to_server_ms", "server_to_page_ms")]
        cols = " ".join(f"{v:8.1f}" if v is not None else f"{'-':>8s}" for v in extra)
        print(f"{r['text']:32s} {r['edit_ms']:8.1f} {r['render_ms']:9.1f} {r['server_ms']:9.1f} {cols}")

    def stats(xs):
        return {"median": round(statistics.median(xs), 1), "p90": round(sorted(xs)[int(0.9 * (len(xs) - 1))], 1),
                "max": round(max(xs), 1)} if xs else None

    to_server = [r["page_to_server_ms"] for r in rows if "page_to_server_ms" in r]
    to_page = [r["server_to_page_ms"] for r in rows if "server_to_page_ms" in r]
    summary = {"gaussians": n, "frame_size": rows[0]["size"] if rows else None, "edits": len(rows),
               "edit_ms": stats(edit), "render_ms": stats(render), "server_ms": stats(server), "page_ms": stats(page),
               "page_to_server_ms": stats(to_server), "server_to_page_ms": stats(to_page),
               "load_average": os.getloadavg(), "cpus": os.cpu_count(), "rows": rows}
    print(f"\nmedian (p90, max) over {len(rows)} edits, {n} Gaussians, frames {summary['frame_size']}:")
    for key in ("edit_ms", "render_ms", "server_ms", "page_ms", "page_to_server_ms", "server_to_page_ms"):
        if summary[key]:
            s = summary[key]
            print(f"  {key:10s} {s['median']:7.1f}  ({s['p90']:.1f}, {s['max']:.1f})")
    print(f"  load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(summary, indent=2))
    print(f"wrote {out}")
    return 0


def _server_only(viewer, args) -> list[dict]:
    """Frames go to a stand-in client object (what viser's ClientHandle offers the viewer)."""
    import numpy as np

    from morphosim_gym.viewer.camera import viewer_pose

    class _Camera:
        def __init__(self, cam):
            self.wxyz, self.position = viewer_pose(cam)
            self.fov, self.aspect = np.radians(cam.fov_y_deg), 16 / 9

    class _Scene:
        def set_background_image(self, image, format="jpeg", jpeg_quality=None):
            import cv2
            cv2.imencode(".jpg", image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality or 85])

    class _Client:
        client_id = 0
        camera = _Camera(viewer.session.scene.camera)
        scene = _Scene()

        def flush(self):
            pass

    client = _Client()
    viewer.server.get_clients = lambda: {0: client}        # the only stand-in: no websocket
    rows = []
    for _ in range(args.rounds):
        for text in EDITS:
            viewer.run_command(text)
            viewer.wait_idle()
            rows.append(_row(viewer, text))
    return rows


def _with_browser(viewer, args) -> list[dict]:
    from morphosim_gym.viewer.testing import headless_chromium, type_command, wait_for

    w, h = (int(v) for v in args.window.split("x"))
    rows = []
    with headless_chromium(w, h) as driver:
        driver.get(viewer.url)
        wait_for(lambda: viewer.server.get_clients(), 30, message="the page")
        wait_for(lambda: viewer.frames, 30, message="a first frame")
        time.sleep(1.0)
        driver.execute_script("""
            window.__mt = {};
            document.addEventListener('keydown', e => {
                if (e.key === 'Enter') window.__mt.enter = performance.now(); }, true);
            new MutationObserver(() => {
                if (window.__mt.expect && !window.__mt.frame && document.body.innerText.includes(window.__mt.expect))
                    window.__mt.frame = performance.now();
            }).observe(document.body, {subtree: true, childList: true, characterData: true});
        """)
        for _ in range(args.rounds):
            for text in EDITS:
                count = len(viewer.latencies)
                driver.execute_script("window.__mt = {expect: arguments[0]};", f"Frame of '{text}' sent")
                type_command(driver, text)
                wait_for(lambda: len(viewer.latencies) > count, 20, message=f"the frame of {text!r}")
                t = wait_for(lambda: driver.execute_script("return window.__mt.frame ? window.__mt : null"), 10,
                             message="the page to receive the frame")
                row = _row(viewer, text)
                row["page_ms"] = t["frame"] - t["enter"]
                # the page's clock to the server's (same machine): where the time outside the server goes
                origin = driver.execute_script("return performance.timeOrigin;")
                lat = viewer.latencies[-1]
                row["page_to_server_ms"] = 1000.0 * lat["received_epoch"] - (origin + t["enter"])
                row["server_to_page_ms"] = (origin + t["frame"]) - 1000.0 * lat["sent_epoch"]
                rows.append(row)
                time.sleep(0.2)
    return rows


def _row(viewer, text: str) -> dict:
    lat = viewer.latencies[-1]
    assert lat["text"] == text, (lat, text)
    entry = viewer.session.log[-1]
    return {"text": text, "edit_ms": 1000.0 * entry.seconds, "render_ms": lat["render_ms"],
            "server_ms": lat["total_ms"], "size": lat["size"]}


if __name__ == "__main__":
    raise SystemExit(main())
