"""Global stage, least squares from starts of two kinds, then the cost itself: the default pipeline.

1. **Global stage** (``global_fraction`` of the budget): differential evolution
   (``current-to-best/1/bin``, dithered ``F``) from a Latin-hypercube sample of
   ``popsize * n_var`` points, vectorised: one ``problem.evaluate`` call per generation.
   Coordinates are normalised to ``[0, 1]`` and logarithmic for parameters whose bounds are
   both positive (``log_scale``), so that a range of two decades is searched evenly.
2. **Local stage**: SciPy's least squares (``method``: ``trf``) on the residual vector, from
   starts of two kinds taken in turn: the best points of the differential evolution, and points
   of its Latin-hypercube sample (``sample_order``: ``spread``, the one of the sample's better
   half farthest from every start so far; ``cost``: in order of cost); every start at least
   ``min_distance`` normalised units from the others, each spending at most ``local_fraction``
   of the budget. The Jacobian is a forward difference whose ``n_var`` points are simulated in
   one batch (``problem.residuals_batch``); every residual vector is one counted evaluation.
3. **Cost stage**, when the problem's cost is not the sum of squares least squares minimised
   (eq. 15's absolute errors: a nearby but different minimum, 0.7 % lower on a quantised speed
   record, 18 % on a noise-free one): local CMA-ES runs on the cost itself in the Gauss-Newton
   metric of the best minimum (:func:`_cost_stage`), within ``cost_fraction`` of the budget,
   which the local stage leaves for it.

Why two kinds of start: differential evolution converges as one population, so its best points
share one basin, and on records dominated by the steady state that basin can be a broad false
one (issue 38: a motulator direct-on-line start of a 5 hp motor, speed quantised at 0.5 rad/s:
``J`` at its lower bound, cost 33 times the truth's; two starts from the population agreed and
the previous default called it converged); least squares from 14 of 20 Latin-hypercube points
reached the truth there. The best points of the sample by cost also sit in the broad basin
more often than not, hence ``spread``. A minimum is **confirmed** when ``confirm`` starts
reached it (the same sum of squares within ``agree_rtol``), ``sample_confirm`` of them from the
sample; the local stage stops then. ``result.json``'s ``message`` says how the minimum was
confirmed, or, when it was not (budget or starts used up), that it may not be the global minimum
and what to run instead: that warning is multistart's own.

``sample_starts=false, starts=4, cost_fraction=0, local_fraction=1, global_fraction=0.4``
reproduces the previous default bit for bit (the suite measures it as ``multistart_previous``).
The run ends ``converged`` when the plugin stopped before the budget (the message says whether
the minimum was confirmed), else ``budget_spent``. A problem without a residual vector gets the
global stage only, on the whole budget. Deterministic for a given ``seed``.
"""

from __future__ import annotations

import math
import threading
import warnings

import numpy as np
from scipy.optimize import least_squares

from benchmark.core.problem import BudgetExhausted, OptimizerOutput, SearchProblem

__all__ = ["minimize"]

#: What a run that ends unconfirmed tells the user to try (the suite's results/suite/README.md).
ADVICE = "budget=30000, or optimizer=cmaes polish=true"
#: The cost stage's CMA-ES draws from NumPy's global random state (seeded, then restored): runs in
#: other threads wait for it, so that runs side by side give what each gives alone.
_GLOBAL_RNG = threading.Lock()


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


class _Reserved(Exception):
    """A least-squares start stopped so that the cost stage keeps its share of the budget."""


def _latin_hypercube(rng, n: int, d: int) -> np.ndarray:
    U = (rng.random((n, d)) + np.arange(n)[:, None]) / n
    for j in range(d):
        U[:, j] = U[rng.permutation(n), j]
    return U


def _finite(f) -> np.ndarray:
    f = np.asarray(f, float)
    return np.where(np.isfinite(f), f, np.inf)


def _global_stage(problem, coords, rng, budget: int, popsize: int, cr: float):
    """Differential evolution within ``budget`` evaluations. Returns the Latin-hypercube
    sample (U, cost), every point evaluated (U, cost) and the number of generations."""
    d = problem.n_var
    npop = max(8, popsize * d)
    budget = min(budget, problem.remaining)
    if budget < npop:
        npop = max(1, budget)
    U = _latin_hypercube(rng, npop, d)
    f = _finite(problem.evaluate(coords.to_x(U)))
    sample = (U.copy(), f.copy())
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
        ft = _finite(problem.evaluate(coords.to_x(trial)))
        used += npop
        gens += 1
        better = ft <= f
        U[better], f[better] = trial[better], ft[better]
        seen_U.append(trial)
        seen_f.append(ft)
    return sample, (np.concatenate(seen_U), np.concatenate(seen_f)), gens


