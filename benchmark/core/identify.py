"""The one run sequence of an identification: the optimiser plugin on the counting wrapper,
then (optionally) the least-squares polish from its best point, keeping the better point.

The harness (with its journal, time limit and progress bar) and the diagnosis's base
identification both go through :func:`polish_and_keep_better`; :func:`identify` is the whole
sequence for callers that need no checkpoint.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from benchmark.core.budget import BudgetedProblem, run_plugin
from benchmark.core.polish import polish_least_squares
from benchmark.core.problem import OptimizeResult, Problem


@dataclass
class Identification:
    """What one identification produced.

    Attributes
    ----------
    result : the optimiser's fixed result record (its own evaluations and status).
    x : the better of the optimiser's and the polish's best points (searched parameters), or None.
    cost : the cost at ``x`` (the problem's own cost).
    polish : what the polish did (evaluations, cost before/after, wall time, SciPy's message), or None.
    history : (evaluations, best cost, phase) after every improvement; phase ``optimizer`` or ``polish``.
    status : how the whole sequence ended (:func:`final_status`): the polish's termination when a
        polish ran (``converged`` when SciPy's tolerances stopped it, ``budget_spent`` when its
        budget did), else the optimiser's status.
    """

    result: OptimizeResult
    x: np.ndarray | None
    cost: float
    polish: dict | None = None
    history: list[tuple[int, float, str]] = field(default_factory=list)
    status: str = ""

    def __post_init__(self):
        if not self.status:
            self.status = self.result.status.value


#: Substrings of SciPy ``least_squares`` messages that mean its tolerances were met.
_CONVERGED_MESSAGES = ("`ftol` termination", "`xtol` termination", "`gtol` termination", "Both `ftol` and `xtol`")


def polish_converged(message: str) -> bool:
    """True when a polish message is one of SciPy's tolerance terminations."""
    return any(m in str(message) for m in _CONVERGED_MESSAGES)


def final_status(result: OptimizeResult, polish: dict | None) -> str:
    """How a run really ended: with a polish that ran from the optimiser's point, ``converged``
    when the polish met its tolerances and ``budget_spent`` when it ran out of evaluations; a
    failed or timed-out optimiser keeps its status; no polish: the optimiser's status."""
    status = result.status.value
    if not polish or not polish.get("evaluations") or status in ("failed", "timeout"):
        return status
    return "converged" if polish.get("converged") else "budget_spent"


def polish_and_keep_better(problem: Problem, result: OptimizeResult, budgeted: BudgetedProblem,
                           polish_budget: int | None) -> Identification:
    """Polish from the optimiser's best point within ``polish_budget`` evaluations (None: no
    polish) and keep whichever point has the lower cost."""
    history = [(e, c, "optimizer") for e, c in zip(budgeted.history.evaluations, budgeted.history.best_cost,
                                                   strict=True)]
    out = Identification(result=result, x=result.x, cost=result.fun, history=history)
    if polish_budget is None:
        return out
    if not problem.has_residuals:
        out.polish = {"evaluations": 0, "message": f"problem {problem.name!r} has no residual vector"}
        return out
    if result.x is None:
        return out
    t0 = time.perf_counter()
    pol = polish_least_squares(problem, result.x, int(polish_budget))
    out.polish = {"evaluations": pol.nfev, "cost_before": result.fun, "cost_after": pol.best_cost,
                  "wall_time_s": time.perf_counter() - t0, "message": pol.message,
                  "improved": bool(pol.best_x is not None and pol.best_cost < result.fun),
                  "converged": polish_converged(pol.message)}
    out.status = final_status(result, out.polish)
    out.history += [(result.nfev + e, c, "polish") for e, c in zip(pol.history.evaluations, pol.history.best_cost,
                                                                    strict=True)]
    if pol.best_x is not None and pol.best_cost <= out.cost:
        out.x, out.cost = pol.best_x, pol.best_cost
    return out


def identify(problem: Problem, plugin, *, budget: int, seed: int, name: str, polish_budget: int | None = None,
             time_limit_s: float | None = None) -> Identification:
    """The optimiser ``plugin`` within ``budget`` evaluations, then the polish (see
    :func:`polish_and_keep_better`)."""
    budgeted = BudgetedProblem(problem, budget)
    result = run_plugin(plugin, budgeted, seed=seed, name=name, time_limit_s=time_limit_s)
    return polish_and_keep_better(problem, result, budgeted, polish_budget)
