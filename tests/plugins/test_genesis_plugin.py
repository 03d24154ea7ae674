"""Tests of the GENESIS 5.0 clone (plugins/genesis/) as the benchmark's optimiser plugin: budget,
seeds and the engine's equivalence on a budgeted problem, rank selection and generation gaps,
the saved list, edge settings. The original program's vectors: ``test_genesis.py``."""

from __future__ import annotations

import numpy as np
import pytest

import plugins.genesis as G
from benchmark.core.budget import BudgetedProblem
from benchmark.core.problem import OptimizerOutput, Problem

# (4) the plugin on a budgeted problem --------------------------------------------------------


class ShiftedSphere(Problem):
    name = "shifted_sphere"

    def __init__(self, n=4, diverge_above=None):
        self.parameter_names = tuple(f"p{i}" for i in range(n))
        self.lower = np.full(n, -2.0)
        self.upper = np.full(n, 3.0)
        self.shift = np.linspace(0.3, 1.1, n)
        self.diverge_above = diverge_above
        self.calls = []

    def evaluate(self, X):
        self.calls.append(len(X))
        c = ((X - self.shift) ** 2).sum(axis=1)
        if self.diverge_above is not None:
            c = np.where(X[:, 0] > self.diverge_above, np.inf, c)
        return c


def _run_plugin(seed, budget=2050, n=4, **kw):
    prob = ShiftedSphere(n, kw.pop("diverge_above", None))
    bp = BudgetedProblem(prob, budget)
    out = G.minimize(bp, seed=seed, **kw)
    return bp, out, prob


def test_plugin_uses_exact_budget_and_is_reproducible():
    bp1, out1, prob1 = _run_plugin(0)
    assert isinstance(out1, OptimizerOutput)
    assert bp1.nfev == bp1.budget == 2050
    assert out1.nit == 21  # 20 full generations of 100, then one trimmed by the harness
    assert prob1.calls[:3] == [100, 100, 100]  # one batch per generation
    assert np.isfinite(bp1.best_cost) and bp1.history.evaluations[-1] > 100  # improved after gen 0
    assert out1.x is not None and out1.x.shape == (4,)
    assert np.all(out1.x >= bp1.lower) and np.all(out1.x <= bp1.upper)

    bp2, out2, _ = _run_plugin(0)
    assert np.array_equal(out1.x, out2.x)
    assert bp1.best_cost == bp2.best_cost
    assert bp1.history.evaluations == bp2.history.evaluations
    assert bp1.history.best_cost == bp2.history.best_cost
    assert out1.message == out2.message

    bp3, out3, _ = _run_plugin(1)
    assert bp3.nfev == 2050
    assert (bp3.history.best_cost, bp3.history.evaluations) != (
        bp1.history.best_cost,
        bp1.history.evaluations,
    )


def test_plugin_random_seed_overrides_seed():
    bp1, out1, _ = _run_plugin(5, random_seed=123456789)
    bp2, out2, _ = _run_plugin(0)
    assert np.array_equal(out1.x, out2.x) and bp1.history.best_cost == bp2.history.best_cost


def test_plugin_matches_engine_with_same_settings():
    """The plugin is the engine: same settings, same decoded best point."""
    bp, out, prob = _run_plugin(0, budget=3000, n=3, population_size=50, bits_per_gene=10)
    s = G.Settings(
        total_trials=3000,
        population_size=50,
        structure_length=30,
        report_interval=100,
        options="acefgl",
        random_seed=123456789,
    )
    t = G.Template([G.Gene(-2.0, 3.0, 1024) for _ in range(3)])
    res = G.Genesis(s, t, lambda X: ((X - prob.shift) ** 2).sum(axis=1)).run()
    assert res.trials == bp.nfev == 3000
    assert np.array_equal(t.decode(res.best_bits[None, :], True)[0], out.x)


def test_plugin_survives_diverging_candidates():
    bp, out, _ = _run_plugin(3, diverge_above=2.0)
    assert bp.nfev == 2050
    assert np.isfinite(bp.best_cost)
    assert "1e300" not in out.message


