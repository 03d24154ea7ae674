"""A model the data can fix, chosen by the data (``problem.model: auto``).

Candidates: the 8-parameter circuit and the 6-parameter one, each with the leakage split free
or tied (``X1 = X2``). Each is fitted by least squares (SciPy trust-region, from the problem's
initial models A and E, the centre of the bounds and the fit of a simpler candidate), then
judged on two counts:

* **information criterion**: Schwarz's BIC, ``n ln(S^2) + k ln(n)`` with ``S^2`` the cost
  (the mean squared misfit of the n residuals) and k the searched parameters: a term must pay
  for itself in misfit;
* **identifiability from the Jacobian** at the fit: the textbook covariance ``s^2 (J'J)^-1`` (a test
  report, whose residuals are over its readings' stated errors: ``(J'J)^-1`` times the reduced chi^2 where
  it exceeds 1, the rule of the run's table, :func:`benchmark.core.uncertainty.stated_noise_covariance`)
  (rank-deficient directions count as infinite variance) gives each parameter's relative
  standard error and the correlations. A candidate's terms beyond the tied 6-parameter circuit
  (the free ``X2``; ``R2sigma``, ``X3``) must each be fixed by the data: relative standard error
  at most 25 %. (A correlation near 1 alone does not disqualify a term: on noise-free data the
  X1/X2 split of a full sweep is correlated at -1.0000 and yet fixed to 1e-10; the standard error
  weighs the correlation against the noise.)

The chosen model is the candidate of lowest BIC whose extra terms are fixed (the tied
6-parameter circuit has none, so there is always one). What the chosen model's data still cannot
separate is named: parameters with a relative standard error above 10 % and their most
correlated partner (near synchronous speed the stator resistance trades against the core-loss
resistance), and the tie itself (only ``X1 + X2`` is then fixed).

The fits spend evaluations outside the optimiser's budget (like the initial model E's
regression, a data-reduction step); the record says how many.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from benchmark.core.quality import jacobian
from benchmark.core.uncertainty import correlation, stated_noise_covariance, white_covariance

__all__ = ["CandidateFit", "ModelChoice", "fit_candidate", "choose_model", "CANDIDATES"]

#: (model, tie_x1_x2), most general first.
CANDIDATES = ((8, False), (8, True), (6, False), (6, True))
#: Terms a candidate adds to the tied 6-parameter circuit.
EXTRA = {(8, False): ("X2", "R2sigma", "X3"), (8, True): ("R2sigma", "X3"), (6, False): ("X2",), (6, True): ()}
#: Relative standard error above which a candidate's extra term is not fixed enough to keep it.
EXTRA_MAX = 0.25
#: Relative standard error above which a parameter is not fixed by the data (as the run's warnings).
NOT_FIXED = 0.5
#: Relative standard error above which a parameter is named as weakly fixed.
WEAK = 0.1
#: Smallest cost entering the criterion (noise-free data).
COST_FLOOR = 1e-24


@dataclass
class CandidateFit:
    """One candidate's least-squares fit and its verdicts."""

    model: int
    tie: bool
    names: tuple[str, ...]
    x: np.ndarray
    cost: float
    n: int
    rel_se: dict[str, float]
    corr: np.ndarray
    evaluations: int
    extra_fixed: bool = True
    reasons: list[str] = field(default_factory=list)
    stated_noise: bool = False  # residuals over the readings' stated errors (a test report)

    @property
    def label(self) -> str:
        return f"{self.model}-parameter, X1/X2 {'tied' if self.tie else 'free'}"

    @property
    def bic(self) -> float:
        return float(self.n * np.log(max(self.cost, COST_FLOOR)) + len(self.names) * np.log(self.n))

    def partner(self, name: str) -> tuple[str, float] | None:
        """The parameter most correlated with ``name`` and the correlation."""
        i = self.names.index(name)
        row = np.where(np.arange(len(self.names)) == i, 0.0, np.nan_to_num(np.abs(self.corr[i]), nan=0.0))
        j = int(np.argmax(row))
        return (self.names[j], float(self.corr[i, j])) if row[j] > 0 else None


