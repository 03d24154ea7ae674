"""Global stage, then least squares from several starts: the default pipeline.

1. **Global stage** (``global_fraction`` of the budget): differential evolution
   (``current-to-best/1/bin``, dithered ``F``, Latin-hypercube start), vectorised: one
   ``problem.evaluate`` call per generation. Coordinates are normalised to ``[0, 1]`` and
   logarithmic for parameters whose bounds are both positive (``log_scale``), so that a range
   of two decades is searched evenly.
2. **Local stage**: SciPy's trust-region reflective least squares (``trf``) on the residual
   vector from up to ``starts`` points: the best point of the global stage, then the best
   points that lie at least ``min_distance`` (normalised units) from every start already taken.
   The Jacobian is a forward difference whose ``n_var`` points are simulated in one batch
   (``problem.residuals_batch``); every residual vector is one counted evaluation.
   The local stage stops early once two starts reach the same cost (relative ``agree_rtol``):
   the minimum is confirmed from two basins.

The run ends ``converged`` when the local stage stopped on SciPy's tolerances (the message
says how many starts agreed), or when the budget is spent. A problem without a residual vector
gets the global stage only, on the whole budget. Deterministic for a given ``seed``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from benchmark.core.problem import BudgetExhausted, OptimizerOutput, SearchProblem

__all__ = ["minimize"]


class _Coordinates:
    """Normalised coordinates ``u`` in [0, 1]: logarithmic where both bounds are positive."""

    def __init__(self, lower, upper, log_scale: bool):
        self.lo, self.hi = np.asarray(lower, float), np.asarray(upper, float)
        self.log = (self.lo > 0) & (self.hi > 0) & bool(log_scale)
        self.a = np.where(self.log, np.log(np.where(self.log, self.lo, 1.0)), self.lo)
        self.b = np.where(self.log, np.log(np.where(self.log, self.hi, 1.0)), self.hi)

    def to_x(self, U):
        U = np.clip(U, 0.0, 1.0)
        y = self.a + U * (self.b - self.a)
        x = np.where(self.log, np.exp(y), y)
        return np.clip(x, self.lo, self.hi)

    def to_u(self, X):
        X = np.clip(np.asarray(X, float), self.lo, self.hi)
        y = np.where(self.log, np.log(np.where(self.log, X, 1.0)), X)
        return np.clip((y - self.a) / (self.b - self.a), 0.0, 1.0)


def _latin_hypercube(rng, n: int, d: int) -> np.ndarray:
    U = (rng.random((n, d)) + np.arange(n)[:, None]) / n
    for j in range(d):
        U[:, j] = U[rng.permutation(n), j]
    return U


def _global_stage(problem, coords, rng, budget: int, popsize: int, cr: float):
    """Differential evolution within ``budget`` evaluations; returns all (U, cost) evaluated."""
    d = problem.n_var
    npop = max(8, popsize * d)
    budget = min(budget, problem.remaining)
    if budget < npop:
        npop = max(1, budget)
    U = _latin_hypercube(rng, npop, d)
    f = np.asarray(problem.evaluate(coords.to_x(U)), float)
    f = np.where(np.isfinite(f), f, np.inf)
    seen_U, seen_f = [U.copy()], [f.copy()]
    used = npop
    gens = 0
    while used + npop <= budget:
        best = U[int(np.argmin(f))]
        F = rng.uniform(0.5, 1.0)
        idx = np.array([rng.choice(np.delete(np.arange(npop), i), 2, replace=False) for i in range(npop)])
        mutant = U + F * (best - U) + F * (U[idx[:, 0]] - U[idx[:, 1]])
        mutant = np.where(mutant < 0, rng.random(mutant.shape) * U, mutant)  # bounce back inside
        mutant = np.where(mutant > 1, U + rng.random(mutant.shape) * (1 - U), mutant)
        cross = rng.random((npop, d)) < cr
        cross[np.arange(npop), rng.integers(0, d, npop)] = True
        trial = np.where(cross, mutant, U)
        ft = np.asarray(problem.evaluate(coords.to_x(trial)), float)
        ft = np.where(np.isfinite(ft), ft, np.inf)
        used += npop
        gens += 1
        better = ft <= f
        U[better], f[better] = trial[better], ft[better]
        seen_U.append(trial)
        seen_f.append(ft)
    return np.concatenate(seen_U), np.concatenate(seen_f), gens


def _pick_starts(U, f, starts: int, min_distance: float) -> list[np.ndarray]:
    order = np.argsort(f, kind="stable")
    chosen: list[np.ndarray] = []
    for k in order:
        if not np.isfinite(f[k]):
            break
        if all(np.max(np.abs(U[k] - c)) >= min_distance for c in chosen):
            chosen.append(U[k].copy())
        if len(chosen) >= starts:
            break
    return chosen


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    global_fraction: float = 0.4,
    popsize: int = 10,
    crossover: float = 0.9,
    starts: int = 4,
    min_distance: float = 0.1,
    agree_rtol: float = 1e-6,
    log_scale: bool = True,
    diff_step: float = 1e-7,
    ftol: float = 1e-10,
    xtol: float = 1e-10,
    gtol: float = 1e-10,
    nonfinite_residual: float = 1e6,
) -> OptimizerOutput:
    """Differential evolution on ``global_fraction`` of the budget, then trf least squares
    from up to ``starts`` distinct good points (see the module docstring)."""
    if not 0.0 < float(global_fraction) <= 1.0:
        raise ValueError(f"multistart: global_fraction must be in (0, 1], got {global_fraction}")
    if int(starts) < 1:
        raise ValueError(f"multistart: starts must be >= 1, got {starts}")
    rng = np.random.default_rng(seed)
    coords = _Coordinates(problem.lower, problem.upper, log_scale)
    total = problem.remaining
    g_budget = total if not problem.has_residuals else max(1, int(math.floor(global_fraction * total)))
    try:
        U, f, gens = _global_stage(problem, coords, rng, g_budget, int(popsize), float(crossover))
    except BudgetExhausted:
        return OptimizerOutput(x=None, nit=0, message="evaluation budget spent in the global stage")
    if not problem.has_residuals:
        return OptimizerOutput(x=coords.to_x(U[int(np.argmin(f))]), nit=gens,
                               message="global stage only: the problem has no residual vector")
    big = float(nonfinite_residual)
    step = float(diff_step)

    def rows(Uq):
        """Residual vectors of a batch, every row counted; when the batch does not fit the budget
        the rows that fit are evaluated (so the run ends exactly at the budget), then
        BudgetExhausted."""
        X = coords.to_x(np.atleast_2d(Uq))
        k = min(len(X), problem.remaining)
        if k == 0:
            raise BudgetExhausted(f"budget of {problem.budget} evaluations spent")
        R = np.asarray(problem.residuals_batch(X[:k]), float).reshape(k, -1)
        if k < len(X):
            raise BudgetExhausted(f"budget of {problem.budget} evaluations spent")
        return np.where(np.isfinite(R), R, big)

    results = []  # (sum of squares, u, scipy status message)
    nit = gens
    message = ""
    for k, u0 in enumerate(_pick_starts(U, f, int(starts), float(min_distance))):
        cache: dict = {}

        def fun(u, cache=cache):
            r = rows(u[None, :])[0]
            cache["u"], cache["r"] = np.array(u, float), r
            return r

        def jac(u, cache=cache):
            r0 = cache["r"] if "u" in cache and np.array_equal(cache["u"], u) else fun(u)
            h = np.where(u + step > 1.0, -step, step)
            R = rows(u[None, :] + np.diag(h))
            return ((R - r0[None, :]) / h[:, None]).T

        try:
            sol = least_squares(fun, u0, jac=jac, bounds=(0.0, 1.0), method="trf", x_scale="jac", ftol=ftol,
                                xtol=xtol, gtol=gtol, max_nfev=max(1, problem.remaining))
        except BudgetExhausted:
            message = f"evaluation budget spent in local start {k + 1}"
            break
        nit += int(sol.nfev)
        ss = float(sol.cost * 2)
        results.append((ss, sol.x, sol.message))
        best = min(r[0] for r in results)
        agree = [r for r in results if abs(r[0] - best) <= agree_rtol * max(best, 1e-300)]
        if len(agree) >= 2:
            message = (f"converged: {len(agree)} of {len(results)} least-squares starts reached the same "
                       f"minimum ({sol.message})")
            break
    if not results:
        return OptimizerOutput(x=None, nit=nit, message=message or "no local start completed")
    ss, u, msg = min(results, key=lambda r: r[0])
    if not message:
        message = f"converged: best of {len(results)} least-squares starts ({msg}); no two starts agreed"
    return OptimizerOutput(x=coords.to_x(u), nit=nit, message=message)
