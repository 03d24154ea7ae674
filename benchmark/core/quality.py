"""What a user needs to trust an identification: parameter uncertainty, a fit-quality verdict
and plain-English warnings, computed once at the final point of a run.

* **Standard errors and correlation** (:func:`parameter_uncertainty`): the residual Jacobian at
  the final point by central differences through ``problem.residuals_batch`` (in the problem's
  own units: the searched parameters), then the HAC sandwich covariance of
  :func:`benchmark.core.uncertainty.hac_covariance` per residual channel (honest for coloured
  residuals and a smooth model misfit; lags never cross a channel). The Bartlett bandwidth is
  the Andrews plug-in, but at least the problem's ``hac_bandwidth_floor()`` (time domain: one
  supply period in samples): the scores of a machine record are modulated at the supply
  frequency, and the AR(1) plug-in reads white + AR(1) bench noise as nearly white (zoo study:
  coverage of the 95 % intervals 70 % with the plug-in alone, 90 % with the floor, coloured
  noise; 98 % either way with white noise). A problem whose residuals are over their readings' stated
  standard errors (``problem.stated_noise``: a motor's test report) takes ``(J'J)^-1`` instead, times the
  reduced chi^2 where it exceeds 1 (:func:`benchmark.core.uncertainty.stated_noise_covariance`). These ``2 n_var``
  evaluations are not counted in the optimiser's budget: the record says so.
* **Fit quality** (:func:`fit_quality`): per channel, the RMS of the held-in residual over the
  channel's noise estimated from the data alone (the problem's ``fit_channels``: a steady-state
  periodic fit, a quiet pre-trigger or a smooth channel), judged by
  :func:`benchmark.core.uncertainty.misfit_ratio` (the band the diagnosis uses for its
  statuses).
* **Warnings** (:func:`quality_warnings`): the optimiser stopped short or the model misses the
  data (:func:`misses_data_warning`, each with a complete command to run next), a parameter at a bound,
  a parameter not identifiable (huge standard error, ``|corr|`` near 1), the budget spent
  without convergence, plus the problem's own (``problem.quality_warnings``: e.g. Rs against
  the DC resistance).
"""

from __future__ import annotations

import math
import warnings as _warnings

import numpy as np

from benchmark.core import commands
from benchmark.core.nuisance import JointView, has_nuisance
from benchmark.core.uncertainty import (
    correlation,
    hac_covariance_floored,
    misfit_ratio,
    standard_errors,
    stated_noise_covariance,
    uncertainty_warnings,
)

#: Central-difference step, relative to each parameter (absolute floor: this times the bound span).
JACOBIAN_REL_STEP = 1e-5
#: ``|corr|`` above which two parameters are reported as not separately identifiable.
CORR_MAX = 0.995
#: Relative standard error above which a parameter is reported as not identifiable.
REL_SE_MAX = 0.5


def jacobian(problem, x, rel_step: float = JACOBIAN_REL_STEP) -> tuple[np.ndarray, np.ndarray]:
    """(residuals at ``x``, Jacobian (m, k)) by central differences, one batch of ``2k + 1``
    residual vectors through ``problem.residuals_batch`` (uncounted). A step that would leave
    the bounds (a parameter at or next to a bound, e.g. a friction of 0) is taken one-sided,
    inside the bounds."""
    x = np.asarray(x, float)
    k = len(x)
    lo, hi = np.asarray(problem.lower, float), np.asarray(problem.upper, float)
    span = hi - lo
    h = rel_step * np.maximum(np.abs(x), np.where(np.isfinite(span), span, 1.0) * 1e-3)
    up = np.where(x + h <= hi, x + h, x)      # forward point (x itself at the upper bound)
    down = np.where(x - h >= lo, x - h, x)    # backward point (x itself at the lower bound)
    X = np.vstack([x[None, :], np.where(np.eye(k, dtype=bool), up[None, :], x[None, :]),
                   np.where(np.eye(k, dtype=bool), down[None, :], x[None, :])])
    R = np.asarray(problem.residuals_batch(X), float)
    r0 = R[0]
    J = (R[1:k + 1] - R[k + 1:]).T / (up - down)[None, :]
    return r0, J


STATED_METHOD = ("(J'J)^-1 of the residuals over the readings' stated standard errors at the final point, "
                 "times the reduced chi^2 where it exceeds 1 (the stated errors too small for the misfit)")


