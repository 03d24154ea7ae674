"""How the models' compiled kernels are compiled (every ``njit`` of the extended model, its T
mode, the base model's stepper and cost): cached on disk, and with NumPy's error model, so that a
row whose arithmetic divides by zero (a score test's linear step that puts one of its divisors,
a leakage, an inertia, a reference speed, at 0) gives inf or NaN: a diverged candidate, whose
residuals the fits count as :data:`~benchmark.problems.timedomain.diagnosis.fit.DIVERGED`,
never an exception that ends the run. The arithmetic of every other row is the same operation
for operation (the Python error model only adds a test of each divisor)."""

from __future__ import annotations

import numba


def compiled(**options):
    """``numba.njit(cache=True, error_model="numpy", **options)``."""
    return numba.njit(cache=True, error_model="numpy", **options)
