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

import contextlib
import enum
import faulthandler
import json
import math
import os
import signal
import struct
import sys
import threading
import time
import traceback
import warnings
import zlib
from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "Problem",
    "BudgetedProblem",
    "BudgetExhausted",
    "TimeLimitExceeded",
    "EvaluationJournal",
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


class TimeLimitExceeded(BaseException):
    """Raised inside a run when its wall-time limit (``time_limit_s``) has passed: from the
    SIGALRM handler at the next Python bytecode, or by :meth:`BudgetedProblem.evaluate` at
    the next evaluation. It derives from ``BaseException`` so that a plugin's own ``except
    Exception`` does not swallow it; :func:`run_plugin` records the run as ``timeout``."""


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
        from benchmark.errors import ConfigError

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
        from benchmark.errors import ResumeWarning

        warnings.warn(f"resume: {self.replay_mismatch['message']}", ResumeWarning, stacklevel=3)
        self._replay.clear()
        if self.journal is not None:
            self.journal.truncate_here()
        return None

    def verify_replay(self) -> None:
        """Before the plugin starts: simulate the first journaled point again. A different cost
        means the data or the code changed since the journal was written, and replaying it
        would be wrong (ResumeError). Not counted as an evaluation."""
        from benchmark.errors import ResumeError

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
        # residual vectors are not journaled (too large): a resumed run checks the point and
        # simulates it again
        with self._counting():
            n_before = self.replayed_batches
            if self._replay:
                self._replayed(KIND_RESIDUALS, X)
            replayed = self.replayed_batches > n_before
            r = np.asarray(self.problem.residuals(x), float)
            # the harness scores every evaluation by the problem's own cost, not the sum of squares
            cost = self.problem.cost_from_residuals(r) if np.all(np.isfinite(r)) else np.inf
            if not replayed:
                self._journal(KIND_RESIDUALS, X, np.array([cost]))
            self._record(X, np.array([cost]))
        return r

    def residuals_batch(self, X: np.ndarray) -> np.ndarray:
        """Residual vectors of a population (e.g. a finite-difference Jacobian's points), each
        counted as one evaluation. Raises BudgetExhausted if the batch does not fit the budget."""
        X = np.ascontiguousarray(np.atleast_2d(np.asarray(X, float)))
        if len(X) > self.remaining:
            raise BudgetExhausted(f"budget of {self.budget} evaluations spent")
        self.check_time()
        with self._counting():
            n_before = self.replayed_batches
            if self._replay:
                self._replayed(KIND_RESIDUALS, X)
            replayed = self.replayed_batches > n_before
            R = np.asarray(self.problem.residuals_batch(X), float)
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


def run_plugin(plugin, budgeted: BudgetedProblem, seed: int, name: str, *, time_limit_s: float | None = None,
               record_failures: bool = False) -> OptimizeResult:
    """Run one plugin callable ``plugin(problem, seed=...) -> OptimizerOutput`` and build the
    fixed result record from the harness's own counter.

    ``time_limit_s``: wall-time limit of the plugin (see :func:`time_limit`); past it the run
    ends with status ``timeout`` and the best point counted so far. ``record_failures``: an
    exception raised by the plugin becomes a ``failed`` result with its reason and traceback
    (``OptimizeResult.traceback``) instead of propagating; user errors
    (:class:`benchmark.errors.UserError`) always propagate. A plugin that returns something
    other than an :class:`OptimizerOutput` (or None), or an ``x`` that is not a finite vector
    of the right length, has failed too."""
    from benchmark.errors import UserError

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


# -- wall-time limit ---------------------------------------------------------------------------
#: After the limit, a plugin stuck in native code (which neither SIGALRM nor the check in
#: ``evaluate`` can interrupt) gets this much more time before the process is ended by
#: ``faulthandler`` (tracebacks on stderr, exit status 1, no result.json): max(this, limit/2) s.
HARD_KILL_GRACE_S = 30.0