def parameter_uncertainty(problem, x) -> dict:
    """Standard errors, correlation and the method of a least-squares problem at ``x``.

    Returns ``{"standard_error": {name: se}, "correlation": [[...]], "info": {...}}``; the
    standard errors are nan where not finite (rank-deficient Jacobian)."""
    names = list(problem.parameter_names)
    k = len(names)
    joint = None
    if has_nuisance(problem):  # the nuisance is estimated too: its columns join the Jacobian
        joint = JointView(problem)
        x = np.concatenate([np.asarray(x, float), np.asarray(problem.nuisance_values, float)])
    r0, J = jacobian(joint or problem, x)
    ok = np.all(np.isfinite(J), axis=1) & np.isfinite(r0)
    layout = residual_layout(problem, len(r0))
    groups = np.empty(len(r0), dtype=int)
    for g, (_, a, b) in enumerate(layout):
        groups[a:b] = g
    # drop rows that carry no information (zero weight, masked, non-finite); keep segments contiguous
    live = ok & (np.any(J != 0, axis=1) | (r0 != 0))
    Jl, rl, gl = J[live], r0[live], groups[live]
    if len(rl) <= J.shape[1]:
        raise ValueError("too few informative residuals for a covariance")
    floor_fn = getattr(problem, "hac_bandwidth_floor", None)
    floor = float(floor_fn()) if floor_fn is not None else 0.0
    stated = bool(getattr(problem, "stated_noise", False))
    with _warnings.catch_warnings(record=True) as caught:
        _warnings.simplefilter("always")
        if stated:
            cov, info = stated_noise_covariance(Jl, rl)
        else:
            cov, info = hac_covariance_floored(Jl, rl, groups=gl, floor=floor)
    se = standard_errors(cov)
    if info.rank < info.k:
        involved = np.flatnonzero(np.abs(info.null_space).max(axis=1) > 1e-3)
        se[involved] = np.nan
    corr = correlation(cov)
    nuisance = None
    if joint is not None:
        nuisance = {n: {"value": float(v), "standard_error": float(s) if np.isfinite(s) else None}
                    for n, v, s in zip(problem.nuisance_names, x[k:], se[k:], strict=True)}
        se, corr = se[:k], corr[:k, :k]
    return {
        "standard_error": {n: (float(s) if np.isfinite(s) else None) for n, s in zip(names, se, strict=True)},
        "correlation": [[(float(c) if np.isfinite(c) else None) for c in row] for row in corr],
        "info": {
            "method": (STATED_METHOD if stated else
                       "HAC sandwich (Newey-West, Andrews bandwidth, VAR(1) prewhitening) on the residual "
                       "Jacobian at the final point, per residual channel"),
            "jacobian": f"central differences (one-sided at a bound), relative step {JACOBIAN_REL_STEP:g}",
            "evaluations": 2 * J.shape[1] + 1,
            "nuisance": (None if nuisance is None else
                         "marginalised: the Jacobian has a column per nuisance parameter (estimated with "
                         "the motor's parameters) " + ", ".join(
                             f"{n} = {d['value']:.4g} (standard error {d['standard_error'] or float('nan'):.2g})"
                             for n, d in nuisance.items())),
            "counted_in_budget": False,
            "rank": int(info.rank),
            "bandwidth": float(info.bandwidth),
            "bandwidth_floor": floor,
            "messages": [str(w.message) for w in caught],
        },
        "_se": se,
        "_corr": corr,
    }


def residual_layout(problem, m: int) -> list[tuple[str, int, int]]:
    """(channel name, start, stop) of each contiguous residual segment: the problem's own
    ``residual_layout()`` when it has one, else one channel."""
    fn = getattr(problem, "residual_layout", None)
    if fn is None:
        return [("residual", 0, m)]
    return list(fn())


def fit_quality(problem, x) -> dict:
    """``{channel: {ratio, threshold, at_noise_level, noise, noise_method}}`` from the
    problem's ``fit_channels(x)`` (empty when it has none)."""
    fn = getattr(problem, "fit_channels", None)
    if fn is None:
        return {}
    out = {}
    for name, residual, noise in fn(x):
        if noise is None:
            continue
        q = misfit_ratio(residual, noise)
        out[name] = {"ratio": float(q.ratio), "threshold": float(q.threshold), "lower": float(q.lower),
                     "at_noise_level": bool(q.at_noise_level), "noise": float(noise.std),
                     "noise_method": noise.method,
                     "rms_misfit": float(math.sqrt(float(np.mean(np.asarray(residual, float) ** 2))))}
    return out


def _above(quality: dict) -> dict:
    return {k: v for k, v in (quality or {}).items() if isinstance(v, dict) and v["ratio"] > v["threshold"]}


def _misfits(above: dict) -> str:
    return ", ".join(f"{k} {v['ratio']:.3g}x the noise (band up to {v['threshold']:.3g})" for k, v in above.items())


