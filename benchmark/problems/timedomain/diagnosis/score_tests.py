"""Linearised score tests: what each candidate effect would gain in one Gauss-Newton step.

For every addition (one effect, or a pair for the look-ahead) to the current model, the
augmented model is linearised at the current fit on one fold with the new effects at their
starting point (:func:`start_extras`: the point the screening fits start from; where an effect's
neutral value lies inside its box, e.g. a load torque or a heating of 0, that is its first
start), by forward differences in the fits' coordinates (each parameter normalised to its box,
as :meth:`JointModel.fit` does). One Gauss-Newton step for all parameters (base, chosen and
new), bounded to the box (:func:`scipy.optimize.lsq_linear`), is fitted to that fold's
residuals, and its linear prediction scores the other fold: ``predicted_heldout_chi2``. The
same step for the current model alone (``addition=()``) is the reference, so that what the
base's own unfinished convergence would gain is not credited to an effect: an addition's
``predicted_drop`` is the reference's predicted held-out chi^2 less its own.

Cost: one batch of ``k + 1`` rows per addition (``k`` its parameters), every addition's rows
simulated in one kernel call (:class:`.kernel_cache.KernelCache`), against a screening fit's
several Jacobians, its grid and its convergence rounds. A linearisation cannot see what only a
large step reaches (an instant, a knee far from the start): it ranks, the fits decide.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy import optimize

from benchmark.core.effects import Effect, EffectContext
from benchmark.problems.timedomain.diagnosis.fit import JointModel


def start_extras(eff: Effect, ctx: EffectContext) -> np.ndarray:
    """The point at which an effect is linearised: its first starting value."""
    return np.asarray(eff.extra_starts(ctx)[0], float)


def _linearisation(model: JointModel, x0: np.ndarray):
    """(u0, steps h, points X (k+1, k): x0 then x0 with each normalised coordinate stepped)."""
    lo, hi = model.lower, model.upper
    span = np.where(hi > lo, hi - lo, 1.0)
    u0 = np.clip((np.clip(x0, lo, hi) - lo) / span, 0.0, 1.0)
    h = 1e-6 * np.maximum(np.abs(u0), 1e-3)
    h = np.where(u0 + h > 1.0, -h, h)
    U = np.vstack([u0, u0[None, :] + np.diag(h)])
    return u0, h, lo + np.clip(U, 0.0, 1.0) * span


def score_tests(make_model: Callable[[list[Effect]], JointModel], chosen: Sequence[Effect], x_fit: np.ndarray,
                fit_mask: np.ndarray, held_mask: np.ndarray, additions: Sequence[tuple[Effect, ...]],
                ctx: EffectContext) -> list[dict]:
    """Score tests of ``additions`` (tuples of effects) to the model ``make_model(chosen)``
    fitted at ``x_fit`` on ``fit_mask``, scored on ``held_mask`` (residual masks). Returns one
    row per addition, best (largest predicted drop) first: ``effect`` (names joined by ``+``),
    ``predicted_heldout_chi2`` and ``predicted_drop`` (chi^2 per held-out residual),
    ``heldout_chi2_at_start`` (the linearisation point's own held-out chi^2) and ``step`` (the
    bounded Gauss-Newton step in normalised coordinates, new effects' part)."""
    todo = [()] + [tuple(a) for a in additions]
    plans = []
    for add in todo:
        model = make_model(list(chosen) + list(add))
        x0 = np.concatenate([np.asarray(x_fit, float)] + [start_extras(e, ctx) for e in add])
        u0, h, X = _linearisation(model, x0)
        plans.append((add, model, u0, h, X, model.rows(X)))
    kernel = plans[0][1].data.kernel
    sims = kernel.simulate(np.vstack([p[5] for p in plans]))
    rows_out, k = [], 0
    for add, model, u0, h, X, rows in plans:
        R = model.residuals_of(model.outputs(X, rows, sims[k:k + len(X)]))
        k += len(X)
        r0, J = R[0], ((R[1:] - R[0][None, :]) / h[:, None]).T  # d r / d u, (n_residuals, k)
        sol = optimize.lsq_linear(J[fit_mask], -r0[fit_mask], bounds=(-u0, 1.0 - u0), method="bvls")
        pred = r0[held_mask] + J[held_mask] @ sol.x
        n_new = sum(len(e.extra_names) for e in add)
        rows_out.append({"effect": "+".join(e.name for e in add), "predicted_heldout_chi2": float(np.mean(pred**2)),
                         "heldout_chi2_at_start": float(np.mean(r0[held_mask] ** 2)),
                         "step": sol.x[len(sol.x) - n_new:].tolist()})
    reference = rows_out[0]["predicted_heldout_chi2"]
    for row in rows_out:
        row["predicted_drop"] = reference - row["predicted_heldout_chi2"]
    return sorted(rows_out[1:], key=lambda r: -r["predicted_drop"])
