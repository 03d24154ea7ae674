"""A second look at an identification before its verdict: did the optimiser stop short, and does
the problem itself want the result from another set-up?

* **Stopped short** (:func:`stopped_short`): when the result misses the data or its budget ran
  out, a least-squares polish from the result (and, on synthetic data, the cost at the true
  parameters) tells an optimiser that stopped short from a model that misses the data. If
  either is lower than the result's cost by more than :data:`SHORT_GAIN`, the optimiser
  stopped short: a model at fault leaves a minimum a polish cannot lower. The result is not
  replaced (the benchmark compares optimisers as they ran); the warning says so and names the
  command that finishes the job (:mod:`benchmark.core.quality`).
* **The problem's second look** (``problem.second_look(x, identify, seed)``, optional): when the
  fit still misses the data, the problem may return a result of another problem that should
  replace it (time domain: a stop record that is no free coast set aside,
  :mod:`benchmark.problems.timedomain.stop_record`), with the lines that say why.
* **Calibration** (``problem.calibrate(x)``, optional, first): a cost whose weights depend on the
  fit (time domain: a prior on Rs weighed by the data's own uncertainty of Rs,
  :mod:`benchmark.problems.timedomain.stator_prior`) is set at the result, which is polished
  again, until the weights hold; ``problem.explain(x, polish_budget)`` (optional, at the final
  point: :meth:`Review.explain`) says what such a term did (``notes`` of the result).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from benchmark.core.budget import BudgetedProblem
from benchmark.core.polish import least_squares_batch, polish_least_squares
from benchmark.core.quality import fit_quality

#: A polish from the result, or the truth, with a cost this share lower: the optimiser stopped short.
SHORT_GAIN = 0.01
#: At most this many rounds of a problem's calibration (each: weights set at the fit, then a polish).
CALIBRATION_ROUNDS = 4


def misses(quality: dict) -> bool:
    """Some channel of a :func:`benchmark.core.quality.fit_quality` is above its noise band."""
    return any(isinstance(v, dict) and v["ratio"] > v["threshold"] for v in quality.values())


def true_point(problem) -> np.ndarray | None:
    """The searched vector at the problem's true parameters (synthetic data), or None."""
    truth = getattr(problem, "truth", None) or {}
    if not all(n in truth for n in problem.parameter_names):
        return None
    x = np.array([truth[n] for n in problem.parameter_names], float)
    return np.clip(x, problem.lower, problem.upper)


def stopped_short(problem, x, cost: float, status: str, polish_budget: int, quality: dict | None = None) -> dict | None:
    """Whether the optimiser stopped short of the minimum near its result ``x`` (cost ``cost``):
    checked when the fit misses the data or the status is ``budget_spent`` (None otherwise).
    Returns ``{"short", "cost", "polished_cost", "polish_evaluations", "truth_cost",
    "quality_polished", "x_polished"}`` (the polish's entries None for a problem without
    residuals, the truth's None without a truth); ``polish_evaluations`` are not counted in the
    optimiser's budget. ``quality``: the fit quality at ``x`` when already known."""
    if x is None or not math.isfinite(cost):
        return None
    quality = fit_quality(problem, x) if quality is None else quality
    if not (misses(quality) or status == "budget_spent"):
        return None
    out = {"cost": float(cost), "polished_cost": None, "polish_evaluations": 0, "truth_cost": None,
           "quality_polished": None, "x_polished": None}
    if getattr(problem, "has_residuals", False):
        with np.errstate(all="ignore"):
            pol = polish_least_squares(problem, np.asarray(x, float), int(polish_budget))
        if pol.best_x is not None and pol.best_cost < cost:
            out.update(polished_cost=float(pol.best_cost), x_polished=np.asarray(pol.best_x, float),
                       quality_polished=fit_quality(problem, pol.best_x))
        else:
            out["polished_cost"] = float(cost)
        out["polish_evaluations"] = int(pol.nfev)
    xt = true_point(problem)
    if xt is not None:
        out["truth_cost"] = float(problem.evaluate(xt[None, :])[0])
    lower = [c for c in (out["polished_cost"], out["truth_cost"]) if c is not None]
    out["short"] = bool(lower and min(lower) < (1.0 - SHORT_GAIN) * cost)
    return out


