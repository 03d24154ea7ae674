"""SciPy's bounded least squares (``trf``) capped at a number of evaluations, without the
Jacobian it takes and never reads at its last point.

``least_squares`` takes a Jacobian at every point it accepts, also at the one that spends its
last allowed evaluation, and then stops without reading it. With finite differences of a
costly model (the diagnosis's local fits: a simulation per parameter) that Jacobian is a whole
iteration's work: a brief fit of six evaluations takes five Jacobians where it took six. The
solver's path and its end are the same, bit for bit (``tests/core/test_capped_least_squares.py``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy import optimize


def capped_least_squares(fun: Callable, jac: Callable, x0: np.ndarray, max_nfev: int,
                         **options) -> tuple[optimize.OptimizeResult, bool]:
    """``scipy.optimize.least_squares(fun, x0, jac=jac, method="trf", max_nfev=max_nfev,
    **options)`` and whether it stopped at ``max_nfev`` (not at a tolerance). ``jac`` is not
    called where the solver would not read its answer (at the point that spent the last
    evaluation); the result's ``jac``, ``grad`` and ``optimality`` are then zeros, its ``x``,
    ``fun``, ``cost`` and ``nfev`` those of the plain call."""
    state = {"evaluations": 0, "residuals": 0, "spent": False}

    def counted(x):
        state["evaluations"] += 1
        f = fun(x)
        state["residuals"] = len(f)
        return f

    def jac_unless_spent(x):
        if state["evaluations"] >= max_nfev:  # the solver stops without reading it
            state["spent"] = True
            return np.zeros((state["residuals"], len(x)))
        return jac(x)

    sol = optimize.least_squares(counted, x0, jac=jac_unless_spent, method="trf", max_nfev=max_nfev, **options)
    # status 0: stopped at max_nfev; a zero Jacobian at the last point reads as gtol's status 1
    return sol, bool(sol.status == 0 or (sol.status == 1 and state["spent"]))
