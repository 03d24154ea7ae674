"""NLopt controlled random search (GN_CRS2_LM, Kaelo & Ali 2006) as an imbench plugin.

NLopt asks for one point at a time, so every evaluation is a one-row ``problem.evaluate``
call. The search runs in normalised coordinates ``u`` in ``[0, 1]^n``
(``x = lower + u * (upper - lower)``), starting from the centre of the box (CRS puts ``x0`` in
its initial population; the other members are random).

Budget: ``maxeval`` is set to the budget, and the objective raises ``nlopt.ForcedStop`` if
NLopt asks for a point once the budget is spent, so the run ends exactly at the budget even
where NLopt would overshoot (e.g. while filling a population larger than the budget).

``+inf`` costs are handed to NLopt as a huge finite value (``1e300``): CRS only compares
costs, and finite values keep NLopt's tolerance tests well defined.

Seeding: NLopt has one global generator; ``nlopt.srand(seed)`` is called immediately before
``optimize`` (not thread-safe against other NLopt runs at the same time).
"""

from __future__ import annotations

import nlopt
import numpy as np

from benchmark.core.problem import OptimizerOutput, SearchProblem

__all__ = ["minimize"]

_INF_STANDIN = 1e300


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    population: int | None = None,
    ftol_rel: float = 0.0,
    xtol_rel: float = 0.0,
) -> OptimizerOutput:
    """Minimise ``problem`` with NLopt's GN_CRS2_LM within its evaluation budget.

    ``population`` None (or 0) takes NLopt's default ``10 * (n_var + 1)``; it must be at least
    ``n_var + 1``. ``ftol_rel``/``xtol_rel`` are NLopt's relative stopping tolerances (0 = off,
    the run then spends the whole budget).
    """
    n = problem.n_var
    lo, span = problem.lower, problem.upper - problem.lower
    pop = 0 if population is None else int(population)
    if pop and pop < n + 1:
        raise ValueError(f"nlopt_crs: population must be at least n_var + 1 = {n + 1}, got {pop}")

    best_u, best_c = None, np.inf
    calls = 0

    def objective(u, grad):
        nonlocal best_u, best_c, calls
        if problem.exhausted:
            raise nlopt.ForcedStop
        u = np.clip(np.asarray(u, float), 0.0, 1.0)
        c = problem.evaluate_one(lo + u * span)
        calls += 1
        if c < best_c:
            best_c, best_u = c, u.copy()
        return float(c) if np.isfinite(c) else _INF_STANDIN

    opt = nlopt.opt(nlopt.GN_CRS2_LM, n)
    opt.set_lower_bounds(np.zeros(n))
    opt.set_upper_bounds(np.ones(n))
    opt.set_min_objective(objective)
    opt.set_maxeval(max(1, problem.remaining))
    if pop:
        opt.set_population(pop)
    if ftol_rel:
        opt.set_ftol_rel(float(ftol_rel))
    if xtol_rel:
        opt.set_xtol_rel(float(xtol_rel))
    x0 = np.full(n, 0.5)

    nlopt.srand(int(seed) % 2**32)
    try:
        opt.optimize(x0)
        result = opt.last_optimize_result()
    except nlopt.ForcedStop:
        result = nlopt.FORCED_STOP
    except nlopt.RoundoffLimited:  # NLopt: "the result is still useful"; the harness keeps the best
        result = nlopt.ROUNDOFF_LIMITED
    names = {
        nlopt.MAXEVAL_REACHED: "maxeval reached",
        nlopt.FORCED_STOP: "forced stop at the budget",
        nlopt.FTOL_REACHED: "ftol reached",
        nlopt.XTOL_REACHED: "xtol reached",
        nlopt.STOPVAL_REACHED: "stopval reached",
        nlopt.SUCCESS: "success",
        nlopt.ROUNDOFF_LIMITED: "roundoff limited",
    }
    why = names.get(result, f"nlopt result {result}")
    msg = "evaluation budget spent" if problem.exhausted else f"nlopt stopped: {why}"
    x = None if best_u is None else lo + best_u * span
    return OptimizerOutput(x=x, nit=calls, message=msg)