def test_plugin_rejects_maximise():
    from benchmark.core.errors import ConfigError

    with pytest.raises(ConfigError, match="options"):
        _run_plugin(0, options="acefgM")


# (5) rank selection and generation gap < 1 ---------------------------------------------------


@pytest.mark.parametrize("options", ["acefgR", "cefgR", "ceRfg"])
@pytest.mark.parametrize("gap", [0.5, 0.73])
def test_rank_selection_and_gap(options, gap):
    budget = 1537
    bp, out, _ = _run_plugin(7, budget=budget, n=5, options=options, generation_gap=gap, population_size=40)
    assert bp.nfev <= budget
    assert np.isfinite(bp.best_cost)
    assert out.nit > 1
    # engine invariants on the same settings: it stops at the first generation reaching Total Trials
    s = G.Settings(
        total_trials=budget,
        population_size=40,
        structure_length=5 * 11,
        generation_gap=gap,
        options=options,
        report_interval=100,
        random_seed=G.seed_to_randu(7),
    )
    t = G.Template([G.Gene(-2.0, 3.0, 2048) for _ in range(5)])
    res = G.Genesis(s, t, G.sum_of_squares).run()
    if res.stop_reason.startswith("Total Trials"):
        assert budget <= res.trials < budget + 40
    else:
        assert res.trials < budget
    if "a" in options:
        # with 'a' every generation costs N trials
        assert res.trials == 40 * res.generations
    assert len(res.saved) == 10
    keys = {e.bits.tobytes() for e in res.saved}
    assert len(keys) == len(res.saved)  # distinct strings


def test_saved_list_holds_best_distinct():
    s = G.Settings(
        total_trials=3000,
        population_size=30,
        structure_length=12,
        options="cefgl",
        structures_saved=6,
        report_interval=50,
    )
    t = G.Template([G.Gene(-1.0, 1.0, 64), G.Gene(-1.0, 1.0, 64)])
    seen: dict[bytes, float] = {}

    def obj(X):
        return G.sum_of_squares(X)

    eng = G.Genesis(s, t, obj)
    orig = eng._evaluate

    def spy(pop, perf, needs):
        for i in np.flatnonzero(needs):
            seen[pop[i].tobytes()] = None
        return orig(pop, perf, needs)

    eng._evaluate = spy
    res = eng.run()
    costs = sorted(float(G.sum_of_squares(t.decode(np.frombuffer(k, np.uint8)[None, :], True))[0]) for k in seen)
    assert sorted(e.cost for e in res.saved) == costs[: len(res.saved)]
    assert len(res.saved) == 6


@pytest.mark.parametrize(
    "changes",
    [
        {"options": "acegl"},  # no 'f': plain bit strings
        {"options": "aCefgl"},  # statistics without convergence
        {"options": "aefgl"},  # no out lines at all
        {"experiments": 2},
        {"scaling_window": 0},
        {"mutation_rate": 0.0, "options": "cefgl"},
        {"mutation_rate": 1.0},
        {"crossover_rate": 0.0, "generation_gap": 0.1},
        {"options": "cefgLM"},  # maximise
    ],
)
def test_edge_settings_run(tmp_path, changes):
    s = G.Settings(total_trials=600, population_size=20, structure_length=12, report_interval=100)
    for k, v in changes.items():
        setattr(s, k, v)
    t = G.Template([G.Gene(-1.0, 1.0, 64), G.Gene(-1.0, 1.0, 64)])
    res = G.Genesis(s, t if "f" in s.options else None, G.sum_of_squares).run()
    assert res.trials <= 600 + 20
    lines = G.format_min_lines(res.saved, t if "f" in s.options else None, "g" in s.options)
    assert len(lines) == len(res.saved) <= s.structures_saved
    if "c" in s.options or "C" in s.options:
        assert res.out_lines and res.out_lines[0].startswith("    0    20")
    else:
        assert res.out_lines == []
