"""The LLM client against a hostile endpoint (a raw socket server on 127.0.0.1 in this test):
every bad reply ends as a clean error naming the problem, or as the rule parser's plan with
``fallback="rules"``; one deadline bounds the whole parse; huge replies are refused unread and
never sent back."""

from __future__ import annotations

import json
import socket
import threading
import time

import pytest

from morphosim_gym.errors import BackendUnavailableError, CommandError
from morphosim_gym.language.llm import LLMConfig, parse_llm
from morphosim_gym.language.rules import parse_rules

TEXT = "a red ball bounces from right to left"


def _reply(content: str) -> bytes:
    return json.dumps({"choices": [{"message": {"role": "assistant", "content": content}}]}).encode()


def _http(body: bytes, length: int | None = None, extra: bytes = b"") -> bytes:
    n = len(body) if length is None else length
    return (b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\nContent-Length: " + str(n).encode()
            + b"\r\nConnection: close\r\n" + extra + b"\r\n" + body)


class RawServer:
    """Answers each connection with `answer(sock)` after reading its request; records request sizes."""

    def __init__(self, answer, connections: int = 2) -> None:
        self.answer = answer
        self.request_sizes: list[int] = []
        self.listener = socket.socket()
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(4)
        self.listener.settimeout(0.2)
        self.url = f"http://127.0.0.1:{self.listener.getsockname()[1]}/v1"
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, args=(connections,), daemon=True)
        self.thread.start()

    def _serve(self, connections: int) -> None:
        served, end = 0, time.monotonic() + 60
        while served < connections and not self.stop.is_set() and time.monotonic() < end:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                continue
            served += 1
            with conn:
                conn.settimeout(5)
                try:
                    self.request_sizes.append(self._read_request(conn))
                    self.answer(conn)
                except OSError:     # the client hung up (as it should on floods and trickles)
                    pass

    @staticmethod
    def _read_request(conn) -> int:
        data = b""
        while b"\r\n\r\n" not in data:
            data += conn.recv(65536)
        head, _, body = data.partition(b"\r\n\r\n")
        length = next(int(line.split(b":")[1]) for line in head.split(b"\r\n")
                      if line.lower().startswith(b"content-length"))
        while len(body) < length:
            body += conn.recv(65536)
        return len(body)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5)
        self.listener.close()


def send(data: bytes):
    return lambda conn: conn.sendall(data)


def trickle(prefix: bytes, byte: bytes = b" ", every: float = 0.2, count: int = 400):
    def answer(conn):
        conn.sendall(prefix)
        for _ in range(count):
            conn.sendall(byte)
            time.sleep(every)
    return answer


