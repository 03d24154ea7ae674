"""The stepper's stator current per leakage flux (:func:`~benchmark.problems.timedomain.extended._stator_gain`):
the saturating leakage's law, taken without a square root or power and with one division, is the
law ``1 / (f + (1 - f) / (1 + k (|psi|/ref)^ex)) / L_sigma`` to rounding, at zero flux too."""

import numpy as np
import pytest

from benchmark.problems.timedomain.extended import IDX, _leak_constants, _stator_gain, base_row

MOTOR = {"Rs": 0.29, "Ls": 0.036, "Le": 0.0019, "Rr": 0.15, "J": 0.09, "fv": 0.004, "fc": 0.3, "p": 3}


def _law(d2, k, ref, ex, floor, L):
    s = 1.0 + k * (np.sqrt(d2) / ref) ** ex
    return 1.0 / (floor + (1.0 - floor) / s) / L


@pytest.mark.parametrize("k, ref, ex, floor", [(0.3, 0.05, 1.7, 0.0), (2.0, 0.02, 4.0, 0.3), (1000.0, 0.5, 1.0, 0.9),
                                                (0.5, 0.1, 8.0, 0.25), (0.0, 1.0, 2.0, 0.0), (0.0, 1.0, 2.0, 0.4)])
def test_the_gain_is_the_saturating_leakage_law(k, ref, ex, floor):
    row = base_row(MOTOR)
    row[IDX["ls_k"]], row[IDX["ls_psi"]], row[IDX["ls_exp"]], row[IDX["ls_floor"]] = k, ref, ex, floor
    inv_ref2, half_ex = _leak_constants(row)
    for d2 in np.concatenate([[0.0], np.geomspace(1e-12, 4.0, 200)]):
        got = _stator_gain(row, d2, inv_ref2, half_ex)
        assert got == pytest.approx(_law(d2, k, ref, ex, floor, MOTOR["Le"]), rel=1e-13, abs=0.0)
