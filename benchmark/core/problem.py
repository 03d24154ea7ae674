"""The plugin interface: what an optimiser sees of an identification problem.

An optimiser plugin only knows this module. It receives a :class:`SearchProblem` (in practice a
:class:`benchmark.core.budget.BudgetedProblem`)
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
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Protocol

import numpy as np


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
    #: Unit of each parameter of :meth:`estimate` (``{"Rs": "ohm", ...}``): tables and messages.
    units: dict[str, str] = {}

    @property
    def n_var(self) -> int:
        return len(self.parameter_names)

    def check_bounds(self) -> None:
        """Reject bounds that cannot be searched, with a message saying how to fix them."""
        from benchmark.core.errors import ConfigError

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


class TimeLimitExceeded(BaseException):
    """Raised inside a run when its wall-time limit (``time_limit_s``) has passed: from the
    SIGALRM handler at the next Python bytecode, or by :meth:`BudgetedProblem.evaluate` at
    the next evaluation. It derives from ``BaseException`` so that a plugin's own ``except
    Exception`` does not swallow it; :func:`run_plugin` records the run as ``timeout``."""




class SearchProblem(Protocol):
    """What an optimiser plugin may use of the problem it is handed (a
    :class:`benchmark.core.budget.BudgetedProblem`): names, bounds, a population cost, the
    residual vector of least-squares problems, and the evaluations left."""

    parameter_names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    n_var: int
    budget: int

    def evaluate(self, X: np.ndarray) -> np.ndarray:
        """Costs ``(n_pop,)`` of the population ``X (n_pop, n_var)``; rows past the budget cost +inf."""

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residual vector at ``x`` (least-squares problems); counts one evaluation."""

    def evaluate_one(self, x: np.ndarray) -> float:
        """Cost of one point; counts one evaluation."""

    def residuals_batch(self, X: np.ndarray) -> np.ndarray:
        """Residual vectors of a population, each counted; raises BudgetExhausted past the budget."""

    def crude_start(self) -> np.ndarray:
        """The problem's documented crude starting point (local methods start here)."""

    @property
    def remaining(self) -> int:
        """Evaluations left in the budget."""

    @property
    def exhausted(self) -> bool:
        """True once the budget is spent."""

    @property
    def has_residuals(self) -> bool:
        """True when the cost is a sum of squares with a residual vector."""

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
    traceback: str | None = None


