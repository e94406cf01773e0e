"""Reading a child process's output with a deadline: a server that prints nothing cannot block a test."""

from __future__ import annotations

import queue
import re
import subprocess
import threading
import time


def lines_of(stream) -> queue.Queue:
    """The lines of `stream`, read on a daemon thread (None at the end)."""
    lines: queue.Queue = queue.Queue()

    def pump() -> None:
        for line in iter(stream.readline, ""):
            lines.put(line)
        lines.put(None)

    threading.Thread(target=pump, daemon=True).start()
    return lines


def wait_for_line(proc: subprocess.Popen, pattern: str, timeout: float) -> tuple[re.Match | None, list[str]]:
    """The first match of `pattern` in `proc`'s stdout within `timeout` s (None when it ends or times
    out first), and the lines read so far."""
    pending, lines, deadline = lines_of(proc.stdout), [], time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            line = pending.get(timeout=max(0.1, deadline - time.monotonic()))
        except queue.Empty:
            break
        if line is None:
            break
        lines.append(line)
        found = re.search(pattern, line)
        if found:
            return found, lines
    return None, lines