def flood(total: int, announce: bool):
    def answer(conn):
        head = b"HTTP/1.1 200 OK\r\nContent-Type: application/json\r\n"
        head += (b"Content-Length: " + str(total).encode() + b"\r\n") if announce else b""
        conn.sendall(head + b"Connection: close\r\n\r\n" + b'{"choices": "')
        block = b"a" * (1 << 20)
        for _ in range(total // len(block)):
            conn.sendall(block)
    return answer


DEEP = b"[" * 100_000 + b"]" * 100_000
HOSTILE = {
    "binary body": send(_http(bytes(range(256)) * 64)),
    "non-HTTP reply": send(b"SSH-2.0-OpenSSH_9.6\r\nProtocol mismatch.\r\n"),
    "empty reply": send(b""),
    "short body": send(_http(b'{"choices": [', length=5000)),
    "bad Content-Length": send(_http(b"{}", length=None, extra=b"Content-Length: -1\r\n")),
    "huge integer (envelope)": send(_http(b'{"choices": [], "n": ' + b"9" * 100_000 + b"}")),
    "huge integer (plan)": send(_http(_reply('{"mode": "generate", "objects": [{"noun": "ball", "count": '
                                             + "9" * 5000 + "}]}"))),
    "deep JSON (envelope)": send(_http(DEEP)),
    "deep JSON (plan)": send(_http(_reply(DEEP.decode()))),
    "nested 65 deep (plan)": send(_http(_reply("[" * 65 + "]" * 65))),
    "escaped quotes flood": send(_http(b'{"choices": "' + b'\\"' * 400_000)),
    "escaped quotes flood (plan)": send(_http(_reply('{"mode": "' + '\\"' * 200_000))),
    "open code fence and 900k spaces": send(_http(_reply("```" + " " * 900_000))),
    "Infinity in plan": send(_http(_reply('{"mode": "generate", "objects": [{"noun": "ball", "scale": 1e999}]}'))),
    "plan of wrong types": send(_http(_reply('{"mode": "generate", "objects": "ball", "then": 7, "edits": {}}'))),
    "content not a string": send(_http(b'{"choices": [{"message": {"content": {"a": 1}}}]}')),
    "header line too long": send(b"HTTP/1.1 200 OK\r\nX: " + b"a" * 200_000 + b"\r\n\r\n"),
    "HTTP 500": send(b"HTTP/1.1 500 Oops\r\nContent-Length: 0\r\n\r\n"),
}


def _config(server, **kw) -> LLMConfig:
    return LLMConfig(base_url=server.url, model="m", **{"timeout_s": 5, **kw})


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_replies_fall_back_to_the_rules(name):
    server = RawServer(HOSTILE[name])
    start = time.perf_counter()
    try:
        plan = parse_llm(TEXT, config=_config(server))
        elapsed = time.perf_counter() - start      # the client's time; closing our server is not part of it
    finally:
        server.close()
    assert plan.backend == "rules" and plan == parse_rules(TEXT)
    assert elapsed < 3.0                           # no reply costs more than reading it once


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_replies_raise_clean_errors(name):
    server = RawServer(HOSTILE[name])
    try:
        with pytest.raises((BackendUnavailableError, CommandError)) as info:
            parse_llm(TEXT, config=_config(server, fallback="raise"))
    finally:
        server.close()
    assert len(str(info.value)) < 1000 and "Traceback" not in str(info.value)


@pytest.mark.parametrize("where", ["body", "status line"])
def test_a_slow_trickle_ends_at_the_deadline(where):
    prefix = _http(b"", length=100_000) if where == "body" else b"HTTP/1.1 200 "
    server = RawServer(trickle(prefix), connections=2)
    start = time.perf_counter()
    try:
        with pytest.raises(BackendUnavailableError, match="within 1 s"):
            parse_llm(TEXT, config=_config(server, timeout_s=1, fallback="raise"))
        assert time.perf_counter() - start < 2.0
        start = time.perf_counter()
        assert parse_llm(TEXT, config=_config(server, timeout_s=1)).backend == "rules"
        assert time.perf_counter() - start < 2.0
    finally:
        server.close()


@pytest.mark.parametrize("announce", [True, False])
def test_a_50_mb_reply_is_refused_quickly(announce):
    server = RawServer(flood(50 << 20, announce))
    start = time.perf_counter()
    try:
        with pytest.raises(BackendUnavailableError, match="bytes"):
            parse_llm(TEXT, config=_config(server, fallback="raise"))
        elapsed = time.perf_counter() - start      # before our flooding server is stopped (up to 5 s)
    finally:
        server.close()
    assert elapsed < 2.0


def test_the_deadline_covers_every_retry():
    """Each answer is slow but in time for one request; two of them are not in time for the parse."""
    def slow_invalid(conn):
        time.sleep(0.6)
        conn.sendall(_http(_reply('{"mode": "dance"}')))

    server = RawServer(slow_invalid, connections=3)
    start = time.perf_counter()
    try:
        with pytest.raises(BackendUnavailableError, match="within 1 s"):
            parse_llm(TEXT, config=_config(server, timeout_s=1, max_retries=2, fallback="raise"))
        elapsed = time.perf_counter() - start
    finally:
        server.close()
    assert elapsed < 1.5 and len(server.request_sizes) == 2


def test_a_long_invalid_reply_is_not_sent_back():
    long_reply = _http(_reply('{"mode": "dance", "pad": "' + "a" * 900_000 + '"}'))
    server = RawServer(send(long_reply), connections=2)
    try:
        assert parse_llm(TEXT, config=_config(server)).backend == "rules"
    finally:
        server.close()
    first, retry = server.request_sizes
    assert retry < first + 2_000, server.request_sizes
