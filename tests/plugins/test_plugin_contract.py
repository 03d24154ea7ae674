"""Contract tests for every optimiser plugin configured in ``conf/optimizer/*.yaml``.

Each YAML file is loaded with OmegaConf and its ``plugin`` node instantiated exactly as the
harness does (``hydra.utils.instantiate(cfg.plugin)(budgeted_problem, seed=seed)``), with the
YAML's own default settings. The plugins run on small toy problems defined here:

(a) the same seed gives bit-identical best x and cost, also after other plugins ran and the
    global ``random``/``numpy.random`` states were changed in between;
(b) the run stops at exactly the budget (or earlier, if the plugin says it converged), the
    toy problem never receives a row past the budget, and the plugin does not keep calling
    the problem once the budget is spent;
(c) the toy optimum is found to a real accuracy within the YAML's budget (capped at 20000);
(d) ``+inf`` costs (a region of the box, the crude start, or the whole box) never crash a
    plugin;
(e) a budget smaller than one population is respected;
(f) a problem with a single parameter works.

A plugin module that cannot be imported (e.g. one still being written) is skipped; any other
failure fails.
"""

from __future__ import annotations

import importlib
import random
from pathlib import Path

import numpy as np
import pytest
from hydra.utils import instantiate
from omegaconf import OmegaConf

from benchmark.core.budget import BudgetedProblem, run_plugin
from benchmark.core.problem import OptimizeResult, OptimizerOutput, Problem, Status

CONF_DIR = Path(__file__).resolve().parents[2] / "conf" / "optimizer"
YAMLS = sorted(CONF_DIR.glob("*.yaml"))
IDS = [p.stem for p in YAMLS]
#: Population methods whose default settings have no convergence stop: they must spend the
#: whole budget. Every other plugin may stop earlier if it says so (status CONVERGED, message).
SPENDS_WHOLE_BUDGET = {"cmaes", "deap", "nlopt_crs", "pygad", "scipy_de"}


# -- toy problems ------------------------------------------------------------------------------


class ShiftedSphere(Problem):
    """A weighted sphere in normalised units, off-centre, on bounds spanning decades (like motor
    parameters). Random points cost ~0.1-1; the optimum costs 0. Counts every row it sees."""

    name = "toy_sphere"
    parameter_names = ("r_s", "l_s", "j", "offset")
    lower = np.array([0.1, 1e-3, 10.0, -5.0])
    upper = np.array([10.0, 0.1, 1000.0, 1.0])
    #: the optimum, in normalised coordinates: away from the centre and from the crude start
    u_opt = np.array([0.27, 0.62, 0.81, 0.15])
    weights = np.array([1.0, 2.0, 0.5, 1.5])

    def __init__(self):
        self.rows = 0  # rows simulated (evaluate rows + residual vectors)
        self.calls = 0

    @property
    def x_opt(self) -> np.ndarray:
        return self.lower + self.u_opt * (self.upper - self.lower)

    def to_u(self, X) -> np.ndarray:
        return (np.asarray(X, float) - self.lower) / (self.upper - self.lower)

    def _res(self, X: np.ndarray) -> np.ndarray:
        return (self.to_u(X) - self.u_opt) * self.weights

    def _bad(self, X: np.ndarray) -> np.ndarray:
        """Rows whose simulation 'diverges' (none here)."""
        return np.zeros(len(X), bool)

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        self.rows += len(X)
        self.calls += 1
        c = np.sum(self._res(X) ** 2, axis=1)
        c[self._bad(X)] = np.inf
        return c

    def residuals(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, float)[None, :]
        self.rows += 1
        self.calls += 1
        r = self._res(x)[0]
        return np.full_like(r, np.nan) if self._bad(x)[0] else r


class InfRegion(ShiftedSphere):
    """+inf (NaN residuals) where u[0] > 0.35 or u[3] > 0.6: the optimum lies close to the
    border; the crude start is outside the +inf region."""

    name = "toy_inf_region"

    def _bad(self, X):
        u = self.to_u(X)
        return (u[:, 0] > 0.35) | (u[:, 3] > 0.6)


class InfAtStart(ShiftedSphere):
    """+inf around the crude start (u[1] < 0.3), finite elsewhere."""

    name = "toy_inf_at_start"

    def _bad(self, X):
        return self.to_u(X)[:, 1] < 0.3