@contextlib.contextmanager
def time_limit(seconds: float | None, budgeted: BudgetedProblem | None = None):
    """Raise :class:`TimeLimitExceeded` in the block once ``seconds`` of wall time have passed.

    Three layers, because no single one covers every way a plugin can hang:

    1. ``signal.setitimer(ITIMER_REAL)``: the SIGALRM handler raises in the main thread at
       the next Python bytecode, which stops a pure-Python loop that never evaluates, a
       ``time.sleep``, or a wait on a lock. Only in the main thread of a POSIX process (not
       on Windows, nor when a launcher runs jobs in threads); it replaces any SIGALRM handler
       for the duration of the block and restores it afterwards.
    2. ``budgeted.deadline``: every evaluation checks the clock, so a plugin that keeps
       evaluating stops even where signals are unavailable.
    3. ``faulthandler.dump_traceback_later``: native code that never returns to Python
       (a C extension or a compiled loop spinning forever, holding the GIL) cannot be
       interrupted at all from inside the process; after a grace period
       (:data:`HARD_KILL_GRACE_S`) the process dumps its tracebacks and exits with status 1.
       That run then has no ``result.json`` (its checkpoint journal survives) and a sweep in the
       same process stops: run such plugins under an external ``timeout`` if that matters.

    A signal arriving inside a plugin's ``finally``/``except BaseException`` block may be
    swallowed by it; layer 2 then catches the plugin at its next evaluation.
    """
    if seconds is None:
        yield
        return
    seconds = float(seconds)
    start = time.monotonic()
    if budgeted is not None:
        budgeted.deadline = start + seconds
        budgeted.time_limit_s = seconds
    if budgeted is not None:
        message = budgeted._time_message
    else:
        def message():
            return f"time limit of {seconds:g} s exceeded"

    use_signal = (hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread())
    previous = None
    armed = [True]

    def on_alarm(signum, frame):
        if not armed[0]:
            return
        armed[0] = False
        if budgeted is not None and budgeted._critical:
            budgeted._timeout_pending = True  # raised once the batch in flight is counted
            return
        raise TimeLimitExceeded(message())

    if use_signal:
        previous = signal.signal(signal.SIGALRM, on_alarm)
        signal.setitimer(signal.ITIMER_REAL, max(seconds, 1e-3))
    hard = max(HARD_KILL_GRACE_S, 0.5 * seconds) + seconds
    with contextlib.suppress(Exception):
        faulthandler.dump_traceback_later(hard, exit=True, file=sys.stderr)
    try:
        yield
    finally:
        armed[0] = False
        if budgeted is not None:
            budgeted._timeout_pending = False
        if use_signal:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous if previous is not None else signal.SIG_DFL)
        with contextlib.suppress(Exception):
            faulthandler.cancel_dump_traceback_later()
        if budgeted is not None:
            budgeted.deadline = None


# -- checkpoint journal ------------------------------------------------------------------------
KIND_EVALUATE = 0
KIND_RESIDUALS = 1


@dataclass
class JournalRecord:
    """One journaled batch: kind, the evaluated points (n, n_var), their costs, and where the
    record sits in the file (``offset`` .. ``end``)."""

    kind: int
    X: np.ndarray
    cost: np.ndarray
    offset: int
    end: int


@dataclass
class JournalContents:
    header: dict
    records: list[JournalRecord]
    valid_end: int  # bytes of header + complete records
    ignored_bytes: int  # a truncated or corrupt tail (a kill during a write), ignored


