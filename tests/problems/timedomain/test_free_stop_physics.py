"""The free-stop pre-identification keeps to the physics: friction cannot drive the shaft."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from benchmark.problems.timedomain.mechanical import fit_free_stop


def test_a_coast_braked_harder_as_it_slows_fits_no_negative_friction():
    """An eddy-current brake left excited through the stop (viscous below its critical speed,
    its torque falling above it) decelerates the coast harder as it slows: the free-stop fit's
    unbounded least squares took that for a negative viscous friction (``tau_m`` -1.7e6 s on a
    motulator record), every candidate of the identification then invalid ("no local start
    completed"). Refitted within the physics, fv and fc are non-negative and the identification
    runs (its fit quality then says the model misses the stop)."""
    J, fc, T_k, w_k = 0.011, 0.05, 10.3, 35.0

    def f(_, y):
        w = max(y[0], 0.0)
        return [-(fc + T_k * 2 * (w / w_k) / (1 + (w / w_k) ** 2)) / J if w > 0 else 0.0]

    t = np.arange(0, 0.6, 1e-3)
    w = solve_ivp(f, (0, t[-1]), [155.0], t_eval=t, rtol=1e-9, atol=1e-9, max_step=1e-3).y[0]
    est = fit_free_stop(t, np.maximum(w, 0.0), case=2)
    assert 0 < est.tau_m < np.inf and est.fc_over_J >= 0.0
    # a coast that friction explains is fitted as before: the exponential's constants recovered
    w_free = (155.0 + 0.2 / 0.5) * np.exp(-t / 0.5) - 0.2 / 0.5
    est = fit_free_stop(t, np.maximum(w_free, 0.0), case=2, filter_speed=False)
    assert est.tau_m == pytest.approx(0.5, rel=1e-6) and est.fc_over_J == pytest.approx(0.2 / 0.5 / 0.5, rel=1e-5)