def _identifiability(problem, x) -> tuple[dict[str, float], np.ndarray]:
    """Relative standard errors and correlations at ``x`` (infinite where the Jacobian is rank-deficient)."""
    r, J = jacobian(problem, x)
    ok = np.all(np.isfinite(J), axis=1) & np.isfinite(r)
    r, J = r[ok], J[ok]
    scale = np.where(np.abs(x) > 0, np.abs(x), 1e-3 * (problem.upper - problem.lower))
    sv, vt = np.linalg.svd(J * scale, full_matrices=False)[1:]
    null = sv <= sv.max() * 1e-9 if sv.size and sv.max() > 0 else np.ones(len(x), bool)
    if getattr(problem, "stated_noise", False):
        cov = stated_noise_covariance(J, r, warn=False)[0]  # the null space is read below
    else:
        cov = white_covariance(J, r)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if null.any():
        se[np.abs(vt[null]).max(axis=0) > 1e-3] = np.inf
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(np.abs(x) > 0, se / np.abs(x), np.inf)
    return dict(zip(problem.parameter_names, map(float, rel), strict=True)), correlation(cov)


def fit_candidate(problem, model: int, tie: bool, warm: dict | None = None) -> CandidateFit:
    """Least squares of ``problem`` (normalised to its bounds) from several starts, best kept."""
    lo, hi = problem.lower, problem.upper
    span = hi - lo
    starts = []
    for kind in ("E", "A"):
        try:
            with np.errstate(all="ignore"):
                x0 = problem.initial_guess(kind)
        except (ValueError, np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError):
            x0 = None
        if x0 is not None and np.all(np.isfinite(x0)):
            starts.append(x0)
    starts.append(problem.crude_start())
    if warm is not None:
        x0 = np.array([warm.get(n, 0.02 * (hi[i] - lo[i]) + lo[i]) for i, n in enumerate(problem.parameter_names)])
        starts.insert(0, np.clip(x0, lo + 1e-6 * span, hi - 1e-6 * span))
    best, evaluations = None, 0
    for x0 in starts:
        u0 = np.clip((x0 - lo) / span, 1e-9, 1 - 1e-9)
        res = problem.residuals(lo + u0 * span)
        if not np.all(np.isfinite(res)):
            continue
        sol = least_squares(lambda u: np.nan_to_num(problem.residuals(lo + u * span), nan=1e6, posinf=1e6),
                            u0, bounds=(0.0, 1.0), x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12,
                            max_nfev=300 * len(lo))
        evaluations += int(sol.nfev) + int(sol.njev or 0) * len(lo)
        if best is None or sol.cost < best.cost:
            best = sol
    if best is None:
        raise ValueError("no start with a finite cost")
    x = lo + best.x * span
    with np.errstate(all="ignore"):
        rel, corr = _identifiability(problem, x)
    fit = CandidateFit(model, tie, tuple(problem.parameter_names), x, float(problem.evaluate(x[None])[0]),
                       2 * problem.data.n, rel, corr, evaluations + 2 * len(x) + 1,
                       stated_noise=bool(getattr(problem, "stated_noise", False)))
    for name in EXTRA[(model, tie)]:
        if not rel[name] <= EXTRA_MAX:
            p = fit.partner(name)
            fit.reasons.append(f"{name} not fixed (relative standard error {_pct(rel[name])}"
                               + (f"; correlation with {p[0]} {p[1]:+.4f})" if p else ")"))
    fit.extra_fixed = not fit.reasons
    return fit


def _pct(v: float) -> str:
    return "infinite" if not np.isfinite(v) else f"{100 * v:.3g} %"


