"""SciPy trust-region least squares (``scipy.optimize.least_squares``, method ``trf``) as a plugin.

A local method: it starts from ``problem.crude_start()`` (the documented crude start, the
geometric centre of the bounds for positive bounds) and works on the problem's residual
vector, in normalised coordinates ``u`` in ``[0, 1]^n`` (``x = lower + u * (upper - lower)``)
with the box as bounds and ``x_scale='jac'`` by default. The Jacobian is by finite
differences; every residual evaluation, Jacobian columns included, is one counted evaluation.

Budget: ``problem.residuals`` raises ``BudgetExhausted`` once the budget is spent; the plugin
catches it and ends the run there. ``max_nfev`` is also set to the budget, but SciPy does not
count finite-difference Jacobian evaluations in it, so it is only a second guard. When trf
meets its own tolerances first, the run ends before the budget and the message says so.

Non-finite residuals (a diverging simulation) are replaced by ``nonfinite_residual`` so that
trf sees a large, finite misfit and keeps going.

Problems without a residual vector: with ``no_residuals: sqrt_cost`` (default) the plugin
minimises the one-element residual ``sqrt(cost)`` (valid for non-negative costs; a negative
cost raises a clear error), with ``no_residuals: error`` it refuses to run.

``seed`` is accepted for the plugin interface and unused: the method is deterministic.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from benchmark.problem import BudgetedProblem, BudgetExhausted, OptimizerOutput

__all__ = ["minimize"]


def minimize(
    problem: BudgetedProblem,
    *,
    seed: int,
    ftol: float = 1e-8,
    xtol: float = 1e-8,
    gtol: float = 1e-8,
    x_scale: str | float = "jac",
    diff_step: float | None = None,
    loss: str = "linear",
    f_scale: float = 1.0,
    nonfinite_residual: float = 1e6,
    no_residuals: str = "sqrt_cost",
) -> OptimizerOutput:
    """Minimise the residual vector of ``problem`` with SciPy's trf from the crude start."""
    del seed  # deterministic method
    n = problem.n_var
    lo, span = problem.lower, problem.upper - problem.lower
    big = float(nonfinite_residual)
    if not (np.isfinite(big) and big > 0):
        raise ValueError(f"least_squares: nonfinite_residual must be a positive finite number, got {big}")

    if problem.has_residuals:

        def raw(x: np.ndarray) -> np.ndarray:
            return np.asarray(problem.residuals(x), float).ravel()

    elif no_residuals == "sqrt_cost":

        def raw(x: np.ndarray) -> np.ndarray:
            if problem.exhausted:
                raise BudgetExhausted(f"budget of {problem.budget} evaluations spent")
            c = problem.evaluate_one(x)
            if c < 0:
                raise ValueError(
                    f"least_squares: the problem has no residual vector and its cost is negative "
                    f"({c:g}), so sqrt(cost) cannot stand in for one; use a global optimiser"
                )
            return np.array([np.sqrt(c)])

    elif no_residuals == "error":
        raise ValueError(
            "least_squares: this plugin needs a residual vector, and the problem has none "
            "(set no_residuals: sqrt_cost to minimise sqrt(cost) instead)"
        )
    else:
        raise ValueError(f"least_squares: no_residuals must be 'sqrt_cost' or 'error', got {no_residuals!r}")

    def fun(u: np.ndarray) -> np.ndarray:
        r = raw(lo + np.clip(u, 0.0, 1.0) * span)
        return np.where(np.isfinite(r), r, big)

    u0 = np.clip((problem.crude_start() - lo) / span, 0.0, 1.0)
    x_scale = x_scale if isinstance(x_scale, str) else float(x_scale)
    try:
        res = least_squares(
            fun,
            u0,
            bounds=(np.zeros(n), np.ones(n)),
            method="trf",
            ftol=ftol,
            xtol=xtol,
            gtol=gtol,
            x_scale=x_scale,
            diff_step=diff_step,
            loss=loss,
            f_scale=float(f_scale),
            max_nfev=max(1, problem.remaining),
        )
    except BudgetExhausted:
        # the harness reports the best point it counted; trf's iterate is lost with the exception
        return OptimizerOutput(x=None, nit=0, message="evaluation budget spent")
    x = lo + np.clip(res.x, 0.0, 1.0) * span
    if problem.exhausted:
        msg = "evaluation budget spent"
    else:
        msg = f"converged before the budget: {res.message}"
    # trf makes one residual evaluation per iteration (Jacobian columns aside): nfev = iterations
    return OptimizerOutput(x=x, nit=int(res.nfev), message=msg)
