"""`numba_threads`: run numba kernels with a given thread count, then restore it."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator, Optional

from morphosim_gym.parallel import kernel_lock

__all__ = ["numba_threads"]


@contextmanager
def numba_threads(n: Optional[int]) -> Iterator[None]:
    """Run the enclosed numba kernels with `n` threads (numba's setting is per calling thread), then
    restore the previous count; None leaves it alone. Holds `kernel_lock()`, so envs stepped from
    several Python threads take turns where numba's threading layer needs it (workqueue)."""
    with kernel_lock():
        if n is None:
            yield
            return
        import numba

        old = numba.get_num_threads()
        numba.set_num_threads(min(int(n), numba.config.NUMBA_NUM_THREADS))
        try:
            yield
        finally:
            numba.set_num_threads(old)
