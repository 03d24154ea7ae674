"""A row whose arithmetic divides by zero is a diverged candidate, never an exception.

The independent plant's held-out blind draw (seed 414, set 24: a 7.5 kW direct start) ended the
whole blind run with ``ZeroDivisionError`` raised inside the extended model's kernel, during the
pair step's score tests (a linear step from a single fit; which divisor it put at 0 was not traced,
so every divisor of the kernel is tested here).
The kernels are compiled with NumPy's error model (:mod:`benchmark.problems.timedomain.compiled`):
such a row's outputs are inf or NaN, and the fits count them as diverged."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.problems.timedomain.diagnosis.fit import DIVERGED, JointModel
from benchmark.problems.timedomain.diagnosis.kernel_cache import KernelCache
from benchmark.problems.timedomain.extended import IDX, base_rows, simulate_extended_batch

T = np.arange(400) * 1e-4
V_A, V_B = 325.0 * np.cos(2 * np.pi * 50 * T), 325.0 * np.sin(2 * np.pi * 50 * T)
#: A 7.5 kW machine (the set's plant) with every effect's branch switched on, so that each divisor is used
EFFECTS_ON = {"R_r2": 0.5, "L_sigma2": 0.01, "ls_k": 0.5, "ls_psi": 0.05, "ls_exp": 2.0, "ms_k": 0.2,
              "ms_psi": 0.9, "ms_exp": 7.0, "T_q": 1.0, "w_ref": 150.0, "T_s": 2.0, "t_step": 0.01,
              "tau_s": 0.005, "J_l": 0.02, "k_sh": 1000.0, "c_sh": 1.0, "R_r3": 0.4, "L_sigma3": 0.01,
              "h_th": 1e-3, "alpha_th": 0.004}
#: Every field some division of the kernel takes (the Python error model raised on each at 0)
DIVISORS = ("L_sigma", "L_M", "R_r1", "L_sigma2", "ms_psi", "ls_psi", "J", "p", "w_ref", "L_sigma3")


def _row(zero: str) -> np.ndarray:
    row = base_rows(np.array([[0.81, 0.142, 0.0076, 0.613, 0.0358, 0.0024, 0.185]]), 2)[0]
    for name, value in EFFECTS_ON.items():
        row[IDX[name]] = value
    row[IDX[zero]] = 0.0
    return row


@pytest.mark.parametrize("field", DIVISORS)
def test_a_zero_divisor_gives_a_diverged_row_not_an_exception(field):
    good = _row("t_rise")  # t_rise 0: a hard step, nothing divides by it
    out = simulate_extended_batch(np.stack([good, _row(field)]), V_A, V_B, True, 1e-4, 1)
    assert np.isfinite(out[0]).all()  # the row beside it is simulated as ever
    bad = out[1]
    assert not np.isfinite(bad).all()
    # the same row alone gives the same outputs: the rows of a batch do not see each other
    alone = simulate_extended_batch(_row("t_rise")[None, :], V_A, V_B, True, 1e-4, 1)
    np.testing.assert_array_equal(alone[0], out[0])


def test_the_fits_count_a_zero_divisor_row_as_diverged():
    cache = KernelCache(V_A, V_B, True, 1e-4)
    sim = cache.simulate(np.stack([_row("t_rise"), _row("L_sigma2")]))
    model = JointModel.__new__(JointModel)
    model.measured = np.zeros(3 * len(T))
    model.weight = np.ones(3 * len(T))
    r = model.residuals_of(sim.reshape(2, -1))
    assert np.isfinite(r).all()
    assert np.all(np.abs(r[0]) < DIVERGED)
    assert np.any(r[1] == DIVERGED)
