"""SciPy differential evolution as an imbench plugin.

``scipy.optimize.differential_evolution`` runs in normalised coordinates ``u`` in ``[0, 1]^n``
(``x = lower + u * (upper - lower)``), vectorised: each generation is one
``problem.evaluate`` call on the whole population. ``updating='deferred'`` (required for
vectorised calls), no polishing (a polish would spend evaluations outside the population
logic; the harness has its own ``polish`` step).

Budget: the population has ``NP = max(5, popsize * n_var)`` members and costs ``NP``
evaluations at start and per generation, so ``maxiter = ceil(budget / NP) - 1`` generations
reach the budget; the last generation is trimmed to the remaining evaluations (the members
past the budget cost ``+inf`` and are never accepted). The objective also stops the run if it
is called after the budget is spent, so the run can never overshoot.
"""

from __future__ import annotations

import inspect
import math

import numpy as np
from scipy.optimize import differential_evolution

from benchmark.core.problem import OptimizerOutput, SearchProblem

__all__ = ["minimize"]


class _BudgetSpent(Exception):
    """Raised from the objective when DE asks for more evaluations than the budget allows."""


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    strategy: str = "best1bin",
    popsize: int = 15,
    mutation: float | tuple[float, float] = (0.5, 1.0),
    recombination: float = 0.7,
    init: str = "latinhypercube",
    tol: float = 0.0,
    atol: float = 0.0,
) -> OptimizerOutput:
    """Minimise ``problem`` with SciPy's differential evolution within its evaluation budget.

    ``popsize`` is a multiplier (population = ``max(5, popsize * n_var)``), as in SciPy.
    ``tol``/``atol`` are SciPy's convergence test on the spread of population costs; with the
    default 0 the run only stops early if every member has exactly the same cost.
    """
    n = problem.n_var
    lo, span = problem.lower, problem.upper - problem.lower
    if init not in ("latinhypercube", "random"):
        # 'sobol'/'halton' change the population size; keep the budget arithmetic exact
        raise ValueError(f"scipy_de: init must be 'latinhypercube' or 'random', got {init!r}")
    npop = max(5, int(popsize) * max(1, n))
    maxiter = max(0, math.ceil(problem.remaining / npop) - 1)
    # a (low, high) pair arrives from YAML as a ListConfig: make it a plain tuple for SciPy
    mutation = float(mutation) if np.isscalar(mutation) else tuple(float(m) for m in mutation)

    def cost(u: np.ndarray) -> np.ndarray:
        # vectorized=True: u has shape (n_var, S); return (S,)
        U = np.atleast_2d(np.asarray(u, float).T)
        if problem.exhausted:
            raise _BudgetSpent
        k = min(len(U), problem.remaining)
        c = np.full(len(U), np.inf)
        c[:k] = problem.evaluate(lo + np.clip(U[:k], 0.0, 1.0) * span)
        return c

    generations = 0

    def callback(*args, **kwargs):
        nonlocal generations
        generations += 1
        return False

    rng_kw = "rng" if "rng" in inspect.signature(differential_evolution).parameters else "seed"
    kwargs = {rng_kw: int(seed)}
    try:
        with np.errstate(invalid="ignore", over="ignore"):
            res = differential_evolution(
                cost,
                bounds=[(0.0, 1.0)] * n,
                strategy=strategy,
                maxiter=maxiter,
                popsize=int(popsize),
                tol=float(tol),
                atol=float(atol),
                mutation=mutation,
                recombination=float(recombination),
                init=init,
                polish=False,
                updating="deferred",
                vectorized=True,
                callback=callback,
                **kwargs,
            )
    except _BudgetSpent:
        return OptimizerOutput(x=None, nit=generations, message="evaluation budget spent")
    x = lo + np.clip(res.x, 0.0, 1.0) * span
    msg = "evaluation budget spent" if problem.exhausted else f"scipy stopped: {res.message}"
    return OptimizerOutput(x=x, nit=int(res.nit), message=msg)
