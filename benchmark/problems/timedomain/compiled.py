"""How the models' compiled kernels are compiled (every ``njit`` of the extended model, its T
mode, the base model's stepper and cost): cached on disk, and with NumPy's error model, so that a
row whose arithmetic divides by zero (a score test's linear step that sets a double cage's
leakage or a load's reference speed to 0, say) gives inf or NaN: a diverged candidate, whose
residuals the fits count as :data:`~benchmark.problems.timedomain.diagnosis.fit.DIVERGED`,
never an exception that ends the run. The arithmetic of every other row is the same operation
for operation (the Python error model only adds a test of each divisor)."""

from __future__ import annotations

import numba


def compiled(**options):
    """``numba.njit(cache=True, error_model="numpy", **options)``."""
    return numba.njit(cache=True, error_model="numpy", **options)
