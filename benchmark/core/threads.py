"""One BLAS thread for the project's numerical work.

The compiled kernels evaluate populations on every core (numba ``prange``); the linear algebra
between them (the SVD of a least-squares Jacobian, tall and thin: tens of thousands of residuals by
7-20 parameters) gains nothing from more threads, and OpenBLAS's idle workers spin on the cores the
kernels need. A threaded BLAS also sums in an order that depends on the machine's core count, so
the same seed gave a different last digit on a machine with another number of cores.

Measured (the perf benchmark's diagnosis, 1 s at 12 kHz, every candidate, 2 cores shared with
other work): 121 CPU s with OpenBLAS's two threads, 73 CPU s with one; the same verdict, the
fitted parameters within 1e-5 relative of each other.
"""

from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def one_blas_thread(fn):
    """Decorator: ``fn`` runs with one BLAS/LAPACK thread in every BLAS loaded when it is called
    (NumPy's and SciPy's may be two libraries); the previous limits return afterwards."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import scipy.linalg  # noqa: F401  (loads SciPy's own BLAS, if it has one, before the limit)

        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)

    return wrapper
