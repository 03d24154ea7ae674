"""The plugin interface: what an optimiser sees of an identification problem.

An optimiser plugin only knows this module. It receives a :class:`BudgetedProblem`
(parameter names, bounds, a batch cost, the evaluation budget) and a seed, and returns an
:class:`OptimizerOutput`. The harness, not the plugin, counts evaluations, keeps the best
point ever evaluated and builds the fixed :class:`OptimizeResult` record.

Conventions
-----------
* A population is an array ``X`` of shape ``(n_pop, n_var)`` in the problem's parameter
  order; ``evaluate(X)`` returns ``(n_pop,)`` costs. Costs are minimised.
* A candidate whose simulation diverges or yields non-finite values costs ``+inf``; it is
  counted as an evaluation like any other.
* Exactly one place counts evaluations: :class:`BudgetedProblem`. Every row of every call
  counts, also inside a vectorised call; the call that crosses the budget is trimmed and the
  rows past the budget get ``+inf`` without being simulated.
"""

from __future__ import annotations

import enum
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "Problem",
    "BudgetedProblem",
    "BudgetExhausted",
    "OptimizerOutput",
    "OptimizeResult",
    "Status",
]


class Problem(ABC):
    """An identification problem: named, bounded parameters and a population cost.

    Subclasses set ``name``, ``parameter_names``, ``lower`` and ``upper`` (arrays, in the
    units documented by the problem) and implement :meth:`evaluate`. Problems that are sums
    of squares also implement :meth:`residuals`, used by least-squares methods and ``polish``.
    """

    name: str = "problem"
    parameter_names: tuple[str, ...] = ()
    lower: np.ndarray
    upper: np.ndarray
    #: True parameter values (all names in :meth:`estimate`), or None for measured data.
    #: Only the scoring step reads it; the cost never does.
    truth: dict[str, float] | None = None

    @property
    def n_var(self) -> int:
        return len(self.parameter_names)

    def check_bounds(self) -> None:
        """Reject bounds that cannot be searched, with a message saying how to fix them."""
        from benchmark.errors import ConfigError

        lo, hi = np.asarray(self.lower, float), np.asarray(self.upper, float)
        if lo.shape != (self.n_var,) or hi.shape != (self.n_var,):
            raise ConfigError(
                f"bounds: expected {self.n_var} lower and upper values for {list(self.parameter_names)}, "
                f"got {lo.shape} and {hi.shape}"
            )
        for name, a, b in zip(self.parameter_names, lo, hi, strict=True):
            if not (np.isfinite(a) and np.isfinite(b)):
                raise ConfigError(f"bounds.{name}: bounds must be finite, got [{a}, {b}]")
            if a >= b:
                raise ConfigError(
                    f"bounds.{name}: low {a} >= high {b} (did you swap low and high?)"
                )

    @abstractmethod
    def evaluate(self, X: np.ndarray) -> np.ndarray:
        """Cost of each row of ``X`` (shape ``(n_pop, n_var)``) -> ``(n_pop,)``, +inf if invalid."""

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Weighted residual vector at ``x`` whose sum of squares is a least-squares cost.

        Not every problem has one; plugins that need it check :attr:`has_residuals`.
        """
        raise NotImplementedError(f"problem {self.name!r} has no residual vector")

    @property
    def has_residuals(self) -> bool:
        return type(self).residuals is not Problem.residuals

    def residuals_batch(self, X: np.ndarray) -> np.ndarray:
        """Residual vectors of a population, (n_pop, n_residuals); override to batch."""
        return np.stack([self.residuals(x) for x in np.atleast_2d(X)])

    def cost_from_residuals(self, r: np.ndarray) -> float:
        """The problem's own cost from its residual vector, without simulating again.

        Default: the sum of squares. Problems whose cost is not a sum of squares (e.g. the
        absolute-error cost of eq. 15) override it, so that every evaluation the harness
        counts is scored by the same cost, whichever way the plugin asked for it."""
        return float(r @ r)

    def estimate(self, x: np.ndarray) -> dict[str, float]:
        """Full named parameter set for the searched vector ``x`` (fixed or derived values added)."""
        return {n: float(v) for n, v in zip(self.parameter_names, x, strict=True)}

    def crude_start(self) -> np.ndarray:
        """A documented starting point for local methods: the centre of the bounds (geometric
        for positive bounds, since motor parameters span decades)."""
        lo, hi = np.asarray(self.lower, float), np.asarray(self.upper, float)
        pos = lo > 0
        return np.where(pos, np.sqrt(np.abs(lo * hi)), 0.5 * (lo + hi))

    def describe(self) -> dict:
        """Extra facts recorded in ``result.json`` (data source, fixed parameters...)."""
        return {}


class BudgetExhausted(Exception):
    """Raised by :meth:`BudgetedProblem.residuals` (and optionally checked by plugins) once the
    evaluation budget is spent. The harness catches it; a plugin may let it propagate."""


@dataclass
class History:
    """Convergence history: after ``evaluations[k]`` evaluations the best cost was ``best_cost[k]``.

    One entry per improvement (plus the last evaluation), so it stays small for long runs."""

    evaluations: list[int] = field(default_factory=list)
    best_cost: list[float] = field(default_factory=list)


class BudgetedProblem:
    """The problem as a plugin sees it: counts every evaluation and enforces the budget.

    ``evaluate(X)`` returns costs for all rows; rows beyond the budget are not simulated and
    cost ``+inf``. ``best_x``/``best_cost`` track the best point ever evaluated, which is what
    the harness reports, whatever the plugin returns.
    """

    def __init__(self, problem: Problem, budget: int):
        from benchmark.errors import ConfigError

        if int(budget) < 1:
            raise ConfigError(f"budget: must be a positive number of evaluations, got {budget}")
        self.problem = problem
        self.budget = int(budget)
        self.nfev = 0
        self.best_x: np.ndarray | None = None
        self.best_cost = np.inf
        self.history = History()

    # what plugins read
    @property
    def parameter_names(self) -> tuple[str, ...]:
        return self.problem.parameter_names

    @property
    def n_var(self) -> int:
        return self.problem.n_var

    @property
    def lower(self) -> np.ndarray:
        return np.asarray(self.problem.lower, float)

    @property
    def upper(self) -> np.ndarray:
        return np.asarray(self.problem.upper, float)

    @property
    def remaining(self) -> int:
        return self.budget - self.nfev

    @property
    def exhausted(self) -> bool:
        return self.nfev >= self.budget

    @property
    def has_residuals(self) -> bool:
        return self.problem.has_residuals

    def crude_start(self) -> np.ndarray:
        return np.asarray(self.problem.crude_start(), float)

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if X.shape[1] != self.n_var:
            raise ValueError(f"population has {X.shape[1]} columns, problem has {self.n_var} parameters")
        n_run = max(0, min(len(X), self.remaining))
        cost = np.full(len(X), np.inf)
        if n_run:
            c = np.asarray(self.problem.evaluate(X[:n_run]), dtype=float).reshape(n_run)
            c = np.where(np.isnan(c), np.inf, c)
            cost[:n_run] = c
            self._record(X[:n_run], c)
        return cost

    def __call__(self, X: np.ndarray) -> np.ndarray:
        return self.evaluate(X)

    def evaluate_one(self, x: np.ndarray) -> float:
        return float(self.evaluate(np.asarray(x, float)[None, :])[0])

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residual vector at ``x``; counts one evaluation. Raises BudgetExhausted when spent."""
        if self.exhausted:
            raise BudgetExhausted(f"budget of {self.budget} evaluations spent")
        x = np.asarray(x, float)
        r = np.asarray(self.problem.residuals(x), float)
        # the harness scores every evaluation by the problem's own cost, not the sum of squares
        cost = self.problem.cost_from_residuals(r) if np.all(np.isfinite(r)) else np.inf
        self._record(x[None, :], np.array([cost]))
        return r

    def residuals_batch(self, X: np.ndarray) -> np.ndarray:
        """Residual vectors of a population (e.g. a finite-difference Jacobian's points), each
        counted as one evaluation. Raises BudgetExhausted if the batch does not fit the budget."""
        X = np.atleast_2d(np.asarray(X, float))
        if len(X) > self.remaining:
            raise BudgetExhausted(f"budget of {self.budget} evaluations spent")
        R = np.asarray(self.problem.residuals_batch(X), float)
        cost = np.array([self.problem.cost_from_residuals(r) if np.all(np.isfinite(r)) else np.inf for r in R])
        self._record(X, cost)
        return R

    def _record(self, X: np.ndarray, c: np.ndarray) -> None:
        k = int(np.argmin(c)) if len(c) else 0
        start = self.nfev
        self.nfev += len(c)
        if len(c) and c[k] < self.best_cost:
            self.best_cost = float(c[k])
            self.best_x = np.array(X[k], dtype=float)
            self.history.evaluations.append(start + k + 1)
            self.history.best_cost.append(self.best_cost)


