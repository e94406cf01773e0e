"""Parallel kernels that survive `fork()` and several Python threads.

numba runs `parallel=True` kernels on a threading layer chosen at the first parallel launch:
"tbb", "omp" or "workqueue" (numba's default order). On Linux "omp" is GNU OpenMP, which does
not survive `fork()`: once its threads have started, numba terminates every child the process
forks ("Terminating: fork() called from a process already using GNU OpenMP, this is unsafe."),
which is what killed Gymnasium's `AsyncVectorEnv` workers (fork is its default start method on
Linux) after the parent had stepped an env. torch's GNU OpenMP has the same flaw without the
message: a forked child that runs a parallel torch op (e.g. the text-embedding model behind an
edit) hangs if the parent ran one.

`configure()` (run when this module is imported, first thing on `import morphosim_gym`) therefore

* asks numba for its "forksafe" layer unless the user chose one (`NUMBA_THREADING_LAYER`):
  "tbb" when installed (the `tbb` dependency; fork- and thread-safe, within ~4% of "omp" for
  one env at one thread, and far faster than "omp" on oversubscribed cores, where GNU OpenMP
  spins), else "workqueue" (fork-safe but not thread-safe; it hands every launch to a worker
  thread, ~30% slower than "omp" for one env at one thread on a loaded 2-core machine);
* makes forked children run torch on one thread (what torch's own DataLoader workers do), and
  forks only between kernel launches (the child starts with `kernel_lock` free).

"workqueue" is not thread-safe: two Python threads launching kernels at once terminate the
process. `kernel_lock()` serialises launches while that layer (or a layer not yet chosen) is in
use; the envs' `numba_threads` and `render` / `rasterize` (`serialised`) hold it.
"""

from __future__ import annotations

import functools
import os
import sys
import threading
from contextlib import nullcontext
from typing import Any, Callable, ContextManager, Optional, TypeVar

__all__ = ["configure", "kernel_lock", "serialised", "threading_layer", "THREAD_SAFE_LAYERS", "FORK_SAFE_REQUEST"]

F = TypeVar("F", bound=Callable[..., Any])

FORK_SAFE_REQUEST = "forksafe"
THREAD_SAFE_LAYERS = frozenset({"tbb", "omp"})
_LOCK = threading.RLock()
_layer: Optional[str] = None          # the layer numba launched, once known
_configured = False


def _before_fork() -> None:
    _LOCK.acquire()


def _after_fork_in_parent() -> None:
    _LOCK.release()


def _after_fork_in_child() -> None:
    global _LOCK
    _LOCK = threading.RLock()
    torch = sys.modules.get("torch")          # never import torch here: only fix it if it is in use
    if torch is not None:
        try:
            torch.set_num_threads(1)
        except Exception:  # pragma: no cover - a torch that cannot set threads keeps its own
            pass


_TBB_SONAMES = ("libtbb.so.12",)


def _preload_tbb() -> Optional[str]:
    """Load the `tbb` wheel's library so numba's TBB layer can link to it.

    pip installs `libtbb.so.12` into `<prefix>/lib`, which a virtual environment does not put on
    the dynamic loader's path, so numba reports TBB unavailable ("Unknown import problem") and
    falls back to workqueue. Loading it once with RTLD_GLOBAL lets numba's `tbbpool` resolve it.
    Returns the path loaded, or None (not Linux, no wheel, or already loadable)."""
    if not sys.platform.startswith("linux"):
        return None
    import ctypes

    for prefix in dict.fromkeys((sys.prefix, sys.base_prefix)):
        for name in _TBB_SONAMES:
            path = os.path.join(prefix, "lib", name)
            if os.path.exists(path):
                try:
                    ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
                except OSError:  # pragma: no cover - a broken wheel: numba falls back to workqueue
                    continue
                return path
    return None


def configure() -> None:
    """Request a fork-safe numba threading layer (unless the user chose one) and make forked
    children run torch single-threaded. Idempotent; has no effect on a layer already launched."""
    global _configured
    if _configured:
        return
    _configured = True
    if os.environ.get("NUMBA_THREADING_LAYER", "") in ("", FORK_SAFE_REQUEST, "safe", "tbb"):
        _preload_tbb()
    if not os.environ.get("NUMBA_THREADING_LAYER"):
        # numba re-reads its settings when the environment changes, so the request goes there
        # (children inherit it); the config attribute covers a numba imported before us.
        os.environ["NUMBA_THREADING_LAYER"] = FORK_SAFE_REQUEST
        config = getattr(sys.modules.get("numba"), "config", None)
        if config is not None and config.THREADING_LAYER == "default":
            config.THREADING_LAYER = FORK_SAFE_REQUEST
    if hasattr(os, "register_at_fork"):
        # no fork in the middle of another thread's kernel; the child gets a fresh, free lock
        os.register_at_fork(before=_before_fork, after_in_parent=_after_fork_in_parent,
                            after_in_child=_after_fork_in_child)


def threading_layer() -> Optional[str]:
    """The threading layer numba launched ("tbb", "omp", "workqueue"), or None before the first
    parallel kernel."""
    global _layer
    if _layer is None:
        import numba

        try:
            _layer = numba.threading_layer()
        except ValueError:           # no parallel kernel has run yet
            return None
    return _layer


def kernel_lock() -> ContextManager[Any]:
    """A context that serialises numba kernel launches across Python threads when the layer is
    not thread-safe (workqueue, or not chosen yet); a no-op context for tbb and omp. Reentrant."""
    return nullcontext() if threading_layer() in THREAD_SAFE_LAYERS else _LOCK


def serialised(fn: F) -> F:
    """Decorate a function that launches numba kernels to run under `kernel_lock()`."""
    @functools.wraps(fn)
    def run(*args: Any, **kwargs: Any) -> Any:
        with kernel_lock():
            return fn(*args, **kwargs)

    return run  # type: ignore[return-value]


configure()