@dataclass
class ModelChoice:
    """The candidates, the chosen one and what its data cannot fix."""

    chosen: CandidateFit
    candidates: list[CandidateFit]

    @property
    def evaluations(self) -> int:
        return sum(c.evaluations for c in self.candidates)

    def not_fixed(self) -> list[str]:
        """Plain statements of what the chosen model's data do not fix: each weakly fixed parameter
        (relative standard error above 10 %) with its most correlated weakly fixed partner."""
        c, out, seen = self.chosen, [], set()
        weak = [n for n in sorted(c.names, key=lambda n: -c.rel_se[n]) if c.rel_se[n] > WEAK]
        for name in weak:
            if name in seen:
                continue
            i = c.names.index(name)
            partners = [(abs(c.corr[i, c.names.index(m)]), m) for m in weak if m != name and m not in seen
                        and np.isfinite(c.corr[i, c.names.index(m)])]
            r, m = max(partners, default=(0.0, None))
            if m is not None and r >= 0.8:
                out.append(f"{name} and {m} are not separated by these data (correlation "
                           f"{c.corr[i, c.names.index(m)]:+.3f}; relative standard errors {_pct(c.rel_se[name])}, "
                           f"{_pct(c.rel_se[m])})")
                seen |= {name, m}
            else:
                verdict = "not fixed" if not c.rel_se[name] <= NOT_FIXED else "weakly fixed"
                out.append(f"{name} is {verdict} by these data (relative standard error {_pct(c.rel_se[name])})")
                seen.add(name)
        if c.tie:
            out.append("X1 = X2 is a convention (the leakage split is not fixed by terminal measurements): "
                       "only X1 + X2 is fixed")
        return out

    def warnings(self) -> list[str]:
        stated = self.not_fixed()
        covariance = ("from the readings' stated errors, as the table's" if self.chosen.stated_noise
                      else "white-noise ones, not the table's HAC ones of the run")
        return [f"model choice ({self.chosen.label}; standard errors of its own least-squares fit, "
                f"{covariance}): " + "; ".join(stated)] if stated else []

    def record(self) -> dict:
        return {
            "chosen": self.chosen.label,
            "criterion": "lowest BIC = n ln(S^2) + k ln(n) among candidates whose terms beyond the tied "
                         f"6-parameter circuit are fixed (relative standard error <= {EXTRA_MAX:g})",
            "candidates": [{"model": c.label, "bic": c.bic, "cost": c.cost, "parameters": len(c.names),
                            "extra_terms_fixed": c.extra_fixed, "reasons": c.reasons,
                            "relative_standard_error": {k: (v if np.isfinite(v) else None)
                                                        for k, v in c.rel_se.items()}}
                           for c in self.candidates],
            "not_fixed": self.not_fixed(),
            "evaluations": self.evaluations,
            "counted_in_budget": False,
        }


def choose_model(make: Callable[[int, bool], object], ties: tuple[bool, ...] = (False, True)) -> ModelChoice:
    """Fit every candidate (``make(model, tie)`` builds its problem) and choose (module docstring).
    ``ties`` restricts the leakage split (``(True,)``: tied only)."""
    fits: dict[tuple[int, bool], CandidateFit] = {}
    for model, tie in sorted((c for c in CANDIDATES if c[1] in ties), key=lambda c: (c[0], not c[1])):
        warm = None
        if fits:
            best = min(fits.values(), key=lambda f: f.cost)
            warm = dict(zip(best.names, best.x, strict=True))
            if best.tie and not tie:
                warm["X2"] = warm["X1"]
        fits[(model, tie)] = fit_candidate(make(model, tie), model, tie, warm)
    ranked = sorted(fits.values(), key=lambda f: f.bic)
    fewest = min(fits.values(), key=lambda f: len(f.names))  # when no candidate's extra terms are fixed
    chosen = next((f for f in ranked if f.extra_fixed), fewest)
    return ModelChoice(chosen, [fits[c] for c in CANDIDATES if c in fits])