class InfEverywhere(ShiftedSphere):
    name = "toy_inf_everywhere"

    def _bad(self, X):
        return np.ones(len(X), bool)


class Rosenbrock(ShiftedSphere):
    """Residual form of the 4-D Rosenbrock function on a box around (1, 1, 1, 1): local
    methods need a few dozen iterations, so small budgets really bind."""

    name = "toy_rosenbrock"
    parameter_names = ("a", "b", "c", "d")
    lower = np.array([-1.5, -0.5, 0.2, 0.1])
    upper = np.array([2.0, 3.0, 2.5, 4.0])

    def _res(self, X):
        X = np.atleast_2d(X)
        r1 = 10.0 * (X[:, 1:] - X[:, :-1] ** 2)
        r2 = 1.0 - X[:, :-1]
        return np.concatenate([r1, r2], axis=1)


class CountingBudgeted(BudgetedProblem):
    """Also counts calls the plugin makes once the budget is spent."""

    def __init__(self, problem, budget):
        super().__init__(problem, budget)
        self.calls_after_exhausted = 0

    def evaluate(self, X):
        if self.exhausted:
            self.calls_after_exhausted += 1
        return super().evaluate(X)

    def residuals(self, x):
        if self.exhausted:
            self.calls_after_exhausted += 1
        return super().residuals(x)

    def residuals_batch(self, X):
        if self.exhausted:
            self.calls_after_exhausted += 1
        return super().residuals_batch(X)


# -- helpers -----------------------------------------------------------------------------------


def load(path: Path):
    """The YAML's plugin, instantiated as the harness does; skip if its module does not import."""
    cfg = OmegaConf.load(path)
    module = str(cfg.plugin._target_).rsplit(".", 1)[0]
    try:
        importlib.import_module(module)
    except ImportError as exc:
        pytest.skip(f"{module} cannot be imported yet: {exc}")
    return cfg, instantiate(cfg.plugin)


def run(path: Path, problem: Problem, budget: int, seed: int = 3) -> tuple[CountingBudgeted, OptimizeResult]:
    cfg, plugin = load(path)
    bp = CountingBudgeted(problem, budget)
    outputs = []

    def call(b, seed):
        out = plugin(b, seed=seed)
        outputs.append(out)
        return out

    res = run_plugin(call, bp, seed=seed, name=str(cfg.name))
    if outputs:  # a plugin may also end by letting BudgetExhausted propagate
        assert isinstance(outputs[0], OptimizerOutput), f"{path.stem} returned {type(outputs[0]).__name__}"
    return bp, res


def set_global_rng(k: int) -> None:
    random.seed(1000 + k)
    np.random.seed(2000 + k)
    random.random()
    np.random.rand(3)


def assert_budget(bp: CountingBudgeted, res: OptimizeResult, budget: int, name: str) -> None:
    assert bp.problem.rows == bp.nfev, f"{name}: toy problem saw {bp.problem.rows} rows, harness {bp.nfev}"
    assert bp.nfev <= budget, f"{name}: {bp.nfev} evaluations > budget {budget}"
    if bp.nfev < budget:
        assert res.status in (Status.CONVERGED, Status.FAILED), res.status
        assert res.message, f"{name}: stopped at {bp.nfev} < {budget} evaluations without saying why"
    assert bp.calls_after_exhausted <= 2, (
        f"{name}: kept calling the problem {bp.calls_after_exhausted} times after the budget was spent"
    )


# -- tests -------------------------------------------------------------------------------------


def test_every_yaml_has_the_plugin_shape():
    assert {"cmaes", "deap", "least_squares", "nlopt_crs", "pygad", "scipy_de"} <= set(IDS)
    for path in YAMLS:
        cfg = OmegaConf.load(path)
        assert cfg.name == path.stem, f"{path.name}: name {cfg.name!r} differs from the file name"
        assert int(cfg.default_budget) > 0
        assert cfg.plugin._partial_ is True
        assert str(cfg.plugin._target_).startswith("plugins.")