class EvaluationJournal:
    """Append-only binary log of every evaluated batch of a run (its checkpoint).

    Layout: ``MAGIC`` (16 bytes), ``<I`` header length, the header as JSON (fingerprint of
    the run, ``n_var``, parameter names, budget), ``<I`` CRC-32 of the header; then one record
    per batch: ``<4sBBHII`` (``b"EVAL"``, kind, 0, 0, n_rows, n_var), the points as
    little-endian float64 ``(n_rows, n_var)``, the costs as float64 ``(n_rows,)``, and ``<I``
    CRC-32 of all that. Each record is written with one ``write`` and flushed to the
    operating system (so it survives a SIGKILL; an ``fsync`` at most every
    :attr:`fsync_interval_s` also covers a power cut up to that interval). A record cut short by
    a kill fails its length or CRC check and is ignored, with everything after it.
    """

    MAGIC = b"IMBENCH-JOURNAL1"
    RECORD = struct.Struct("<4sBBHII")
    TAG = b"EVAL"
    fsync_interval_s = 5.0

    def __init__(self, path: Path, fh, position: int):
        self.path = Path(path)
        self._fh = fh
        self._pos = position  # end of the last record that belongs to this run
        self._last_sync = time.monotonic()

    # -- writing
    @classmethod
    def create(cls, path: Path, header: dict) -> EvaluationJournal:
        """Start a new journal at ``path`` (replacing any previous one)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        body = json.dumps(header, sort_keys=True, default=str).encode()
        blob = cls.MAGIC + struct.pack("<I", len(body)) + body + struct.pack("<I", zlib.crc32(body))
        fh = open(path, "wb", buffering=0)  # noqa: SIM115 - kept open for the run
        fh.write(blob)
        os.fsync(fh.fileno())
        return cls(path, fh, len(blob))

    @classmethod
    def reopen(cls, path: Path, contents: JournalContents) -> EvaluationJournal:
        """Continue a journal on resume: the ignored tail is cut off; replayed records are
        kept; new records go after the last replayed one."""
        fh = open(path, "r+b", buffering=0)  # noqa: SIM115 - kept open for the run
        fh.truncate(contents.valid_end)
        header_end = contents.records[0].offset if contents.records else contents.valid_end
        return cls(path, fh, header_end)

    def skip(self, rec: JournalRecord) -> None:
        """A replayed record stays: new records go after it."""
        self._pos = rec.end

    def truncate_here(self) -> None:
        """Drop the records after the last replayed one (they belong to another trajectory)."""
        self._fh.truncate(self._pos)

    def append(self, kind: int, X: np.ndarray, cost: np.ndarray) -> None:
        X = np.ascontiguousarray(X, dtype="<f8")
        cost = np.ascontiguousarray(cost, dtype="<f8")
        n, n_var = X.shape
        body = self.RECORD.pack(self.TAG, kind, 0, 0, n, n_var) + X.tobytes() + cost.tobytes()
        # live records only follow the replayed ones (a mismatch cut the rest off first)
        self._fh.seek(self._pos)
        self._fh.write(body + struct.pack("<I", zlib.crc32(body)))
        self._pos += len(body) + 4
        now = time.monotonic()
        if now - self._last_sync > self.fsync_interval_s:
            os.fsync(self._fh.fileno())
            self._last_sync = now

    def close(self) -> None:
        if self._fh is not None and not self._fh.closed:
            with contextlib.suppress(OSError):
                os.fsync(self._fh.fileno())
            self._fh.close()

    # -- reading
    @classmethod
    def read(cls, path: Path) -> JournalContents | None:
        """The header and every complete record of the journal at ``path``; None if there is
        no journal or its header was never completely written. Raises ResumeError if the file
        is not a journal."""
        from benchmark.errors import ResumeError

        path = Path(path)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise ResumeError(f"resume: cannot read the checkpoint {path}: {exc}") from None
        if len(data) < len(cls.MAGIC) + 4:
            return None if cls.MAGIC.startswith(data[: len(cls.MAGIC)]) else cls._not_a_journal(path)
        if not data.startswith(cls.MAGIC):
            cls._not_a_journal(path)
        k = len(cls.MAGIC)
        (hlen,) = struct.unpack_from("<I", data, k)
        k += 4
        if k + hlen + 4 > len(data):
            return None
        body = data[k:k + hlen]
        (crc,) = struct.unpack_from("<I", data, k + hlen)
        if zlib.crc32(body) != crc:
            return None
        try:
            header = json.loads(body)
        except ValueError:
            return None
        k += hlen + 4
        n_var = int(header.get("n_var", -1))
        records = []
        rsize = cls.RECORD.size
        while k + rsize <= len(data):
            tag, kind, _, _, n, nv = cls.RECORD.unpack_from(data, k)
            payload = n * nv * 8 + n * 8
            end = k + rsize + payload + 4
            if tag != cls.TAG or nv != n_var or n < 1 or kind not in (KIND_EVALUATE, KIND_RESIDUALS) \
                    or end > len(data):
                break
            (crc,) = struct.unpack_from("<I", data, end - 4)
            if zlib.crc32(data[k:end - 4]) != crc:
                break
            X = np.frombuffer(data, dtype="<f8", count=n * nv, offset=k + rsize).reshape(n, nv).astype(float)
            cost = np.frombuffer(data, dtype="<f8", count=n, offset=k + rsize + n * nv * 8).astype(float)
            records.append(JournalRecord(kind=kind, X=X, cost=cost, offset=k, end=end))
            k = end
        return JournalContents(header=header, records=records, valid_end=k, ignored_bytes=len(data) - k)

    @staticmethod
    def _not_a_journal(path):
        from benchmark.errors import ResumeError

        raise ResumeError(f"resume: {path} is not an imbench checkpoint journal")
