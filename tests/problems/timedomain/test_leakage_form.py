"""The leakage-saturation augmentation reaches the independent plant's leakage curves.

The independent plant (``synthetic/independent``) saturates its leakage paths as functions of
the current, ``L(i) = L_lin + L_sat phi(i)`` with ``phi = 1/(1 + (i/i_k)^2)`` (lorentzian) or
``1/(1 + i/i_k)`` (frohlich), drawn at ``L(6 I_n)/L(0.9 I_n)`` 0.45-0.75 and linear shares
0.25-0.4. The catalogue's form is a function of the leakage flux, ``l = f + (1 - f)/(1 + k x^n)``;
the test fits it, inside its own bounds (24 starts), to the plant's secant inductance over a
start-up's currents, at the corners of the plant's draw range. A sharp lorentzian knee needs
``k`` in the hundreds (``k`` 439, ``n`` 3.78 on the plant's blind set 52/26, whose diagnosis then
left 2.17 times the noise instead of 6.62 with ``k`` stuck at 20). Measured RMS errors with the
bound at 1000: at most 1.01 % (lorentzian, ratio 0.45, linear share 0.25), frohlich at most
0.37 %; with ``k <= 20``: 1.85 % (lorentzian 0.45 / 0.4) and 1.13 %.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import least_squares

from benchmark.core.effects import load_effects
from synthetic.independent.curves import LeakageCurve
from tests.problems.timedomain.test_effects import _ctx

CTX = _ctx()  # the paper motor's context of the effect tests (28 A start-up peak)


def rms_fit(form: str, ratio: float, linear_share: float) -> float:
    """RMS relative error of the best catalogue curve against the plant's, over 2-100 % of
    the start-up peak (the plant's rated current: a sixth of the peak)."""
    eff = load_effects("timedomain")["leakage_saturation"]
    i_n = CTX.I_peak / 6.0
    plant = LeakageCurve.with_ratio(form, CTX.L_sigma, 0.9 * i_n, 6.0 * i_n, ratio, linear_share)
    cur = np.linspace(0.02, 1.0, 60) * CTX.I_peak
    target = plant.inductance(cur)
    lo, hi = eff.extra_bounds(CTX)

    def miss(x):
        return eff.leakage_curve(x, cur, CTX) / target - 1.0

    starts = [np.array([k, n, f]) for k in (0.3, 3.0, 30.0, 300.0) for n in (1.2, 2.0, 4.0) for f in (0.0, 0.3)]
    best = min((least_squares(miss, np.clip(s, lo, hi), bounds=(lo, hi)) for s in starts), key=lambda r: r.cost)
    return float(np.sqrt(np.mean(miss(best.x) ** 2)))


@pytest.mark.parametrize("form", ["lorentzian", "frohlich"])
@pytest.mark.parametrize("ratio,linear_share", [(0.45, 0.25), (0.45, 0.4), (0.75, 0.25), (0.75, 0.4)])
def test_leakage_form_reaches_the_plant_curves(form, ratio, linear_share):
    assert rms_fit(form, ratio, linear_share) < 0.0125
