"""SciPy trust-region least squares (``scipy.optimize.least_squares``, method ``trf``) as a plugin.

A local method: it starts from ``problem.crude_start()`` (the documented crude start, the
geometric centre of the bounds for positive bounds) and works on the problem's residual
vector, in normalised coordinates ``u`` in ``[0, 1]^n`` (``x = lower + u * (upper - lower)``)
with the box as bounds and ``x_scale='jac'`` by default.

The Jacobian is a forward difference with step ``diff_step`` (in normalised units, i.e. a
fraction of each range; taken inwards at the upper bound) whose ``n_var`` points are simulated
in ONE batch (``problem.residuals_batch``). Every residual vector, Jacobian points included, is
one counted evaluation.

Budget: the harness raises ``BudgetExhausted`` once the budget is spent; when the last
Jacobian does not fit, the points that still fit are evaluated (so the run ends at exactly the
budget) and the run stops. ``max_nfev`` is also set to the budget, but SciPy counts only
residual calls at trial points in it, not Jacobians, so it is only a second guard. When trf
meets its own tolerances first, the run ends before the budget and the message says so.

Non-finite residuals (a diverging simulation) are replaced by ``nonfinite_residual`` so that
trf sees a large, finite misfit and its trust region just shrinks.

Problems without a residual vector: with ``no_residuals: sqrt_cost`` (default) the plugin
minimises the one-element residual ``sqrt(cost)`` (valid for non-negative costs; a negative
cost raises a clear error), with ``no_residuals: error`` it refuses to run.

``seed`` is accepted for the plugin interface and unused: the method is deterministic.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from benchmark.core.problem import BudgetExhausted, OptimizerOutput, SearchProblem

__all__ = ["minimize"]


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    ftol: float = 1e-8,
    xtol: float = 1e-8,
    gtol: float = 1e-8,
    x_scale: str | float = "jac",
    diff_step: float = 1e-7,
    loss: str = "linear",
    f_scale: float = 1.0,
    nonfinite_residual: float = 1e6,
    no_residuals: str = "sqrt_cost",
) -> OptimizerOutput:
    """Minimise the residual vector of ``problem`` with SciPy's trf from the crude start."""
    del seed  # deterministic method
    lo, span = problem.lower, problem.upper - problem.lower
    big = float(nonfinite_residual)
    if not (np.isfinite(big) and big > 0):
        raise ValueError(f"least_squares: nonfinite_residual must be a positive finite number, got {big}")
    step = float(diff_step)
    if not (0.0 < step < 0.5):
        raise ValueError(f"least_squares: diff_step must be in (0, 0.5) (normalised units), got {step}")
    if not problem.has_residuals:
        if no_residuals == "error":
            raise ValueError(
                "least_squares: this plugin needs a residual vector, and the problem has none "
                "(set no_residuals: sqrt_cost to minimise sqrt(cost) instead)"
            )
        if no_residuals != "sqrt_cost":
            raise ValueError(
                f"least_squares: no_residuals must be 'sqrt_cost' or 'error', got {no_residuals!r}"
            )

    def residual_rows(U: np.ndarray) -> np.ndarray:
        """Residual vectors at the rows of U (normalised), one batch; every row counted. If not
        all rows fit the budget, the ones that fit are evaluated, then BudgetExhausted."""
        X = lo + np.clip(np.atleast_2d(U), 0.0, 1.0) * span
        k = min(len(X), problem.remaining)
        if k == 0:
            raise BudgetExhausted(f"budget of {problem.budget} evaluations spent")
        if problem.has_residuals:
            if hasattr(problem, "residuals_batch"):
                R = np.asarray(problem.residuals_batch(X[:k]), float).reshape(k, -1)
            else:
                R = np.stack([np.asarray(problem.residuals(x), float).ravel() for x in X[:k]])
        else:
            c = problem.evaluate(X[:k])
            if np.any(c < 0):
                raise ValueError(
                    f"least_squares: the problem has no residual vector and its cost is negative "
                    f"({c.min():g}), so sqrt(cost) cannot stand in for one; use a global optimiser"
                )
            R = np.sqrt(c)[:, None]
        if k < len(X):
            raise BudgetExhausted(f"budget of {problem.budget} evaluations spent")
        return np.where(np.isfinite(R), R, big)

    cache: dict[str, np.ndarray] = {}

    def fun(u: np.ndarray) -> np.ndarray:
        r = residual_rows(u[None, :])[0]
        cache["u"], cache["r"] = np.array(u, float), r
        return r

    def jac(u: np.ndarray) -> np.ndarray:
        # trf asks for the Jacobian at the point whose residuals it just computed
        r0 = cache["r"] if "u" in cache and np.array_equal(cache["u"], u) else fun(u)
        h = np.where(u + step > 1.0, -step, step)  # inwards at the upper bound
        R = residual_rows(u[None, :] + np.diag(h))
        return ((R - r0[None, :]) / h[:, None]).T

    u0 = np.clip((problem.crude_start() - lo) / span, 0.0, 1.0)
    x_scale = x_scale if isinstance(x_scale, str) else float(x_scale)
    try:
        res = least_squares(
            fun,
            u0,
            jac=jac,
            bounds=(np.zeros_like(u0), np.ones_like(u0)),
            method="trf",
            ftol=ftol,
            xtol=xtol,
            gtol=gtol,
            x_scale=x_scale,
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
    # trf makes one residual evaluation per iteration (Jacobians aside): nfev = iterations
    return OptimizerOutput(x=x, nit=int(res.nfev), message=msg)