def misses_data_warning(quality: dict, overrides=None, shortfall: dict | None = None) -> str | None:
    """The one warning on the fit itself: "the optimiser stopped short" (a polish from the result,
    or the true parameters, lower the cost: :func:`benchmark.core.review.stopped_short`), or
    "the model misses the data" (some channel above its noise band where the optimiser is not
    at fault), or both; each with the complete command to run next (the run's ``overrides``,
    :mod:`benchmark.core.commands`). None when the fit is at the noise level and the optimiser
    did not stop short."""
    overrides = list(overrides or [])
    diagnose = commands.diagnose_command(overrides)
    if shortfall is not None and shortfall.get("short"):
        found = []
        if shortfall.get("polished_cost") is not None and shortfall["polished_cost"] < shortfall["cost"]:
            found.append(f"a least-squares polish from the result lowers the cost from {shortfall['cost']:.6g} to "
                         f"{shortfall['polished_cost']:.6g}")
        if shortfall.get("truth_cost") is not None and shortfall["truth_cost"] < shortfall["cost"]:
            found.append(f"the cost at the true parameters is {shortfall['truth_cost']:.6g}")
        finish = (f"run `{commands.rerun_command(overrides, polish=True)}` (the same run with a polish), or the "
                  f"default optimiser: `{commands.rerun_command(overrides, optimizer=None, budget=None)}`")
        still = _above(shortfall.get("quality_polished"))
        if shortfall.get("quality_polished") and not still:  # (a problem without fit channels says nothing)
            return (f"the optimiser stopped short: {' and '.join(found)}, and the polished fit is at the noise "
                    f"level: the model does not miss the data, the search ended early; {finish}")
        tail = (f"; even the polished fit misses the data: RMS misfit of {_misfits(still)}; then run `{diagnose}`"
                if still else "")
        return f"the optimiser stopped short: {' and '.join(found)}; {finish}{tail}"
    above = _above(quality)
    if not above:
        return None
    why = (" (a polish from the result does not lower the cost: the optimiser is not at fault)"
           if shortfall is not None and shortfall.get("polished_cost") is not None else "")
    return f"the model misses the data{why}: RMS misfit of {_misfits(above)}; run `{diagnose}` to see why"


def quality_warnings(problem, x, *, se, corr, quality: dict, status: str, overrides=None,
                     budget: int | None = None, shortfall: dict | None = None) -> list[str]:
    """All warnings of a result (see the module docstring); empty when all is well."""
    out = []
    w = misses_data_warning(quality, overrides, shortfall)
    if w:
        out.append(w)
    if se is not None:
        out += uncertainty_warnings(problem.parameter_names, x, se, corr, problem.lower, problem.upper,
                                    rel_se_max=REL_SE_MAX, corr_max=CORR_MAX, units=getattr(problem, "units", None),
                                    bounds_key="bounds")
    if status == "budget_spent":
        b = f" of {budget} evaluations" if budget else ""
        if shortfall is not None and not shortfall.get("short") and shortfall.get("polished_cost") is not None:
            out.append(f"the budget{b} was spent without convergence, but a least-squares polish from the result "
                       "lowers the cost by less than 1 %: the estimate is near a minimum")
        elif not (shortfall or {}).get("short"):  # (the stopped-short warning already says what to run)
            out.append(f"the budget{b} was spent without convergence: the estimate may not be a minimum (run "
                       f"`{commands.rerun_command(overrides, polish=True)}`)")
    own = getattr(problem, "quality_warnings", None)
    if own is not None:
        out += list(own(x))
    return out


def assess(problem, x, *, status: str, data_path: str | None = None, budget: int | None = None, overrides=None,
           shortfall: dict | None = None) -> dict:
    """Everything above for a result record: ``standard_error``, ``correlation``,
    ``uncertainty`` (method and notes), ``fit_quality`` and ``warnings`` (a list). ``overrides``
    (the run's command-line overrides; default: ``data.path=data_path`` when given) make the
    commands the warnings suggest; ``shortfall`` is the result's
    :func:`benchmark.core.review.stopped_short` check.

    Never raises: what cannot be computed is None, with the reason in ``uncertainty``."""
    out = {"standard_error": None, "correlation": None, "uncertainty": None, "fit_quality": {}, "warnings": []}
    if x is None:
        return out
    x = np.asarray(x, float)
    se = corr = None
    if getattr(problem, "has_residuals", False):
        try:
            with np.errstate(all="ignore"):
                u = parameter_uncertainty(problem, x)
            se, corr = u.pop("_se"), u.pop("_corr")
            out.update(standard_error=u["standard_error"], correlation=u["correlation"], uncertainty=u["info"])
        except Exception as exc:  # an uncertainty that cannot be computed must not lose the result
            out["uncertainty"] = {"error": f"{type(exc).__name__}: {exc}"}
    else:
        out["uncertainty"] = {"error": f"problem {problem.name!r} has no residual vector"}
    try:
        with np.errstate(all="ignore"):
            out["fit_quality"] = fit_quality(problem, x)
    except Exception as exc:
        out["fit_quality"] = {"error": f"{type(exc).__name__}: {exc}"}
    fq = {k: v for k, v in out["fit_quality"].items() if isinstance(v, dict)}
    if overrides is None:
        overrides = [] if data_path is None else [f"data.path={data_path}"]
    out["warnings"] = quality_warnings(problem, x, se=se, corr=corr, quality=fq, status=status,
                                       overrides=overrides, budget=budget, shortfall=shortfall)
    return out