class _Starts:
    """Start points of the two kinds, taken in turn (evolution first), each at least
    ``min_distance`` (max-norm, normalised units) from every start already taken."""

    def __init__(self, evolved, sample, min_distance: float, spread: bool = False):
        self.pools = {"evolution": self._ordered(*evolved), "sample": self._ordered(*sample) if sample else []}
        if spread and self.pools["sample"]:  # the better half of the sample, taken farthest first
            self.pools["sample"] = self.pools["sample"][:max(1, len(self.pools["sample"]) // 2)]
        self.spread = bool(spread)
        self.min_distance = float(min_distance)
        self.taken: list[np.ndarray] = []
        self.turn = 0

    @staticmethod
    def _ordered(U, f):
        order = np.argsort(f, kind="stable")
        return [U[k] for k in order if np.isfinite(f[k])]

    def _next_from(self, kind):
        pool = self.pools[kind]
        if kind == "sample" and self.spread and pool and self.taken:
            far = [min(np.max(np.abs(u - c)) for c in self.taken) for u in pool]
            pool.insert(0, pool.pop(int(np.argmax(far))))
        while pool:
            u = pool.pop(0)
            if all(np.max(np.abs(u - c)) >= self.min_distance for c in self.taken):
                return u
        return None

    def next(self):
        """(kind, u) of the next start, or None when both pools are used up."""
        kinds = ("evolution", "sample")
        for k in range(2):
            kind = kinds[(self.turn + k) % 2]
            u = self._next_from(kind)
            if u is not None:
                self.turn = (self.turn + k + 1) % 2
                self.taken.append(u.copy())
                return kind, u
        return None


def _minima(results, rtol: float) -> list[dict]:
    """Local results grouped into minima (sums of squares within ``rtol``), best first."""
    groups: list[dict] = []
    for ss, u, kind, msg, jac in sorted(results, key=lambda r: r[0]):
        g = groups[-1] if groups else None
        if g is not None and abs(ss - g["ss"]) <= rtol * max(g["ss"], 1e-300):
            g["kinds"].append(kind)
        else:
            groups.append({"ss": ss, "u": u, "kinds": [kind], "message": msg, "jac": jac})
    return groups


def _confirmed(best: dict, confirm: int, from_sample: int = 1) -> bool:
    return len(best["kinds"]) >= confirm and best["kinds"].count("sample") >= from_sample


def _summary(minima: list[dict], n_starts: int, confirm: int, from_sample: int = 1) -> str:
    best = minima[0]
    n_sample = best["kinds"].count("sample")
    head = (f"the best minimum (sum of squares {best['ss']:.6g}) was reached from {len(best['kinds'])} of "
            f"{n_starts} least-squares starts, {n_sample} from the space-filling sample")
    others = ", ".join(f"{m['ss']:.4g} ({len(m['kinds'])})" for m in minima[1:4])
    tail = f"; other minima: {others}" if others else ""
    if _confirmed(best, confirm, from_sample):
        return f"converged: {head} ({best['message']}){tail}"
    need = f"{confirm}, {from_sample} from the sample" if from_sample else str(confirm)
    return (f"not confirmed: {head} (confirmation needs {need}){tail}; it may not "
            f"be the global minimum: try {ADVICE}")


def _cost_stage(problem, coords, best: dict, seed: int, budget: int, sigma0: float, rtol: float,
                runs: int = 3) -> str:
    """Local CMA-ES on the problem's own cost around the best minimum, when that cost is not the
    sum of squares least squares minimised (eq. 15's absolute errors): coordinates
    ``u = u_b + L z`` with ``L L^T`` the minimum's Gauss-Newton covariance ``s^2 (J^T J)^-1``
    (standard errors as the unit, capped at 0.1 normalised units) and ``u_b`` the best point so
    far, from ``z = 0`` with step ``sigma0``, until cma's own tolerances (``tolfun`` = ``rtol``
    times the cost). Up to ``runs`` runs, each from the last one's best point, while a run still
    lowers the cost by more than 1e-6 (a nonsmooth cost can hold a run on a ridge); all within
    ``budget`` evaluations. The harness keeps the best point evaluated. Returns what it did, for
    the message ('' when the cost is the sum of squares)."""
    u_b, J, n = np.array(best["u"], float), best["jac"], problem.n_var
    c0 = float(problem.evaluate(coords.to_x(u_b[None, :]))[0])
    if not np.isfinite(c0) or abs(c0 - best["ss"]) <= 1e-9 * max(abs(c0), 1e-300) or budget < 2 * (n + 4):
        return ""
    s2 = best["ss"] / max(J.shape[0] - n, 1)
    w, V = np.linalg.eigh(np.linalg.pinv(J.T @ J) * s2)
    L = V * np.sqrt(np.clip(w, 0.0, 0.01))
    import cma  # here, not at the top: its import (1.4 s, scipy.stats, pyplot) only where the stage runs

    n_cma = max(n, 2)  # cma 4.5 fails in 1-D
    seeds = np.random.SeedSequence(int(seed)).generate_state(int(runs))
    used, best_c, done = 1, c0, 0
    with _GLOBAL_RNG:  # cma samples with NumPy's global state: one such stage at a time
        saved = np.random.get_state()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                for k in range(int(runs)):
                    start_c = best_c
                    opts = {"seed": int(seeds[k]) % (2**31 - 2) + 1, "maxfevals": int(budget - used),
                            "tolfun": float(rtol) * abs(best_c), "tolx": 1e-6, "verbose": -9, "verb_log": 0,
                            "verb_disp": 0}
                    es = cma.CMAEvolutionStrategy(np.zeros(n_cma), float(sigma0), opts)
                    origin = u_b.copy()
                    while not es.stop() and used < budget and problem.remaining > 0:
                        Z = es.ask()
                        U = np.clip(origin[None, :] + np.asarray(Z, float)[:, :n] @ L.T, 0.0, 1.0)
                        m = min(len(U), problem.remaining, budget - used)
                        c = np.full(len(U), np.inf)
                        c[:m] = _finite(problem.evaluate(coords.to_x(U[:m])))
                        used += m
                        i = int(np.argmin(c))
                        if c[i] < best_c:
                            best_c, u_b = float(c[i]), U[i].copy()
                        es.tell(Z, list(np.where(np.isfinite(c), c, 1e300)))
                    done += 1
                    if start_c - best_c <= 1e-6 * abs(start_c) or used >= budget or problem.remaining <= 0:
                        break
        finally:
            np.random.set_state(saved)
    return (f"cost stage ({done} CMA-ES run(s) on the cost, in the minimum's Gauss-Newton metric): {c0:.6g} -> "
            f"{best_c:.6g} in {used} evaluations")


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    global_fraction: float = 0.3,
    popsize: int = 10,
    crossover: float = 0.9,
    starts: int = 16,
    confirm: int = 2,
    sample_starts: bool = True,
    sample_order: str = "spread",
    sample_confirm: int = 2,
    local_fraction: float = 0.2,
    cost_fraction: float = 0.25,
    cost_sigma: float = 2.0,
    cost_rtol: float = 1e-7,
    cost_runs: int = 3,
    min_distance: float = 0.1,
    agree_rtol: float = 1e-6,
    log_scale: bool = True,
    method: str = "trf",
    diff_step: float = 1e-7,
    ftol: float = 1e-10,
    xtol: float = 1e-10,
    gtol: float = 1e-10,
    nonfinite_residual: float = 1e6,
) -> OptimizerOutput:
    """Differential evolution on ``global_fraction`` of the budget, then trf least squares from
    up to ``starts`` points of the evolution and of its sample in turn, until ``confirm``
    starts (one from the sample) reach the best minimum (see the module docstring)."""
    if not 0.0 < float(global_fraction) <= 1.0:
        raise ValueError(f"multistart: global_fraction must be in (0, 1], got {global_fraction}")
    if int(starts) < 1 or int(confirm) < 1:
        raise ValueError(f"multistart: starts and confirm must be >= 1, got {starts}, {confirm}")
    if method not in ("trf", "dogbox"):
        raise ValueError(f"multistart: method must be trf or dogbox, got {method!r}")
    if not 0.0 <= float(cost_fraction) <= 1.0:
        raise ValueError(f"multistart: cost_fraction must be in [0, 1], got {cost_fraction}")
    if not 0.0 < float(local_fraction) <= 1.0:
        raise ValueError(f"multistart: local_fraction must be in (0, 1], got {local_fraction}")
    rng = np.random.default_rng(seed)
    coords = _Coordinates(problem.lower, problem.upper, log_scale)
    total = problem.remaining
    g_budget = total if not problem.has_residuals else max(1, int(math.floor(global_fraction * total)))
    try:
        sample, evolved, gens = _global_stage(problem, coords, rng, g_budget, int(popsize), float(crossover))
    except BudgetExhausted:
        return OptimizerOutput(x=None, nit=0, message="evaluation budget spent in the global stage")
    if not problem.has_residuals:
        U, f = evolved
        return OptimizerOutput(x=coords.to_x(U[int(np.argmin(f))]), nit=gens,
                               message="global stage only: the problem has no residual vector")
    big, step = float(nonfinite_residual), float(diff_step)
    per_start = max(4 * (problem.n_var + 1), int(float(local_fraction) * total))

    reserve = 0  # evaluations kept for the cost stage, once it is known to be needed

    def rows(Uq):
        """Residual vectors of a batch, every row counted; when the batch does not fit the budget
        the rows that fit are evaluated (so the run ends exactly at the budget), then
        BudgetExhausted; _Reserved when it would eat into the cost stage's reserve."""
        X = coords.to_x(np.atleast_2d(Uq))
        if reserve and problem.remaining - reserve < len(X):
            raise _Reserved()
        k = min(len(X), problem.remaining)
        if k == 0:
            raise BudgetExhausted(f"budget of {problem.budget} evaluations spent")
        R = np.asarray(problem.residuals_batch(X[:k]), float).reshape(k, -1)
        if k < len(X):
            raise BudgetExhausted(f"budget of {problem.budget} evaluations spent")
        return np.where(np.isfinite(R), R, big)

    cost_budget = int(float(cost_fraction) * total)
    results = []  # (sum of squares, u, kind, scipy message, Jacobian)
    nit, message = gens, ""
    queue = _Starts(evolved, sample if sample_starts else None, min_distance, spread=sample_order == "spread")
    from_sample = int(sample_confirm) if sample_starts else 0
    while len(results) < int(starts):
        nxt = queue.next()
        if nxt is None:
            break
        kind, u0 = nxt
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

        left = problem.remaining - reserve
        try:
            sol = least_squares(fun, u0, jac=jac, bounds=(0.0, 1.0), method=method, x_scale="jac", ftol=ftol,
                                xtol=xtol, gtol=gtol,
                                max_nfev=max(1, left if local_fraction >= 1
                                             else min(left, per_start) // (problem.n_var + 1)))
        except BudgetExhausted:
            message = f"evaluation budget spent in local start {len(results) + 1}"
            break
        except _Reserved:
            message = f"local start {len(results) + 1} stopped to keep {reserve} evaluations for the cost stage"
            break
        nit += int(sol.nfev)
        results.append((float(sol.cost * 2), sol.x, kind, sol.message, sol.jac))
        if len(results) == 1 and cost_budget > 0:
            c = float(problem.evaluate(coords.to_x(sol.x[None, :]))[0])
            if abs(c - results[0][0]) > 1e-9 * max(abs(c), 1e-300):  # the cost is not the sum of squares
                reserve = cost_budget
        if _confirmed(_minima(results, agree_rtol)[0], int(confirm), from_sample):
            break
    if not results:
        return OptimizerOutput(x=None, nit=nit, message=message or "no local start completed")
    minima = _minima(results, agree_rtol)
    summary = _summary(minima, len(results), int(confirm), from_sample)
    summary = f"{message}; {summary}" if message else summary
    budget_left = min(problem.remaining, cost_budget)
    note = "" if budget_left <= 0 else _cost_stage(problem, coords, minima[0], int(rng.integers(2**31)), budget_left,
                                                   float(cost_sigma), float(cost_rtol), int(cost_runs))
    return OptimizerOutput(x=coords.to_x(minima[0]["u"]), nit=nit, message=f"{summary}; {note}" if note else summary)


#: Runs of this plugin may go side by side in one process (each deterministic for its seed: no
#: state outside the run but the cost stage's, under :data:`_GLOBAL_RNG`); docs/plugins.md.
minimize.concurrent_runs = True
