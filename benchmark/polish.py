"""``polish``: SciPy least squares on the residual vector, from an optimiser's best point.

It runs in coordinates normalised to the bounds, with a forward-difference Jacobian whose
``n_var`` points are simulated in one batch; every residual vector counts as one evaluation
of the polish's own budget, reported beside the optimiser's.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

from benchmark.problem import BudgetedProblem, BudgetExhausted, Problem

#: Residuals of a diverged candidate are replaced by this, so the trust region just shrinks.
DIVERGED_RESIDUAL = 1e6


def polish_least_squares(problem: Problem, x0: np.ndarray, budget: int, rel_step: float = 1e-7) -> BudgetedProblem:
    """Minimise the residual sum of squares from ``x0``; returns the counting wrapper, whose
    ``best_x``/``best_cost`` (the problem's own cost) and ``nfev`` are the polish's result."""
    bp = BudgetedProblem(problem, budget)
    lo, hi = bp.lower, bp.upper
    span = hi - lo

    def to_x(u):
        return lo + np.clip(u, 0.0, 1.0) * span

    def clean(R):
        return np.where(np.isfinite(R), R, DIVERGED_RESIDUAL)

    def fun(u):
        return clean(bp.residuals(to_x(u)))

    def jac(u, r0):
        h = rel_step * np.maximum(np.abs(u), 1e-3)
        # step inwards at the upper bound
        h = np.where(u + h > 1.0, -h, h)
        U = u[None, :] + np.diag(h)
        R = clean(bp.residuals_batch(to_x(U)))
        return ((R - r0[None, :]) / h[:, None]).T

    u0 = np.clip((np.asarray(x0, float) - lo) / span, 0.0, 1.0)
    cache = {}

    def fun_cached(u):
        r = fun(u)
        cache["u"], cache["r"] = u.copy(), r
        return r

    def jac_cached(u):
        r0 = cache["r"] if "u" in cache and np.array_equal(cache["u"], u) else fun(u)
        return jac(u, r0)

    try:
        sol = optimize.least_squares(fun_cached, u0, jac=jac_cached, bounds=(0.0, 1.0), method="trf",
                                     x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12,
                                     max_nfev=max(1, budget // (bp.n_var + 1)))
        bp.message = sol.message
    except BudgetExhausted as exc:
        bp.message = str(exc)
    return bp
