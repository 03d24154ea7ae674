"""Least squares on a residual vector in coordinates normalised to the bounds.

``polish``: SciPy least squares from an optimiser's best point, with a forward-difference
Jacobian whose ``n_var`` points are simulated in one batch; every residual vector counts as
one evaluation of the polish's own budget, reported beside the optimiser's. The same routine
fits the augmented models of the sim-to-real diagnosis.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy import optimize

from benchmark.core.budget import BudgetedProblem
from benchmark.core.problem import BudgetExhausted, Problem

#: Residuals of a diverged candidate are replaced by this, so the trust region just shrinks.
DIVERGED_RESIDUAL = 1e6


def least_squares_batch(residuals_batch: Callable[[np.ndarray], np.ndarray], x0: np.ndarray, lower: np.ndarray,
                        upper: np.ndarray, max_evaluations: int, rel_step: float = 1e-7) -> tuple[np.ndarray, str]:
    """Minimise ``|r(x)|^2`` within the bounds from ``x0``.

    ``residuals_batch(X)`` maps candidates (n, n_var) to residual vectors (n, m); it is
    called with one point for the trust-region steps and with ``n_var`` points for each
    forward-difference Jacobian. Returns the last accepted point and SciPy's message (or the
    reason it stopped: ``BudgetExhausted``). Callers that need the best point ever tried
    track it inside ``residuals_batch`` (as :class:`BudgetedProblem` does).
    """
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    span = hi - lo

    def to_x(u):
        return lo + np.clip(u, 0.0, 1.0) * span

    def clean(R):
        return np.where(np.isfinite(R), R, DIVERGED_RESIDUAL)

    cache: dict = {}

    def fun(u):
        r = clean(residuals_batch(to_x(u)[None, :])[0])
        cache["u"], cache["r"] = u.copy(), r
        return r

    def jac(u):
        r0 = cache["r"] if "u" in cache and np.array_equal(cache["u"], u) else fun(u)
        h = rel_step * np.maximum(np.abs(u), 1e-3)
        h = np.where(u + h > 1.0, -h, h)  # step inwards at the upper bound
        R = clean(residuals_batch(to_x(u[None, :] + np.diag(h))))
        return ((R - r0[None, :]) / h[:, None]).T

    u0 = np.clip((np.asarray(x0, float) - lo) / span, 0.0, 1.0)
    try:
        sol = optimize.least_squares(fun, u0, jac=jac, bounds=(0.0, 1.0), method="trf", x_scale="jac",
                                     xtol=1e-12, ftol=1e-12, gtol=1e-12,
                                     max_nfev=max(1, max_evaluations // (len(u0) + 1)))
        return to_x(sol.x), sol.message
    except BudgetExhausted as exc:
        return to_x(cache.get("u", u0)), str(exc)


def polish_least_squares(problem: Problem, x0: np.ndarray, budget: int, rel_step: float = 1e-7) -> BudgetedProblem:
    """Polish from ``x0`` within ``budget`` evaluations; returns the counting wrapper, whose
    ``best_x``/``best_cost`` (the problem's own cost) and ``nfev`` are the polish's result."""
    bp = BudgetedProblem(problem, budget)
    _, bp.message = least_squares_batch(bp.residuals_batch, x0, bp.lower, bp.upper, budget, rel_step)
    return bp
