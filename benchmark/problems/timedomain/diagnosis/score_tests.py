"""Linearised score tests: what each candidate effect would gain in one Gauss-Newton step.

For every addition (one effect, or a pair for the look-ahead) to the current model, the
augmented model is linearised at the current fit on one fold with the new effects at their
starting point (:func:`start_extras`: the point the screening fits start from; where an
effect's neutral value lies inside its box, e.g. a load torque or a heating of 0, that is its
first start; or the screening's own starts, given by the caller; an instant on an effect's
start grid is held), by forward differences in the fits'
coordinates (each parameter normalised to its box, as :meth:`JointModel.fit` does). One
Gauss-Newton step of all parameters (base, chosen and new), bounded to the box
(:func:`scipy.optimize.lsq_linear`), is fitted to that fold's residuals. Its linear prediction
of the other fold is ``predicted_heldout_chi2``; the model evaluated after the step (or half or
a quarter of it, whichever fits the fitted fold best) gives ``heldout_chi2``; the lower of the
two ranks the additions (``score``). The same for the current model alone is the reference, so
that what the base's own unfinished convergence would gain is not credited to an effect:
``drop`` is the reference's score less the addition's.

Cost: a batch of ``k + 1`` rows per addition (``k`` its parameters) and three after the step,
every addition's rows simulated in one kernel call (:class:`.kernel_cache.KernelCache`), and a
grid's rows where an effect has one; a screening fit takes several Jacobians, its grid and its
convergence rounds. One step cannot see what only a long path reaches: it ranks, the fits decide.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy import optimize

from benchmark.core.effects import Effect, EffectContext
from benchmark.problems.timedomain.diagnosis.fit import JointModel
from benchmark.problems.timedomain.diagnosis.grid import grid_column

#: Fractions of the Gauss-Newton step whose models are evaluated (the best on the fitted fold kept).
STEP_FRACTIONS = (1.0, 0.5, 0.25)


def start_extras(eff: Effect, ctx: EffectContext) -> np.ndarray:
    """The point at which an effect is linearised: its first starting value."""
    return np.asarray(eff.extra_starts(ctx)[0], float)


def first_starts(model: JointModel, x_fit: np.ndarray, new: Sequence[Effect], ctx: EffectContext) -> list:
    """The default linearisation point of an addition: the current fit with the new effects'
    first starts (:func:`start_extras`)."""
    return [np.concatenate([np.asarray(x_fit, float)] + [start_extras(e, ctx) for e in new])]


def _grid_columns(model: JointModel, new_from: int, ctx: EffectContext) -> list[int]:
    """Indices of the new effects' grid parameters (:meth:`Effect.start_grid`: instants a local
    step cannot move well), held in the step."""
    return [grid_column(model, j, ctx) for j in range(new_from, len(model.effects))
            if model.effects[j].start_grid(ctx) is not None]


def _to_x(model: JointModel, U: np.ndarray) -> np.ndarray:
    lo, hi = model.lower, model.upper
    return lo + np.clip(U, 0.0, 1.0) * np.where(hi > lo, hi - lo, 1.0)


def _linearisation(model: JointModel, x0: np.ndarray):
    """(u0, steps h, points X (k+1, k): x0 then x0 with each normalised coordinate stepped)."""
    lo, hi = model.lower, model.upper
    u0 = np.clip((np.clip(x0, lo, hi) - lo) / np.where(hi > lo, hi - lo, 1.0), 0.0, 1.0)
    h = 1e-6 * np.maximum(np.abs(u0), 1e-3)
    h = np.where(u0 + h > 1.0, -h, h)
    return u0, h, _to_x(model, np.vstack([u0, u0[None, :] + np.diag(h)]))


def _step(J: np.ndarray, r0: np.ndarray, u0: np.ndarray, held: list[int], fit_mask: np.ndarray) -> np.ndarray:
    """The Gauss-Newton step (normalised coordinates) on ``fit_mask``, within the box, the
    ``held`` parameters not moved."""
    free = np.setdiff1d(np.arange(len(u0)), held)
    step = np.zeros(len(u0))
    sol = optimize.lsq_linear(J[fit_mask][:, free], -r0[fit_mask], bounds=(-u0[free], 1.0 - u0[free]), method="bvls")
    step[free] = sol.x
    return step


def score_tests(make_model: Callable[[list[Effect]], JointModel], chosen: Sequence[Effect], x_fit: np.ndarray,
                fit_mask: np.ndarray, held_mask: np.ndarray, additions: Sequence[tuple[Effect, ...]],
                ctx: EffectContext, starts: Callable | None = None) -> list[dict]:
    """Score tests of ``additions`` (tuples of effects) to the model ``make_model(chosen)``
    fitted at ``x_fit`` on ``fit_mask``, scored on ``held_mask`` (residual masks). Returns one
    row per addition, best first (lowest ``score``): ``effect`` (names joined by ``+``);
    ``predicted_heldout_chi2`` (the step's linear prediction) and ``heldout_chi2`` (the model's
    own held-out chi^2 per residual after the step, or after half or a quarter of it where that
    fits ``fit_mask`` better); ``score``, the lower of the two (each fails on its own: the linear
    prediction where an effect is far from linear at its start, a load step's size beside its
    instant; the step where it overshoots a curved valley, a probe's level and sharpness);
    ``drop`` (the reference's ``score`` less the addition's);
    ``heldout_chi2_at_start`` and ``step`` (the new effects' part, normalised coordinates);
    ``unseen``, the new effects' parameters that change nothing at the linearisation point (a
    load step's instant and shape where its torque starts at 0: a step sees the effect in one
    shape only, the start's, so a score no better than the current model's says nothing of the
    effect's other shapes);
    ``point``, the parameters at which ``heldout_chi2`` was evaluated, by name.

    ``starts(model, x_fit, new)``: the linearisation points of an addition (each is tried, the
    one that fits ``fit_mask`` best after its step kept), e.g. a selection's own starts with a
    start grid's instant set to its best value (``Selector.profiled``); by default
    :func:`first_starts`. A new effect's grid parameter is held in the step. The selection's pair
    screening (``Selector.screen_pairs``) reads ``predicted_heldout_chi2``."""
    todo = [()] + [tuple(a) for a in additions]
    plans = []
    for i, add in enumerate(todo):
        model = make_model(list(chosen) + list(add))
        points = starts(model, x_fit, list(add)) if starts and add else first_starts(model, x_fit, add, ctx)
        held = _grid_columns(model, len(chosen), ctx)
        for x0 in points:
            u0, h, X = _linearisation(model, x0)
            plans.append([i, add, model, u0, h, X, model.rows(X), held])
    lin = plans[0][2].data.kernel.simulate(np.vstack([p[6] for p in plans]))
    stepped, rows_out, k = [], [], 0
    for _, add, model, u0, h, X, rows, held in plans:
        R = model.residuals_of(model.outputs(X, rows, lin[k:k + len(X)]))
        k += len(X)
        r0, J = R[0], ((R[1:] - R[0][None, :]) / h[:, None]).T  # d r / d u, (n_residuals, k)
        step = _step(J, r0, u0, held, fit_mask)
        pred = r0[held_mask] + J[held_mask] @ step
        n_new = sum(len(e.extra_names) for e in add)
        new_cols = range(len(step) - n_new, len(step))
        rows_out.append({"effect": "+".join(e.name for e in add), "predicted_heldout_chi2": float(np.mean(pred**2)),
                         "heldout_chi2_at_start": float(np.mean(r0[held_mask] ** 2)),
                         "step": step[len(step) - n_new:].tolist(), "_start": r0,
                         "unseen": [model.names[j] for j in new_cols if not np.any(J[fit_mask, j])]})
        Xs = _to_x(model, u0[None, :] + np.array(STEP_FRACTIONS)[:, None] * step[None, :])
        stepped.append((model, Xs, model.rows(Xs)))
    after = plans[0][2].data.kernel.simulate(np.vstack([s[2] for s in stepped]))
    k = 0
    best_of: dict[int, dict] = {}
    for plan, row, (model, Xs, rows) in zip(plans, rows_out, stepped, strict=True):
        R = np.vstack([row.pop("_start")[None, :],
                       model.residuals_of(model.outputs(Xs, rows, after[k:k + len(Xs)]))])
        k += len(Xs)
        ssr = np.sum(R[:, fit_mask] ** 2, axis=1)
        best = int(np.argmin(ssr))
        row["point"] = dict(zip(model.names, map(float, plan[5][0] if best == 0 else Xs[best - 1]), strict=True))
        row["heldout_chi2"] = float(np.mean(R[best][held_mask] ** 2))
        row["step_fraction"] = ([0.0] + list(STEP_FRACTIONS))[best]
        row["score"] = min(row["heldout_chi2"], row["predicted_heldout_chi2"])
        row["_ssr"] = float(ssr[best])
        if plan[0] not in best_of or row["_ssr"] < best_of[plan[0]]["_ssr"]:  # an addition's best start
            best_of[plan[0]] = row
    out = [best_of[i] for i in range(len(todo))]
    for row in out:
        row.pop("_ssr")
        row["drop"] = out[0]["score"] - row["score"]
    return sorted(out[1:], key=lambda r: r["score"])
