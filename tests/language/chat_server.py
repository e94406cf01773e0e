"""A real OpenAI-compatible chat server on 127.0.0.1 for the LLM tests (bounded in requests and time)."""

from __future__ import annotations

import json
import threading
import time
from http.server import BaseHTTPRequestHandler, HTTPServer


class ChatServer:
    """An OpenAI-compatible /v1/chat/completions stub that answers a scripted list of replies
    (a str is the message content; an int is an HTTP error status) and records the requests."""

    def __init__(self, replies: list) -> None:
        self.replies = list(replies)
        self.requests: list[dict] = []
        outer = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:  # noqa: N802
                body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
                outer.requests.append({"path": self.path, "auth": self.headers.get("Authorization"),
                                       "body": json.loads(body)})
                reply = outer.replies.pop(0) if outer.replies else 500
                if isinstance(reply, int):
                    self.send_response(reply)
                    self.end_headers()
                    return
                data = json.dumps({"choices": [{"message": {"role": "assistant", "content": reply}}]}).encode()
                self.send_response(200)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def log_message(self, *args) -> None:
                pass

        self.httpd = HTTPServer(("127.0.0.1", 0), Handler)
        self.httpd.timeout = 0.1
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/v1"
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, args=(len(replies) + 1,), daemon=True)
        self.thread.start()

    def _serve(self, n: int) -> None:
        deadline = time.monotonic() + 30.0  # bounded in time and in count (one request more than scripted)
        while len(self.requests) < n and not self.stop.is_set() and time.monotonic() < deadline:
            self.httpd.handle_request()

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=2)
        self.httpd.server_close()
