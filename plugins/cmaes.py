"""CMA-ES (the ``cma`` package) as an imbench plugin, with IPOP restarts until the budget.

Search space: normalised coordinates ``u`` in ``[0, 1]^n`` (``x = lower + u * (upper - lower)``),
bounded with cma's ``bounds=[0, 1]`` option and its default ``BoundTransform`` handler, so every
asked point is feasible and no evaluation is spent outside the box. (cma 4.x has no
``BoundPaduaBoundary``; ``BoundTransform`` or ``BoundPenalty`` are the choices.)

Each ``ask()`` population is evaluated in one ``problem.evaluate`` call, trimmed to the
remaining budget. ``+inf`` costs (diverging candidates, or members past the budget) are given
to ``tell()`` as a finite penalty worse than every finite cost of that population, because cma
needs finite values.

A single CMA-ES run converges long before a budget of tens of thousands of evaluations, so
when cma stops on its own criteria (tolfun, tolx, flat fitness...) it restarts from a new
random point with a population ``incpopsize`` times larger (IPOP-CMA-ES, Auger & Hansen
2005), up to ``restarts`` times; every start gets ``maxfevals`` = the evaluations still left.

In 1-D (where cma 4.5 fails with bounds) the search runs in 2-D and ignores the second
coordinate.

Seeding: cma samples with NumPy's *global* random state and treats seed 0 (or None) as
"seed from the clock". The plugin derives a non-zero cma seed for every start from ``seed``,
and saves/restores the global NumPy state around the run, so a run depends only on ``seed``
and leaves the caller's random state as it was (not thread-safe against other users of
``numpy.random`` running at the same time).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence

import cma
import numpy as np

from benchmark.core.problem import OptimizerOutput, SearchProblem

__all__ = ["minimize"]

#: penalty told to cma for a population in which no member has a finite cost
_ALL_INF_PENALTY = 1e100


def _plain(v):
    """YAML containers (OmegaConf) -> plain Python lists and dicts, which cma expects."""
    if isinstance(v, Mapping):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, Sequence) and not isinstance(v, str):
        return [_plain(x) for x in v]
    return v


def _finite_for_tell(c: np.ndarray) -> np.ndarray:
    """Replace non-finite costs by a finite value worse than every finite cost in ``c``."""
    c = np.asarray(c, float).copy()
    bad = ~np.isfinite(c)
    if bad.any():
        good = c[~bad]
        worst = float(good.max()) if good.size else 0.0
        c[bad] = worst + 1.0 + abs(worst) if good.size else _ALL_INF_PENALTY
    return c


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    sigma0: float = 0.3,
    popsize: int | None = None,
    restarts: int = 20,
    incpopsize: float = 2.0,
    boundary_handler: str = "BoundTransform",
    options: Mapping | None = None,
) -> OptimizerOutput:
    """Minimise ``problem`` with (IPOP-)CMA-ES within its evaluation budget.

    ``sigma0`` is the initial step size in normalised units; ``popsize`` None takes cma's
    default ``4 + 3 ln(n)``; ``options`` are extra cma options (e.g. ``tolfun``), applied last.
    """
    n = problem.n_var
    lo, span = problem.lower, problem.upper - problem.lower
    if boundary_handler not in ("BoundTransform", "BoundPenalty"):
        raise ValueError(
            f"cmaes: boundary_handler must be BoundTransform or BoundPenalty, got {boundary_handler!r}"
        )
    extra = {str(k): _plain(v) for k, v in options.items()} if options else {}
    # cma 4.5 fails in 1-D with bounds (sigma_vec not initialised): search 2-D, ignore the 2nd
    n_cma = max(n, 2)

    ss = np.random.SeedSequence(int(seed) & 0xFFFFFFFFFFFFFFFF)
    start_rng = np.random.default_rng(ss.spawn(1)[0])
    # one non-zero cma seed per start (cma reads 0 as "use the clock")
    cma_seeds = [int(s) % (2**31 - 2) + 1 for s in ss.generate_state(int(restarts) + 1)]

    saved_state = np.random.get_state()
    nit, starts, lam = 0, 0, popsize
    best_u, best_c = None, np.inf
    stop_reason: dict = {}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # cma's flat-fitness and similar chatter
            for start in range(int(restarts) + 1):
                if problem.exhausted:
                    break
                starts += 1
                opts = {
                    "bounds": [0.0, 1.0],
                    "BoundaryHandler": boundary_handler,
                    "seed": cma_seeds[start],
                    "maxfevals": problem.remaining,
                    "verbose": -9,
                    "verb_log": 0,
                    "verb_disp": 0,
                }
                if lam is not None:
                    opts["popsize"] = int(lam)
                opts.update(extra)
                x0 = start_rng.uniform(0.0, 1.0, n_cma)
                es = cma.CMAEvolutionStrategy(x0, float(sigma0), opts)
                while not problem.exhausted and not es.stop():
                    sols = es.ask()  # told back unchanged, so cma finds its own genotypes
                    U = np.clip(np.asarray(sols, float)[:, :n], 0.0, 1.0)
                    k = min(len(U), problem.remaining)
                    c = np.full(len(U), np.inf)
                    c[:k] = problem.evaluate(lo + U[:k] * span)
                    i = int(np.argmin(c))
                    if c[i] < best_c:
                        best_c, best_u = float(c[i]), U[i].copy()
                    es.tell(sols, list(_finite_for_tell(c)))
                    nit += 1
                stop_reason = dict(es.stop())
                lam = int(round(es.popsize * float(incpopsize)))
    finally:
        np.random.set_state(saved_state)

    if problem.exhausted:
        msg = f"evaluation budget spent ({starts} CMA-ES start(s))"
    else:
        msg = f"cma stopped after {starts} start(s), no restart left: {stop_reason}"
    x = None if best_u is None else lo + best_u * span
    return OptimizerOutput(x=x, nit=nit, message=msg)
