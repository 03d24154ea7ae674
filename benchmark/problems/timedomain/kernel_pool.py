"""The thread pool the compiled kernels' blocks run on (the block functions release the GIL),
and the budget of threads a thread's kernel calls may use (:class:`kernel_budget`: a worker of a
pool that runs jobs side by side on every core uses its own, and the cores of workers that
have nothing left to do).
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numba

_pool_state: dict = {"pool": None, "pid": None, "workers": 0}
_pool_lock = threading.Lock()


def shared_executor(workers: int) -> ThreadPoolExecutor:
    """A process-wide thread pool (recreated after a fork or when more workers are needed)."""
    with _pool_lock:
        st = _pool_state
        if st["pool"] is None or st["pid"] != os.getpid() or st["workers"] < workers:
            if st["pool"] is not None and st["pid"] == os.getpid():
                st["pool"].shutdown(wait=False)
            st.update(pool=ThreadPoolExecutor(max_workers=workers, thread_name_prefix="imbench-sim"),
                      pid=os.getpid(), workers=workers)
        return st["pool"]


_share = threading.local()


def kernel_threads() -> int:
    """Threads a batched kernel call may use: numba's thread count, or what this thread's
    :class:`kernel_budget` allows (at least 1)."""
    budget = getattr(_share, "budget", None)
    n = numba.get_num_threads()
    return n if budget is None else max(1, min(n, int(budget())))


class kernel_budget:
    """Context: kernel calls made by this thread use at most ``budget()`` threads, asked at each
    call (a worker of a pool that runs jobs side by side takes one core while the other
    workers are busy, and the idle workers' cores once they are not). A row's outputs do not
    depend on how the rows are split, so the results do not depend on the budget."""

    def __init__(self, budget):
        self.budget = budget

    def __enter__(self):
        self._was = getattr(_share, "budget", None)
        _share.budget = self.budget
        return self

    def __exit__(self, *exc):
        _share.budget = self._was
        return False


def run_split(block_fn, n: int, *args) -> None:
    """``block_fn(start, stop, *args)`` over ``0..n-1`` in :func:`kernel_threads` nearly equal
    blocks run in parallel (the compiled block functions release the GIL); the calling thread
    takes the first."""
    nb = max(1, min(kernel_threads(), n))
    bounds = [b * n // nb for b in range(nb + 1)]
    futures = []
    if nb > 1:
        pool = shared_executor(nb - 1)
        futures = [pool.submit(block_fn, bounds[b], bounds[b + 1], *args) for b in range(1, nb)]
    try:
        block_fn(bounds[0], bounds[1], *args)
    finally:
        for f in futures:
            f.result()
