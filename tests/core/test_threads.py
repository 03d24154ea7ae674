"""The harness's runs use one BLAS thread (benchmark/core/threads.py): the same seed gives the
same digits whatever the machine's core count, and OpenBLAS's idle workers do not spin on the
cores the compiled kernels use."""

from __future__ import annotations

import numpy as np
from threadpoolctl import threadpool_info

from benchmark.core import harness
from benchmark.core.threads import one_blas_thread


def _blas_threads():
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_within_a_run_every_blas_has_one_thread_and_the_limit_is_lifted_after():
    outside = _blas_threads()
    assert outside  # NumPy's BLAS at least is loaded

    @one_blas_thread
    def inside():
        return _blas_threads(), np.linalg.svd(np.arange(12.0).reshape(4, 3), compute_uv=False)

    threads, s = inside()
    assert threads == [1] * len(threads) and len(threads) >= len(outside)
    assert abs(s[0] - 22.4467) < 1e-3
    assert _blas_threads() == outside


def test_identification_and_diagnosis_runs_are_limited():
    for fn in (harness.run, harness.run_diagnosis):
        assert fn.__wrapped__.__module__ == "benchmark.core.harness"
        assert fn.__code__ is not fn.__wrapped__.__code__  # the wrapper of one_blas_thread
        assert fn.__code__ is one_blas_thread(lambda: None).__code__
