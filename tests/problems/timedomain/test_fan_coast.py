"""The free coast with a fan load, ``J w' = -(A + B w + C w^2)``, in closed form
(:class:`benchmark.problems.timedomain.diagnosis.free_coast.FreeCoast`): against an ODE solver in
the tangent's regime (``4 A C > B^2``), the hyperbolic one and where the fan load is tiny beside
the viscous friction (where ``(-B + q tan(...)) / (2 C)`` loses the digits it subtracts)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from benchmark.problems.timedomain.diagnosis.free_coast import FreeCoast

T = np.linspace(0.0, 10.0, 10001)
W0 = 150.0


def _solved(J, B, A, C):
    def stopped(t, y):
        return y[0]
    stopped.terminal = True
    sol = solve_ivp(lambda t, y: [-(A + B * y[0] + C * y[0] ** 2) / J], (0.0, T[-1]), [W0], t_eval=T,
                    rtol=1e-12, atol=1e-11, events=stopped)
    out = np.zeros_like(T)
    out[:sol.y.shape[1]] = sol.y[0]
    return out


@pytest.mark.parametrize(("J", "B", "A", "C"), [
    (0.05, 1e-3, 0.5, 1e-4),    # 4AC > B^2: the tangent; stops within the record
    (0.1, 1e-4, 2.0, 1e-3),     # the same, a heavy fan
    (0.05, 5e-3, 0.0, 1e-5),    # no Coulomb friction: 4AC < B^2, the hyperbolic tangent; still turning
    (0.05, 2e-3, 0.5, 1e-13),   # a fan load far below the viscous friction
    (0.02, 2e-3, 0.01, 1e-6),
])
def test_the_fan_coast_is_the_solution_of_its_equation(J, B, A, C):
    w = FreeCoast(T, *(np.array([[v]]) for v in (J, B, A, C))).speed(np.array([[W0]]))[0]
    ref = _solved(J, B, A, C)
    assert np.max(np.abs(w - ref)) < 1e-7  # rad/s, of 150
    stop = np.argmax(ref <= 0) if np.any(ref <= 0) else None
    if stop is not None:
        assert np.all(w[stop + 1:] == 0.0) and np.all(w[:stop - 1] > 0.0)


def test_each_rows_coast_is_its_own_and_the_same_from_a_second_start():
    J, B, A, C = (np.array([[0.05], [0.1], [0.05]]), np.array([[1e-3], [1e-4], [5e-3]]),
                  np.array([[0.5], [2.0], [0.0]]), np.array([[1e-4], [1e-3], [1e-5]]))
    coast = FreeCoast(T, J, B, A, C)
    together = coast.speed(np.full((3, 1), W0))
    for k in range(3):
        alone = FreeCoast(T, J[k:k + 1], B[k:k + 1], A[k:k + 1], C[k:k + 1]).speed(np.array([[W0]]))
        np.testing.assert_array_equal(together[k], alone[0])
    coast.speed(np.full((3, 1), 120.0))
    np.testing.assert_array_equal(coast.speed(np.full((3, 1), W0)), together)