@dataclass
class OptimizerOutput:
    """What a plugin returns. ``x`` is the plugin's own best guess (informative only: the
    harness reports the best point it counted). ``nit`` is the plugin's iteration or
    generation count."""

    x: np.ndarray | None = None
    nit: int = 0
    message: str = ""


class Status(str, enum.Enum):
    """How a run ended. One enum for every plugin."""

    BUDGET_SPENT = "budget_spent"  # stopped at the evaluation budget
    CONVERGED = "converged"  # the plugin stopped on its own criterion before the budget
    FAILED = "failed"  # the plugin raised or returned nothing usable
    TIMEOUT = "timeout"  # the plugin exceeded its wall-time limit


@dataclass
class OptimizeResult:
    """The fixed result record of one run (scipy.optimize vocabulary, one schema for all)."""

    x: np.ndarray | None
    fun: float
    nfev: int
    nit: int
    status: Status
    message: str
    optimizer: str
    seed: int
    wall_time_s: float


def run_plugin(plugin, budgeted: BudgetedProblem, seed: int, name: str) -> OptimizeResult:
    """Run one plugin callable ``plugin(problem, seed=...) -> OptimizerOutput`` and build the
    fixed result record from the harness's own counter."""
    t0 = time.perf_counter()
    try:
        out = plugin(budgeted, seed=seed)
        status = Status.BUDGET_SPENT if budgeted.exhausted else Status.CONVERGED
        message = getattr(out, "message", "") or ""
        nit = int(getattr(out, "nit", 0) or 0)
    except BudgetExhausted as exc:
        status, message, nit = Status.BUDGET_SPENT, str(exc), 0
    wall = time.perf_counter() - t0
    if budgeted.best_x is None or not np.isfinite(budgeted.best_cost):
        status = Status.FAILED
        message = message or "no finite cost was found"
    return OptimizeResult(
        x=budgeted.best_x,
        fun=budgeted.best_cost,
        nfev=budgeted.nfev,
        nit=nit,
        status=status,
        message=message,
        optimizer=name,
        seed=int(seed),
        wall_time_s=wall,
    )
