"""The batched fitting engine: independent fits of the selection run side by side on every core.

The fits of one selection round (each candidate's fold fits from its starts, each pair of the
look-ahead, each drop-one refit of the backward check) do not depend on one another. They run
on a pool of worker threads, one per numba thread (``numba.get_num_threads()``, 2 on the
project's CI machine): the extended model's kernel and NumPy's array operations release the
GIL, so the workers' simulations and residuals proceed together. Inside a worker a kernel call
stays on that worker's core while every worker has a call to run, and splits its rows over the
idle workers' cores once the calls left are fewer than the workers (:class:`_Batch`,
:class:`~benchmark.problems.timedomain.kernel_pool.kernel_budget`); called from the main thread
a kernel call splits its rows over all cores.

Every fit computes exactly what it computes alone: the results, and so every verdict, are the
same bit for bit whatever the number of workers and the order in which they finish
(``tests/problems/timedomain/test_fit_engine.py``). A :func:`side_by_side` called from inside
a worker runs its items in that worker, one after the other (no nested pools).

Warnings: :func:`warnings.catch_warnings` is not thread-safe (it swaps the module's global
filter list), so the fits' own suppression (:func:`quiet`) is done once, by the thread that
starts the workers, around the whole job.
"""

from __future__ import annotations

import os
import threading
import warnings
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

import numba

from benchmark.problems.timedomain.kernel_pool import kernel_budget

_local = threading.local()
_pool_state: dict = {"pool": None, "pid": None, "workers": 0}
_pool_lock = threading.Lock()


def in_worker() -> bool:
    """True in a worker thread of the engine."""
    return bool(getattr(_local, "worker", False))


def workers() -> int:
    """Worker threads of the engine: numba's thread count (``IMBENCH_FIT_WORKERS`` overrides it;
    1 runs every fit in the calling thread)."""
    env = os.environ.get("IMBENCH_FIT_WORKERS")
    return max(1, int(env)) if env else max(1, numba.get_num_threads())


def _executor(n: int) -> ThreadPoolExecutor:
    with _pool_lock:
        st = _pool_state
        if st["pool"] is None or st["pid"] != os.getpid() or st["workers"] != n:
            if st["pool"] is not None and st["pid"] == os.getpid():
                st["pool"].shutdown(wait=False)
            st.update(pool=ThreadPoolExecutor(max_workers=n, thread_name_prefix="imbench-fit"), pid=os.getpid(),
                      workers=n)
        return st["pool"]


class _Batch:
    """The calls of one :func:`side_by_side` not yet ended, and the kernel threads each running
    call may use: one core each while as many calls remain as there are workers, the cores of
    idle workers shared among the calls left (the last call of a round's fits, a long fold fit,
    no longer runs on one core while the other idles)."""

    def __init__(self, n_items: int, n_workers: int):
        self.left, self.workers, self._lock = n_items, n_workers, threading.Lock()

    def threads(self) -> int:
        return max(1, self.workers // max(1, self.left))

    def run(self, fn: Callable, item):
        _local.worker = True
        try:
            with kernel_budget(self.threads):
                return fn(item)
        finally:
            _local.worker = False
            with self._lock:
                self.left -= 1


def side_by_side(fn: Callable, items: Iterable) -> list:
    """``[fn(item) for item in items]``, the calls run in parallel on the engine's workers (in
    the calling thread, in order, when it is a worker itself or the engine has one worker). An
    exception in a call is raised here once every call has ended."""
    items = list(items)
    n = workers()
    if in_worker() or n <= 1 or len(items) <= 1:
        return [fn(item) for item in items]
    pool = _executor(n)
    with quiet():
        batch = _Batch(len(items), n)
        futures = [pool.submit(batch.run, fn, item) for item in items]
        errors = [f.exception() for f in futures]
    for err in errors:
        if err is not None:
            raise err
    return [f.result() for f in futures]


@contextmanager
def quiet():
    """Warnings ignored while the block runs; inside a worker a no-op (the thread that started
    the workers set it for them)."""
    if in_worker():
        yield
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield
