"""A real-coded genetic algorithm built from DEAP operators, as an imbench plugin.

Scheme, a (mu + lambda) GA in normalised coordinates ``u`` in ``[0, 1]^n``
(``x = lower + u * (upper - lower)``):

1. ``mu`` individuals drawn uniformly in the box;
2. each generation, ``lambda_`` parents chosen by tournament (``tournsize``), paired and
   crossed with bounded SBX (``cxSimulatedBinaryBounded``, probability ``cxpb``,
   distribution index ``eta_c``), then mutated with bounded polynomial mutation
   (``mutPolynomialBounded``, probability ``mutpb`` per child, ``indpb`` per gene, index
   ``eta_m``) - that is ``deap.algorithms.varAnd``;
3. children whose genes did not change keep their parent's cost (no evaluation spent), the
   others are evaluated together;
4. the best ``mu`` of parents + children survive (elitist).

Evaluation: ``toolbox.map`` is replaced by a batch map that stacks the individuals and makes
ONE ``problem.evaluate`` call per generation, trimmed to the remaining budget (members past
the budget cost ``+inf`` and never survive). ``+inf`` costs are ordinary, worst fitness values.

Traps handled:

* DEAP's bounded operators compute powers of ``(x - low) / (x2 - x1)``-style ratios and return
  complex numbers for genes outside ``[low, up]``: every individual is clipped to ``[0, 1]``
  before it is bred and after it is varied.
* ``creator.create`` makes global classes: done once, at import, under names private to this
  plugin, and guarded so that re-imports do not re-create them.
* DEAP draws from Python's global ``random`` module: the plugin saves its state, seeds it with
  ``seed`` for the run and restores it afterwards, so a run depends only on ``seed`` and the
  caller's random stream is left untouched (not thread-safe against other users of ``random``
  running at the same time).
"""

from __future__ import annotations

import random

import numpy as np
from deap import algorithms, base, creator, tools

from benchmark.core.problem import OptimizerOutput, SearchProblem

__all__ = ["minimize"]

_FITNESS = "ImbenchDeapFitnessMin"
_INDIVIDUAL = "ImbenchDeapIndividual"
if not hasattr(creator, _FITNESS):
    creator.create(_FITNESS, base.Fitness, weights=(-1.0,))
if not hasattr(creator, _INDIVIDUAL):
    creator.create(_INDIVIDUAL, list, fitness=getattr(creator, _FITNESS))

#: generations in a row without a single new candidate before the GA gives up
_MAX_IDLE_GENERATIONS = 100


def _clip(ind) -> None:
    for i, v in enumerate(ind):
        ind[i] = 0.0 if v < 0.0 else (1.0 if v > 1.0 else float(v))


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    mu: int = 100,
    lambda_: int = 100,
    tournsize: int = 3,
    cxpb: float = 0.9,
    eta_c: float = 15.0,
    mutpb: float = 1.0,
    eta_m: float = 20.0,
    indpb: float | None = None,
) -> OptimizerOutput:
    """Minimise ``problem`` with a DEAP (mu + lambda) real-coded GA within its budget.

    ``indpb`` None takes ``1 / n_var`` (one gene mutated per child on average).
    """
    n = problem.n_var
    lo, span = problem.lower, problem.upper - problem.lower
    mu, lambda_ = int(mu), int(lambda_)
    if mu < 1 or lambda_ < 2:
        raise ValueError(f"deap: need mu >= 1 and lambda_ >= 2, got mu={mu}, lambda_={lambda_}")
    indpb = 1.0 / n if indpb is None else float(indpb)
    Individual = getattr(creator, _INDIVIDUAL)

    def batch_map(func, individuals):
        """toolbox.map replacement: one problem.evaluate call for the whole list."""
        inds = list(individuals)
        if not inds:
            return []
        U = np.clip(np.asarray(inds, dtype=float).reshape(len(inds), n), 0.0, 1.0)
        k = min(len(U), problem.remaining)
        c = np.full(len(U), np.inf)
        if k > 0:
            c[:k] = problem.evaluate(lo + U[:k] * span)
        return [(float(v),) for v in c]

    toolbox = base.Toolbox()
    toolbox.register("map", batch_map)
    toolbox.register("evaluate", lambda ind: batch_map(None, [ind])[0])
    toolbox.register("mate", tools.cxSimulatedBinaryBounded, eta=float(eta_c), low=0.0, up=1.0)
    toolbox.register("mutate", tools.mutPolynomialBounded, eta=float(eta_m), low=0.0, up=1.0, indpb=indpb)
    toolbox.register("select", tools.selTournament, tournsize=int(tournsize))

    def assign(inds):
        for ind, fit in zip(inds, toolbox.map(toolbox.evaluate, inds), strict=True):
            ind.fitness.values = fit

    saved_state = random.getstate()
    random.seed(int(seed))
    nit, idle = 0, 0
    try:
        pop = [Individual(random.random() for _ in range(n)) for _ in range(mu)]
        assign(pop)
        while not problem.exhausted:
            parents = toolbox.select(pop, lambda_)
            for ind in parents:
                _clip(ind)
            offspring = algorithms.varAnd(parents, toolbox, float(cxpb), float(mutpb))
            for ind in offspring:
                _clip(ind)
            fresh = [ind for ind in offspring if not ind.fitness.valid]
            assign(fresh)
            pop = tools.selBest(pop + offspring, mu)
            nit += 1
            idle = 0 if fresh else idle + 1
            if idle >= _MAX_IDLE_GENERATIONS:
                break
    finally:
        random.setstate(saved_state)

    best = tools.selBest(pop, 1)[0]
    x = lo + np.clip(np.asarray(best, float), 0.0, 1.0) * span
    if problem.exhausted:
        msg = "evaluation budget spent"
    else:
        msg = f"stopped: {_MAX_IDLE_GENERATIONS} generations without a new candidate (cxpb/mutpb too low?)"
    return OptimizerOutput(x=x, nit=nit, message=msg)
