"""The capped least squares (:mod:`benchmark.core.capped_least_squares`): the plain SciPy call's
path and end bit for bit, one Jacobian fewer where it stops at its cap."""

import numpy as np
import pytest
from scipy import optimize

from benchmark.core.capped_least_squares import capped_least_squares

T = np.linspace(0.0, 3.0, 40)
Y = 2.0 * np.exp(-1.3 * T) + 0.4 * np.sin(4.0 * T) + 0.01 * np.cos(37.0 * T)


def residuals(u):  # a decay and a sine, in a box: curved, several iterations to converge
    a, b, c, w = 4.0 * u[0], 3.0 * u[1], u[2], 2.0 + 4.0 * u[3]
    return a * np.exp(-b * T) + c * np.sin(w * T) - Y


def jacobian(u):  # forward differences, as the diagnosis's fits take them
    r0 = residuals(u)
    h = 1e-6 * np.maximum(np.abs(u), 1e-3)
    return np.column_stack([(residuals(u + h[j] * np.eye(len(u))[j]) - r0) / h[j] for j in range(len(u))])


def counting(fn, calls, evaluations=None):
    """``fn`` noting each call (with the residuals' evaluations so far, when given)."""
    def wrapped(u):
        calls.append(len(evaluations) if evaluations is not None else 0)
        return fn(u)
    return wrapped


OPTIONS = {"bounds": (0.0, 1.0), "x_scale": "jac", "xtol": 1e-5, "ftol": 1e-5, "gtol": 1e-8}


@pytest.mark.parametrize("max_nfev", [1, 2, 3, 4, 6, 9, 200])
@pytest.mark.parametrize("u0", [[0.3, 0.2, 0.1, 0.2], [0.9, 0.9, 0.9, 0.9]])
def test_the_same_path_and_end_without_the_jacobian_never_read(max_nfev, u0):
    evaluations, plain_jacs, capped_jacs = [], [], []
    plain = optimize.least_squares(counting(residuals, evaluations), np.array(u0),
                                   jac=counting(jacobian, plain_jacs, evaluations), method="trf",
                                   max_nfev=max_nfev, **OPTIONS)
    capped, at_cap = capped_least_squares(residuals, counting(jacobian, capped_jacs), np.array(u0), max_nfev,
                                          **OPTIONS)
    assert np.array_equal(capped.x, plain.x)  # bit for bit
    assert np.array_equal(capped.fun, plain.fun) and capped.nfev == plain.nfev
    # the plain call's Jacobians taken once every evaluation was spent: never read
    unread = sum(1 for spent in plain_jacs if spent >= max_nfev)
    assert unread <= 1 and len(capped_jacs) == len(plain_jacs) - unread
    # stopped at the cap; also where the gradient first vanishes at the last allowed evaluation
    # (telling that apart needs the Jacobian not taken)
    assert at_cap == (plain.status == 0 or (plain.status == 1 and plain.nfev == max_nfev))


def test_a_converging_fit_is_not_called_stopped_at_the_cap():
    sol, at_cap = capped_least_squares(residuals, jacobian, np.array([0.5, 0.4, 0.4, 0.5]), 200, **OPTIONS)
    assert not at_cap and sol.status > 0 and sol.nfev < 200
    brief, brief_at_cap = capped_least_squares(residuals, jacobian, np.array([0.5, 0.4, 0.4, 0.5]), 3, **OPTIONS)
    assert brief_at_cap and brief.nfev == 3
