"""The lindsay_barton plugin: initial models A/E through the problem's hook, CG searches, budget."""

import numpy as np
import pytest
from hydra.utils import instantiate

from benchmark.core.budget import BudgetedProblem, run_plugin
from benchmark.core.harness import build_problem
from benchmark.core.problem import Problem, Status
from plugins.lindsay_barton import initial_point, minimize
from tests.conftest import compose_config


def cfg_for(*overrides, noise="none"):
    return compose_config(["problem=admittance", "optimizer=lindsay_barton", f"noise={noise}", *overrides])


class Counting(Problem):
    """Wraps a problem and counts the rows it is asked to evaluate, independently of the harness."""

    def __init__(self, inner):
        self.inner = inner
        self.name = inner.name
        self.parameter_names = inner.parameter_names
        self.lower, self.upper = inner.lower, inner.upper
        self.truth = inner.truth
        self.rows = 0

    def evaluate(self, X):
        self.rows += len(np.atleast_2d(X))
        return self.inner.evaluate(X)

    def initial_guess(self, kind):
        return self.inner.initial_guess(kind)

    def estimate(self, x):
        return self.inner.estimate(x)


def run(problem, budget, **kw):
    bp = BudgetedProblem(problem, budget)
    res = run_plugin(lambda b, seed: minimize(b, seed, **kw), bp, seed=0, name="lindsay_barton")
    return bp, res


def test_yaml_wires_the_plugin_as_the_harness_does():
    cfg = cfg_for()
    assert cfg.optimizer.name == "lindsay_barton" and cfg.optimizer.plugin.initial_model == "E"
    assert cfg.optimizer.plugin.searches == 5
    plugin = instantiate(cfg.optimizer.plugin)
    problem = build_problem(cfg_for("motor.test.warming=false"))
    bp = BudgetedProblem(problem, int(cfg.optimizer.default_budget))
    res = run_plugin(plugin, bp, seed=0, name=cfg.optimizer.name)
    assert res.status in (Status.CONVERGED, Status.BUDGET_SPENT) and res.nfev <= 5000
    assert "initial model E" in res.message


@pytest.mark.parametrize("warming", [False, True])
def test_noise_free_eight_parameter_fit_within_0p1_percent(warming):
    """Model-F data, initial model E then CG searches: every identifiable parameter within 0.1 %
    (with warming the data are temperature-compensated from the DC resistances)."""
    p = build_problem(cfg_for(f"motor.test.warming={str(warming).lower()}"))
    bp, res = run(p, 5000, initial_model="E")
    est = p.estimate(res.x)
    for k in ("R1_total", "X1", "R2", "X2", "R0", "X0", "R2sigma", "X3", "R1", "R1sigma"):
        assert est[k] == pytest.approx(p.truth[k], rel=1e-3), k
    assert res.fun <= bp.history.best_cost[0]


def test_initial_model_a_reads_synchronous_and_standstill_admittance():
    p = build_problem(cfg_for("motor.test.warming=false"))
    x = dict(zip(p.parameter_names, p.initial_guess("A"), strict=True))
    Y0 = p.data.Y[np.argmin(np.abs(p.data.slip))]
    Y1 = p.data.Y[np.argmin(np.abs(p.data.slip - 1))]
    Zsc = 1 / Y1
    assert x["R1_total"] == pytest.approx(Zsc.real / 2) and x["X2"] == pytest.approx(Zsc.imag / 2)
    assert x["R0"] + x["R1_total"] == pytest.approx((1 / Y0).real)
    assert x["X0"] + x["X1"] == pytest.approx((1 / Y0).imag)
    # a crude reading: a few per cent of full scale off, much worse than E
    assert 1.0 < p.rms_error_percent(p.initial_guess("A")) < 5.0
    assert p.rms_error_percent(p.initial_guess("E")) < 1e-6


def test_searches_reduce_the_error_from_model_a_on_noisy_data():
    p = build_problem(cfg_for("noise.seed=4", noise="noisy"))
    x0 = p.initial_guess("A")
    bp, res = run(p, 5000, initial_model="A", searches=5)
    assert p.rms_error_percent(res.x) < 0.35 < 1.0 < p.rms_error_percent(x0)
    # 5 searches of n_var CG iterations each
    assert res.nit <= 5 * p.n_var and "5 search(es)" in res.message


def test_counts_exactly_and_stops_at_the_budget():
    inner = build_problem(cfg_for(noise="noisy"))
    for budget in (1, 17, 250):
        c = Counting(inner)
        bp, res = run(c, budget, initial_model="A", searches=50)
        assert c.rows == bp.nfev == budget
        assert res.status == Status.BUDGET_SPENT
    c = Counting(inner)
    bp, res = run(c, 100000, initial_model="E", searches=2)
    assert c.rows == bp.nfev < 100000 and res.status == Status.CONVERGED


class Quadratic(Problem):
    """No initial_guess hook: the plugin must start from crude_start()."""

    name = "quadratic"
    parameter_names = ("a", "b", "c")
    lower = np.array([0.1, 1.0, -2.0])
    upper = np.array([10.0, 100.0, 2.0])
    x_opt = np.array([0.7, 42.0, -0.5])

    def evaluate(self, X):
        u = (np.atleast_2d(X) - self.lower) / (self.upper - self.lower)
        u_opt = (self.x_opt - self.lower) / (self.upper - self.lower)
        return np.sum(((u - u_opt) * [1.0, 3.0, 0.5]) ** 2, axis=1)


def test_problem_without_hook_falls_back_to_crude_start():
    bp = BudgetedProblem(Quadratic(), 2000)
    x0, note = initial_point(bp, "E")
    np.testing.assert_allclose(x0, Quadratic().crude_start())
    assert "crude" in note
    res = run_plugin(lambda b, seed: minimize(b, seed), bp, seed=0, name="lb")
    assert "crude start" in res.message
    np.testing.assert_allclose(res.x, Quadratic.x_opt, rtol=1e-5, atol=1e-6)


def test_deterministic():
    p = build_problem(cfg_for("noise.seed=2", noise="noisy"))
    r1 = run(p, 3000, initial_model="A")[1]
    r2 = run(p, 3000, initial_model="A")[1]
    assert np.array_equal(r1.x, r2.x) and r1.fun == r2.fun and r1.nfev == r2.nfev


def test_runs_on_the_time_domain_problem_from_a_crude_start():
    cfg = compose_config(["problem=timedomain", "optimizer=lindsay_barton"])
    problem = build_problem(cfg)
    assert not hasattr(problem, "initial_guess")
    bp = BudgetedProblem(problem, 300)
    res = run_plugin(instantiate(cfg.optimizer.plugin), bp, seed=0, name="lindsay_barton")
    assert res.nfev == 300 and np.isfinite(res.fun) and "crude start" in res.message
