"""The clone as the benchmark's optimiser plugin (``conf/optimizer/genesis.yaml``)."""

from __future__ import annotations

from benchmark.core.errors import ConfigError
from plugins.genesis.engine import Genesis
from plugins.genesis.randu import seed_to_randu
from plugins.genesis.settings import Gene, Settings, Template


def minimize(
    problem,
    *,
    seed: int,
    population_size: int = 100,
    bits_per_gene: int = 11,
    crossover_rate: float = 0.6,
    mutation_rate: float = 0.001,
    generation_gap: float = 1.0,
    scaling_window: int = 5,
    structures_saved: int = 10,
    max_gens_without_eval: int = 2,
    options: str = "acefgl",
    rank_min: float = 0.75,
    random_seed: int | None = None,
    report_interval: int = 100,
):
    """GENESIS 5.0 on a :class:`benchmark.core.problem.SearchProblem` (cost minimised).

    Total Trials is ``problem.budget``; genes span ``[lower, upper]`` with ``2**bits_per_gene``
    values each (option ``f`` is implied, ``g`` selects Gray code). ``report_interval`` only sets
    when the convergence statistics of option ``c`` are taken (and so when the ``Bias > 0.99``
    stop can happen), as in the original. Each generation's marked structures are evaluated in
    one ``problem.evaluate`` call; rows past the budget are trimmed by the harness (they cost
    +inf, i.e. :data:`INF_COST`, and end the run). Returns the best decoded vector found,
    ``nit`` = generations evaluated including generation 0, and a message with the stop reason
    and the RANDU seed used."""
    from benchmark.core.problem import OptimizerOutput

    def key(name):
        return f"optimizer.plugin.{name}"

    if int(bits_per_gene) < 1 or int(bits_per_gene) > 30:
        raise ConfigError(f"{key('bits_per_gene')}: must be in 1..30, got {bits_per_gene}")
    if "M" in str(options):
        raise ConfigError(f"{key('options')}: option 'M' (maximise) makes no sense for a cost; remove it")
    rseed = seed_to_randu(seed) if random_seed is None else int(random_seed)
    n_var = problem.n_var
    opts = str(options) if "f" in str(options) else str(options) + "f"
    settings = Settings(
        experiments=1,
        total_trials=int(problem.budget),
        population_size=int(population_size),
        structure_length=n_var * int(bits_per_gene),
        crossover_rate=float(crossover_rate),
        mutation_rate=float(mutation_rate),
        generation_gap=float(generation_gap),
        scaling_window=int(scaling_window),
        report_interval=int(report_interval),
        structures_saved=int(structures_saved),
        max_gens_without_eval=int(max_gens_without_eval),
        options=opts,
        random_seed=rseed,
        rank_min=float(rank_min),
    )
    bad = settings.check()
    if bad:
        name, msg = bad[0]
        name = "seed" if name == "random_seed" and random_seed is None else name
        raise ConfigError(f"{key(name)}: {msg}")
    values = 1 << int(bits_per_gene)
    lo, hi = problem.lower, problem.upper
    template = Template([Gene(float(a), float(b), values) for a, b in zip(lo, hi, strict=True)])
    engine = Genesis(settings, template, problem.evaluate)
    res = engine.run()
    x = template.decode(res.best_bits[None, :], engine.gray)[0] if res.best_bits is not None else None
    msg = (
        f"GENESIS: {res.generations} generations, {res.trials} trials, best {res.best_cost:.6e}; "
        f"stopped: {res.stop_reason}; RANDU seed {rseed}"
    )
    return OptimizerOutput(x=x, nit=res.generations, message=msg)
