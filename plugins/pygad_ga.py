"""A real-coded genetic algorithm from PyGAD, as an imbench plugin.

PyGAD maximises a fitness, so ``fitness = -cost``; a ``+inf`` cost (a diverging candidate, or a
member past the budget) becomes the very negative finite fitness ``-1e300`` (finite costs are
capped at ``1e299`` so they always rank better). The search runs in normalised coordinates
``u`` in ``[0, 1]^n`` (``x = lower + u * (upper - lower)``), given to PyGAD as the continuous
gene space ``{low: 0, high: 1}``; SBX crossover and polynomial mutation keep genes inside it.

Evaluation and budget:

* ``fitness_batch_size = sol_per_pop``: the solutions PyGAD needs evaluated in a generation
  reach the fitness function in one batch, i.e. one ``problem.evaluate`` call, trimmed to the
  remaining budget.
* PyGAD does not re-evaluate solutions it already knows (elites kept with ``keep_elitism``,
  and children identical to them), so the number of evaluations per generation varies. The
  harness counter (``SearchProblem``) is the only count: ``num_generations`` is just an upper
  bound (the budget itself: every generation evaluates at least one new solution), and
  ``on_generation`` returns ``"stop"`` as soon as the budget is spent. Once it is, the fitness
  function no longer calls the problem at all.
* ``save_solutions`` stays off (it would cache every solution ever seen, and keep them all).

Seeding: PyGAD 3.9 owns private generators seeded from ``random_seed`` (0 is a valid seed);
the global ``random``/``numpy.random`` states are not touched.
"""

from __future__ import annotations

import logging

import numpy as np
import pygad

from benchmark.core.problem import OptimizerOutput, SearchProblem

__all__ = ["minimize"]

_WORST_FITNESS = -1e300
_COST_CAP = 1e299
_LOG = logging.getLogger("imbench.plugins.pygad")


def minimize(
    problem: SearchProblem,
    *,
    seed: int,
    sol_per_pop: int = 100,
    num_parents_mating: int = 50,
    parent_selection_type: str = "tournament",
    K_tournament: int = 3,
    keep_elitism: int = 2,
    crossover_type: str = "sbx",
    crossover_probability: float | None = None,
    sbx_crossover_eta: float = 15.0,
    mutation_type: str = "polynomial",
    mutation_probability: float | None = None,
    polynomial_mutation_eta: float = 20.0,
) -> OptimizerOutput:
    """Minimise ``problem`` with a PyGAD GA within its evaluation budget.

    ``mutation_probability`` None takes ``1 / n_var`` (per gene). Settings are passed to
    ``pygad.GA`` under the same names.
    """
    n = problem.n_var
    lo, span = problem.lower, problem.upper - problem.lower
    sol_per_pop = int(sol_per_pop)
    if mutation_probability is None:
        mutation_probability = 1.0 / n

    def fitness_func(ga, solutions, indices):
        U = np.clip(np.asarray(solutions, float).reshape(-1, n), 0.0, 1.0)
        fit = np.full(len(U), _WORST_FITNESS)
        k = min(len(U), problem.remaining)
        if k > 0:
            c = problem.evaluate(lo + U[:k] * span)
            fit[:k] = np.where(np.isfinite(c), -np.minimum(c, _COST_CAP), _WORST_FITNESS)
        return fit

    def on_generation(ga):
        return "stop" if problem.exhausted else None

    ga = pygad.GA(
        num_generations=max(1, problem.remaining),
        num_parents_mating=int(num_parents_mating),
        fitness_func=fitness_func,
        fitness_batch_size=sol_per_pop,
        sol_per_pop=sol_per_pop,
        num_genes=n,
        gene_type=float,
        gene_space={"low": 0.0, "high": 1.0},
        init_range_low=0.0,
        init_range_high=1.0,
        parent_selection_type=parent_selection_type,
        K_tournament=int(K_tournament),
        keep_elitism=int(keep_elitism),
        crossover_type=crossover_type,
        crossover_probability=None if crossover_probability is None else float(crossover_probability),
        sbx_crossover_eta=float(sbx_crossover_eta),
        mutation_type=mutation_type,
        mutation_probability=float(mutation_probability),
        polynomial_mutation_eta=float(polynomial_mutation_eta),
        on_generation=on_generation,
        save_solutions=False,
        save_best_solutions=False,
        suppress_warnings=True,
        random_seed=int(seed) % 2**32,
        logger=_LOG,
    )
    ga.run()

    u, _, _ = ga.best_solution(pop_fitness=ga.last_generation_fitness)
    x = lo + np.clip(np.asarray(u, float), 0.0, 1.0) * span
    if problem.exhausted:
        msg = "evaluation budget spent"
    else:
        msg = f"pygad stopped after {ga.generations_completed} generations before the budget was spent"
    return OptimizerOutput(x=x, nit=int(ga.generations_completed), message=msg)