def least_squares_end(problem, x, budget: int) -> tuple[np.ndarray, int]:
    """Where least squares on the problem's residuals from ``x`` ends (within ``budget``
    evaluations), and the evaluations it took. Unlike a polish, which keeps the point of lowest
    problem cost, this is the minimum of the residuals' sum of squares itself: where the cost is
    eq. 15's sum of absolute errors, a term added to the least-squares objective (a prior)
    moves this point, while each step towards it may raise the absolute-error cost."""
    counted = BudgetedProblem(problem, int(budget))
    with np.errstate(all="ignore"):
        end, _ = least_squares_batch(counted.residuals_batch, np.asarray(x, float), counted.lower, counted.upper,
                                     int(budget))
    return np.asarray(end, float), int(counted.nfev)


def calibrated(problem, ident, polish_budget: int) -> tuple[object, dict | None]:
    """``ident`` after the problem's calibration (``problem.calibrate(x)``: True when it changed
    the cost's weights at ``x``; then least squares from ``x`` to its end, :func:`least_squares_end`,
    at most :data:`CALIBRATION_ROUNDS` rounds), with its cost under the final weights; and a
    record (rounds, evaluations), or None when the problem has nothing to calibrate."""
    calibrate = getattr(problem, "calibrate", None)
    if calibrate is None or ident.x is None:
        return ident, None
    x, rounds, evaluations = np.asarray(ident.x, float), 0, 0
    while rounds < CALIBRATION_ROUNDS and calibrate(x):
        rounds += 1
        x, n = least_squares_end(problem, x, polish_budget)
        evaluations += n
    if rounds == 0:
        return ident, None
    cost = float(problem.evaluate(x[None, :])[0])
    return dataclasses.replace(ident, x=x, cost=cost), {"rounds": rounds, "evaluations": evaluations}


def found_short(record: dict) -> bool:
    """Whether a run's record (``result.json``) says its review found the search stopped short of the
    fit's minimum (:func:`stopped_short`'s ``short``)."""
    return bool(((record.get("review") or {}).get("stopped_short") or {}).get("short"))


@dataclass
class Review:
    """What the second look found: the problem and identification to report (replaced when the
    problem's second look said so), the stopped-short check of that identification, what the
    second look and the calibration recorded, the warnings and notes the result must carry."""

    problem: object
    ident: object
    shortfall: dict | None = None
    second_look: dict | None = None
    calibration: dict | None = None
    explained: dict | None = None
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def explain(self, x, polish_budget: int) -> list[str]:
        """What the problem says about its final fit ``x`` (``problem.explain``; after anything
        that still moves ``x``, such as a nuisance's estimate): the notes of the result."""
        explain = getattr(self.problem, "explain", None)
        if explain is not None and x is not None:
            self.notes, self.explained = explain(x, polish_budget)
        return self.notes

    def record(self) -> dict:
        """The JSON-able part of the review for ``result.json``."""
        short = None if self.shortfall is None else {k: v for k, v in self.shortfall.items() if k != "x_polished"}
        second = None if self.second_look is None else self.second_look.get("record")
        return {"stopped_short": short, "second_look": second, "calibration": self.calibration,
                "explained": self.explained}


def review(problem, ident, *, identify: Callable, seed: int, polish_budget: int) -> Review:
    """The problem's calibration of ``ident`` (an :class:`benchmark.core.identify.Identification`),
    its stopped-short check, then, where the fit still misses the data at its best point, the
    problem's second look (``identify(problem, seed=...)`` runs the same identification on another
    problem); a replacing result gets its own calibration and check. What the problem says
    about the final fit comes after (:meth:`Review.explain`)."""
    ident, calibration = calibrated(problem, ident, polish_budget)
    quality = fit_quality(problem, ident.x) if ident.x is not None else {}
    out = Review(problem, ident, calibration=calibration,
                 shortfall=stopped_short(problem, ident.x, ident.cost, ident.status, polish_budget, quality))
    look = getattr(problem, "second_look", None)
    x_best = ident.x
    if out.shortfall is not None and out.shortfall["x_polished"] is not None:
        x_best, quality = out.shortfall["x_polished"], out.shortfall["quality_polished"]
    second = look(x_best, identify, seed) if look is not None and x_best is not None and misses(quality) else None
    if second is not None:
        out.second_look, out.warnings = second, list(second["lines"])
        if second.get("problem") is not None:
            out.problem = second["problem"]
            out.ident, out.calibration = calibrated(out.problem, second["identification"], polish_budget)
            out.shortfall = stopped_short(out.problem, out.ident.x, out.ident.cost, out.ident.status, polish_budget)
    return out
