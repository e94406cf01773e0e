"""Starting a local Ray cluster on a busy machine: a startup timeout is tried again, cleanly."""

from __future__ import annotations

import subprocess
import sys

import pytest

from morphosim_gym.bench.backends import RAY_START_TRIES, _start_ray

TIMEOUT = ("The current node timed out during startup. This could happen because some of the raylet "
           "failed to startup or the GCS has become overloaded.")


class SlowRay:
    """Ray's `init` as a busy machine sees it: each call starts a process (its 'raylet'), then the
    first `timeouts` calls raise Ray's startup timeout, or `error` when given."""

    def __init__(self, timeouts: int, error: Exception | None = None) -> None:
        self.timeouts, self.error = timeouts, error
        self.calls: list[dict] = []
        self.procs: list[subprocess.Popen] = []

    def init(self, **kw) -> None:
        self.calls.append(kw)
        self.procs.append(subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"]))
        if self.error is not None:
            raise self.error
        if len(self.calls) <= self.timeouts:
            raise Exception(TIMEOUT)

    def cleanup(self) -> None:
        for p in self.procs:
            if p.poll() is None:
                p.kill()
                p.wait()


@pytest.fixture
def slow_ray():
    made: list[SlowRay] = []

    def make(*args, **kw) -> SlowRay:
        made.append(SlowRay(*args, **kw))
        return made[-1]

    yield make
    for r in made:
        r.cleanup()


def test_a_startup_timeout_is_tried_again_and_its_processes_ended(slow_ray):
    ray = slow_ray(timeouts=2)
    with pytest.warns(RuntimeWarning, match="timed out during startup") as warned:
        _start_ray(ray, address="local", num_cpus=2)
    assert [str(w.message).split("(")[1][:10] for w in warned] == ["try 1 of 3", "try 2 of 3"]
    assert len(ray.calls) == 3 and all(kw == {"address": "local", "num_cpus": 2} for kw in ray.calls)
    assert [p.poll() is not None for p in ray.procs] == [True, True, False]   # the started cluster stays


def test_every_try_timing_out_is_a_clear_error_with_nothing_left_running(slow_ray):
    ray = slow_ray(timeouts=RAY_START_TRIES)
    with pytest.warns(RuntimeWarning), pytest.raises(RuntimeError, match="timed out during startup 3 times"):
        _start_ray(ray)
    assert len(ray.calls) == RAY_START_TRIES
    assert all(p.poll() is not None for p in ray.procs)


def test_another_start_error_is_raised_at_once(slow_ray):
    ray = slow_ray(timeouts=0, error=ValueError("When connecting to an existing cluster, num_cpus must not be given"))
    with pytest.raises(ValueError, match="existing cluster"):
        _start_ray(ray)
    assert len(ray.calls) == 1
