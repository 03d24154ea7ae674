"""The one place that counts evaluations: :class:`BudgetedProblem`, and :func:`run_plugin`,
which runs a plugin against it and builds the fixed result record.

Every row of every call counts, also inside a vectorised call; the call that crosses the
budget is trimmed and the rows past the budget get ``+inf`` without being simulated.
"""

from __future__ import annotations

import contextlib
import math
import time
import traceback
import warnings
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from benchmark.core.deadline import time_limit
from benchmark.core.journal import KIND_EVALUATE, KIND_RESIDUALS, EvaluationJournal, JournalRecord
from benchmark.core.problem import BudgetExhausted, OptimizeResult, OptimizerOutput, Problem, Status, TimeLimitExceeded


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

    def __init__(self, problem: Problem, budget: int, *, journal: EvaluationJournal | None = None,
                 replay: list[JournalRecord] | None = None):
        from benchmark.core.errors import ConfigError

        if int(budget) < 1:
            raise ConfigError(f"budget: must be a positive number of evaluations, got {budget}")
        self.problem = problem
        self.budget = int(budget)
        self.nfev = 0
        self.best_x: np.ndarray | None = None
        self.best_cost = np.inf
        self.history = History()
        #: ``time.monotonic()`` past which every evaluation raises TimeLimitExceeded (None: no limit)
        self.deadline: float | None = None
        self.time_limit_s: float | None = None
        #: checkpoint: every evaluated batch is appended here (see :class:`EvaluationJournal`)
        self.journal = journal
        #: resume: journaled batches a deterministic plugin will ask for again, in order
        self._replay: deque[JournalRecord] = deque(replay or ())
        self.replayed_batches = 0
        self.replayed_evaluations = 0
        self.replay_mismatch: dict | None = None
        self._critical = 0  # > 0 while a batch is being simulated, journaled and counted
        self._timeout_pending = False
        #: optional ``on_evaluate(self)``, called after every counted batch (the harness sets it
        #: for its progress bar); it must be cheap and must not raise
        self.on_evaluate: Callable[[BudgetedProblem], None] | None = None

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
        if X.ndim != 2 or X.shape[1] != self.n_var:
            raise ValueError(f"population has shape {X.shape}, problem has {self.n_var} parameters")
        n_run = max(0, min(len(X), self.remaining))
        cost = np.full(len(X), np.inf)
        if n_run:
            self.check_time()
            Xr = np.ascontiguousarray(X[:n_run])
            with self._counting():
                c = self._replayed(KIND_EVALUATE, Xr)
                if c is None:
                    c = np.asarray(self.problem.evaluate(Xr), dtype=float).reshape(n_run)
                    c = np.where(np.isnan(c), np.inf, c)
                    self._journal(KIND_EVALUATE, Xr, c)
                cost[:n_run] = c
                self._record(Xr, c)
        return cost

    @contextlib.contextmanager
    def _counting(self):
        """Simulating, journaling and counting a batch is one step: a time-limit alarm that
        arrives meanwhile is held until the batch is counted (so the journal, the count and the
        history agree), then raised."""
        self._critical += 1
        try:
            yield
        finally:
            self._critical -= 1
        if self._critical == 0 and self._timeout_pending:
            self._timeout_pending = False
            raise TimeLimitExceeded(self._time_message())

    def check_time(self) -> None:
        """Raise TimeLimitExceeded once the run's deadline has passed (called before every
        evaluation; plugins that loop without evaluating are stopped by the SIGALRM timer)."""
        if self.deadline is not None and time.monotonic() > self.deadline:
            raise TimeLimitExceeded(self._time_message())

    def _time_message(self) -> str:
        return (f"time limit of {self.time_limit_s:g} s exceeded after {self.nfev} evaluations"
                if self.time_limit_s is not None else "time limit exceeded")

    # -- checkpoint journal and resume ------------------------------------------------------
    def _journal(self, kind: int, X: np.ndarray, cost: np.ndarray) -> None:
        if self.journal is not None:
            self.journal.append(kind, X, cost)

    def _replayed(self, kind: int, X: np.ndarray) -> np.ndarray | None:
        """On resume: the journaled costs if this batch is, bit for bit, the next journaled
        one (not simulated again); None to evaluate live. The first mismatch ends the replay:
        the plugin is not deterministic (or its inputs changed), the journal is cut there and
        the run goes on live (reported in ``result.json`` as ``resume.mismatch``)."""
        if not self._replay:
            return None
        rec = self._replay[0]
        if rec.kind == kind and rec.X.shape == X.shape and rec.X.tobytes() == X.tobytes():
            self._replay.popleft()
            self.replayed_batches += 1
            self.replayed_evaluations += len(X)
            if self.journal is not None:
                self.journal.skip(rec)
            return rec.cost if kind == KIND_EVALUATE else None
        self.replay_mismatch = {
            "batch": self.replayed_batches + 1,
            "evaluations_replayed": self.replayed_evaluations,
            "journaled_rows": int(rec.X.shape[0]),
            "requested_rows": int(X.shape[0]),
            "message": (f"the plugin asked for batch {self.replayed_batches + 1} with points that differ "
                        "from the journal (it is not deterministic for a given seed?): the run went on "
                        f"live from evaluation {self.nfev + 1}, so it is not identical to an "
                        "uninterrupted run"),
        }
        from benchmark.core.errors import ResumeWarning

        warnings.warn(f"resume: {self.replay_mismatch['message']}", ResumeWarning, stacklevel=3)
        self._replay.clear()
        if self.journal is not None:
            self.journal.truncate_here()
        return None

    def verify_replay(self) -> None:
        """Before the plugin starts: simulate the first journaled point again. A different cost
        means the data or the code changed since the journal was written, and replaying it
        would be wrong (ResumeError). Not counted as an evaluation."""
        from benchmark.core.errors import ResumeError

        if not self._replay:
            return
        rec = self._replay[0]
        x = rec.X[:1]
        if rec.kind == KIND_EVALUATE:
            c = float(np.asarray(self.problem.evaluate(x), dtype=float).reshape(-1)[0])
        else:
            r = np.asarray(self.problem.residuals(x[0]), float)
            c = self.problem.cost_from_residuals(r) if np.all(np.isfinite(r)) else math.inf
        c = math.inf if math.isnan(c) else c
        if np.float64(c).tobytes() != np.float64(rec.cost[0]).tobytes():
            raise ResumeError(
                f"resume: the journal's first cost {rec.cost[0]!r} differs from the same point simulated "
                f"now ({c!r}): the data or the code changed since the checkpoint; start afresh with "
                "resume=false"
            )

    @property
    def replaying(self) -> bool:
        return bool(self._replay)

    def __call__(self, X: np.ndarray) -> np.ndarray:
        return self.evaluate(X)

    def evaluate_one(self, x: np.ndarray) -> float:
        return float(self.evaluate(np.asarray(x, float)[None, :])[0])

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Residual vector at ``x``; counts one evaluation. Raises BudgetExhausted when spent."""
        if self.exhausted:
            raise BudgetExhausted(f"budget of {self.budget} evaluations spent")
        self.check_time()
        x = np.asarray(x, float)
        X = np.ascontiguousarray(x[None, :])
        return self._counted_residuals(X, lambda: np.asarray(self.problem.residuals(x), float)[None, :])[0]

    def residuals_batch(self, X: np.ndarray) -> np.ndarray:
        """Residual vectors of a population (e.g. a finite-difference Jacobian's points), each
        counted as one evaluation. Raises BudgetExhausted if the batch does not fit the budget."""
        X = np.ascontiguousarray(np.atleast_2d(np.asarray(X, float)))
        if len(X) > self.remaining:
            raise BudgetExhausted(f"budget of {self.budget} evaluations spent")
        self.check_time()
        return self._counted_residuals(X, lambda: np.asarray(self.problem.residuals_batch(X), float))

    def _counted_residuals(self, X: np.ndarray, residual_rows) -> np.ndarray:
        """The residual rows ``residual_rows()`` (one per row of ``X``), counted, scored and
        journaled. Residual vectors are not journaled (too large): a resumed run checks the
        points and simulates them again."""
        with self._counting():
            n_before = self.replayed_batches
            if self._replay:
                self._replayed(KIND_RESIDUALS, X)
            replayed = self.replayed_batches > n_before
            R = residual_rows()
            # the harness scores every evaluation by the problem's own cost, not the sum of squares
            cost = np.array([self.problem.cost_from_residuals(r) if np.all(np.isfinite(r)) else np.inf
                             for r in R])
            if not replayed:
                self._journal(KIND_RESIDUALS, X, cost)
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
        if self.on_evaluate is not None:
            self.on_evaluate(self)


def run_plugin(plugin, budgeted: BudgetedProblem, seed: int, name: str, *, time_limit_s: float | None = None,
               record_failures: bool = False) -> OptimizeResult:
    """Run one plugin callable ``plugin(problem, seed=...) -> OptimizerOutput`` and build the
    fixed result record from the harness's own counter.

    ``time_limit_s``: wall-time limit of the plugin (see :func:`time_limit`); past it the run
    ends with status ``timeout`` and the best point counted so far. ``record_failures``: an
    exception raised by the plugin becomes a ``failed`` result with its reason and traceback
    (``OptimizeResult.traceback``) instead of propagating; user errors
    (:class:`benchmark.core.errors.UserError`) always propagate. A plugin that returns something
    other than an :class:`OptimizerOutput` (or None), or an ``x`` that is not a finite vector
    of the right length, has failed too."""
    from benchmark.core.errors import UserError

    t0 = time.perf_counter()
    trace = None
    nit = 0
    try:
        with time_limit(time_limit_s, budgeted):
            out = plugin(budgeted, seed=seed)
        status = Status.BUDGET_SPENT if budgeted.exhausted else Status.CONVERGED
        message = ""
        problem_with_output = _check_output(out, budgeted.n_var)
        if problem_with_output:
            status, message = Status.FAILED, problem_with_output
        else:
            message = str(getattr(out, "message", "") or "")
            nit = _as_int(getattr(out, "nit", 0))
    except BudgetExhausted as exc:
        status, message = Status.BUDGET_SPENT, str(exc)
    except TimeLimitExceeded as exc:
        status, message = Status.TIMEOUT, str(exc) or budgeted._time_message()
    except UserError:
        raise
    except Exception as exc:
        if not record_failures:
            raise
        status, message = Status.FAILED, f"{type(exc).__name__}: {exc}"
        trace = traceback.format_exc()
    wall = time.perf_counter() - t0
    if status in (Status.BUDGET_SPENT, Status.CONVERGED) and (
            budgeted.best_x is None or not np.isfinite(budgeted.best_cost)):
        status = Status.FAILED
        message = message or "no finite cost was found"
    elif status == Status.TIMEOUT and budgeted.best_cost < np.inf:
        message += f" (best cost so far {budgeted.best_cost:.6g})"
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
        traceback=trace,
    )


def _check_output(out, n_var: int) -> str:
    """'' if the plugin's return value is usable, else why not."""
    if out is None:
        return ""
    if not isinstance(out, OptimizerOutput):
        return f"plugin returned {_short(out)} ({type(out).__name__}), expected an OptimizerOutput"
    if out.x is not None:
        try:
            x = np.asarray(out.x, dtype=float)
        except (TypeError, ValueError):
            return f"plugin returned x = {_short(out.x)}, not a vector of numbers"
        if x.shape != (n_var,):
            return f"plugin returned x of shape {x.shape}, expected ({n_var},)"
        if not np.all(np.isfinite(x)):
            return f"plugin returned a non-finite x = {_short(x.tolist())}"
    return ""


def _as_int(v) -> int:
    try:
        return int(v or 0)
    except (TypeError, ValueError, OverflowError):
        return 0


def _short(v, limit: int = 80) -> str:
    try:
        r = repr(v)
    except Exception:
        r = f"<{type(v).__name__}>"
    return r if len(r) <= limit else r[: limit - 3] + "..."