@pytest.mark.parametrize("path", YAMLS, ids=IDS)
def test_a_same_seed_same_result_after_other_plugins(path):
    others = [p for p in YAMLS if p != path]
    set_global_rng(1)
    bp1, r1 = run(path, ShiftedSphere(), budget=800, seed=11)
    for k, other in enumerate(others):
        set_global_rng(10 + k)
        try:
            run(other, Rosenbrock(), budget=150, seed=k)
        except pytest.skip.Exception:
            pass
    set_global_rng(2)
    bp2, r2 = run(path, ShiftedSphere(), budget=800, seed=11)
    assert r1.x is not None and r2.x is not None
    assert np.array_equal(r1.x, r2.x), f"{path.stem}: best x differs between identical runs"
    assert r1.fun == r2.fun and r1.nfev == r2.nfev
    assert bp1.history.evaluations == bp2.history.evaluations


@pytest.mark.parametrize("budget", [23, 1237])
@pytest.mark.parametrize("path", YAMLS, ids=IDS)
def test_b_stops_at_the_budget(path, budget):
    bp, res = run(path, Rosenbrock(), budget=budget)
    assert_budget(bp, res, budget, path.stem)
    if path.stem in SPENDS_WHOLE_BUDGET:
        assert bp.nfev == budget, f"{path.stem}: {bp.nfev} evaluations for a budget of {budget}"


@pytest.mark.parametrize("problem_cls", [ShiftedSphere, InfRegion], ids=["sphere", "inf_region"])
@pytest.mark.parametrize("path", YAMLS, ids=IDS)
def test_c_finds_the_toy_optimum(path, problem_cls):
    # the YAML's own budget, capped: 20000 lets even a 1998-style binary GA (genesis) settle
    budget = min(20000, int(OmegaConf.load(path).default_budget))
    problem = problem_cls()
    bp, res = run(path, problem, budget=budget, seed=5)
    assert_budget(bp, res, budget, path.stem)
    assert res.status != Status.FAILED, res.message
    # random points cost ~0.5; 2e-4 puts each coordinate within ~1.4 %/weight of its range
    assert res.fun < 2e-4, f"{path.stem}: best cost {res.fun:.3g} after {res.nfev} evaluations"
    u = problem.to_u(res.x)
    assert np.max(np.abs(u - problem.u_opt)) < 0.01, f"{path.stem}: best u {u} vs optimum {problem.u_opt}"


@pytest.mark.parametrize(
    "problem_cls", [InfRegion, InfAtStart, InfEverywhere], ids=["region", "at_start", "everywhere"]
)
@pytest.mark.parametrize("path", YAMLS, ids=IDS)
def test_d_inf_costs_do_not_crash(path, problem_cls):
    budget = 400
    bp, res = run(path, problem_cls(), budget=budget)
    assert_budget(bp, res, budget, path.stem)
    if problem_cls is InfEverywhere:
        assert res.status == Status.FAILED and not np.isfinite(res.fun)
    elif problem_cls is InfRegion or bp.nfev == budget:
        # a local method started inside the +inf region may stop there (saying so, see
        # assert_budget); anything that spent the budget must have found a finite cost
        assert np.isfinite(res.fun), f"{path.stem}: no finite cost in {bp.nfev} evaluations"


@pytest.mark.parametrize("budget", [1, 7])
@pytest.mark.parametrize("path", YAMLS, ids=IDS)
def test_e_budget_smaller_than_a_population(path, budget):
    bp, res = run(path, ShiftedSphere(), budget=budget)
    assert_budget(bp, res, budget, path.stem)
    assert bp.nfev >= 1
    if path.stem in SPENDS_WHOLE_BUDGET:
        assert bp.nfev == budget and res.status == Status.BUDGET_SPENT


class OneParameter(ShiftedSphere):
    """A single searched parameter (e.g. everything else fixed)."""

    name = "toy_one_parameter"
    parameter_names = ("r_s",)
    lower = np.array([0.1])
    upper = np.array([10.0])
    u_opt = np.array([0.3])
    weights = np.array([1.0])


@pytest.mark.parametrize("path", YAMLS, ids=IDS)
def test_f_one_parameter(path):
    budget = 300
    problem = OneParameter()
    bp, res = run(path, problem, budget=budget)
    assert_budget(bp, res, budget, path.stem)
    assert res.fun < 1e-4, f"{path.stem}: best cost {res.fun:.3g} in 1-D"
