"""Nuisance parameters: quantities of the record, not of the motor, that the fit must estimate
alongside the motor's parameters for those to come out unbiased.

A problem declares them with ``nuisance_names`` (and ``nuisance_units``, ``nuisance_bound``:
the half-width of the range searched, each centred on 0) and implements
``residuals_nuisance(X, eta)`` (residual vectors of the candidates ``X`` with the nuisance
values ``eta``) and ``set_nuisance(eta)`` (make ``eta`` the problem's own from then on: its
cost, residuals, fit quality and figures use it). The time-domain problem's nuisance is the
stator flux step that the volt-seconds of a measured switch-on leave uncertain (contactor
poles closing and bouncing between samples, see
:mod:`benchmark.problems.timedomain.switch_on`).

* :func:`refine_nuisance`: after the optimiser, a joint least-squares fit of the motor's
  parameters and the nuisance from the optimiser's point and nuisance 0
  (:func:`benchmark.core.polish.least_squares_batch`); kept when the problem's own cost falls.
  Its evaluations are reported beside the optimiser's and the polish's.
* :class:`JointView`: the problem seen over (parameters, nuisance), for the Jacobian of
  :func:`benchmark.core.quality.parameter_uncertainty`: the standard errors of the motor's
  parameters are those with the nuisance estimated too (marginalised), not those with it
  held at its estimate.

A problem without ``nuisance_names`` is left alone (bit-identical results).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.core.polish import least_squares_batch

#: Evaluations (residual vectors) the joint refinement may spend.
REFINE_EVALUATIONS = 600


def has_nuisance(problem) -> bool:
    """True when the problem declares nuisance parameters."""
    return bool(getattr(problem, "nuisance_names", ()))


class JointView:
    """The problem over ``z = (x, eta)``: bounds, ``residuals_batch(Z)`` (rows that share a
    nuisance value are simulated in one batch). Uncounted: for the refinement and the
    Jacobian only."""

    def __init__(self, problem):
        self.problem = problem
        self.k = len(problem.parameter_names)
        self.parameter_names = tuple(problem.parameter_names) + tuple(problem.nuisance_names)
        b = np.asarray(problem.nuisance_bound, float)
        self.lower = np.concatenate([np.asarray(problem.lower, float), -b])
        self.upper = np.concatenate([np.asarray(problem.upper, float), b])

    def residuals_batch(self, Z: np.ndarray) -> np.ndarray:
        Z = np.atleast_2d(np.asarray(Z, float))
        X, E = Z[:, :self.k], Z[:, self.k:]
        out = None
        for eta in np.unique(E, axis=0):
            rows = np.flatnonzero(np.all(E == eta[None, :], axis=1))
            R = np.asarray(self.problem.residuals_nuisance(X[rows], eta), float)
            if out is None:
                out = np.empty((len(Z), R.shape[1]))
            out[rows] = R
        return out


@dataclass(frozen=True)
class NuisanceRefinement:
    """What :func:`refine_nuisance` did: the point ``x`` and ``cost`` kept, the nuisance values
    (``values``, in ``units``), the cost before, the evaluations spent and whether the joint
    fit was kept (``accepted``)."""

    x: np.ndarray
    cost: float
    values: dict
    units: dict
    cost_before: float
    evaluations: int
    accepted: bool
    message: str

    def record(self) -> dict:
        """The result record's ``nuisance`` entry."""
        return {"names": list(self.values), "values": dict(self.values), "units": dict(self.units),
                "cost_before": float(self.cost_before), "cost_after": float(self.cost),
                "evaluations": int(self.evaluations), "accepted": bool(self.accepted), "message": self.message}


def refine_nuisance(problem, x, cost: float) -> NuisanceRefinement | None:
    """Joint least squares of the parameters and the problem's nuisance from ``(x, 0)``.

    Kept (and the nuisance set on the problem) when the problem's own cost of the joint fit is
    below ``cost``, the cost at ``x`` with nuisance 0; else the problem is left at nuisance 0.
    None when the problem has no nuisance, or there is no finite point to start from."""
    if x is None or cost is None or not np.isfinite(cost) or not has_nuisance(problem):
        return None
    view = JointView(problem)
    count = [0]

    def counted(Z):
        count[0] += len(np.atleast_2d(Z))
        return view.residuals_batch(Z)

    z0 = np.concatenate([np.asarray(x, float), np.zeros(len(problem.nuisance_names))])
    with np.errstate(all="ignore"):
        z, message = least_squares_batch(counted, z0, view.lower, view.upper, REFINE_EVALUATIONS)
        r = view.residuals_batch(z[None, :])[0]
    new_cost = problem.cost_from_residuals(r) if np.all(np.isfinite(r)) else np.inf
    units = dict(zip(problem.nuisance_names, problem.nuisance_units, strict=True))
    accepted = bool(new_cost < cost)
    eta = z[view.k:] if accepted else np.zeros(len(problem.nuisance_names))
    problem.set_nuisance(eta)
    values = {n: float(v) for n, v in zip(problem.nuisance_names, eta, strict=True)}
    return NuisanceRefinement(x=(z[:view.k] if accepted else np.asarray(x, float)),
                              cost=float(new_cost if accepted else cost), values=values, units=units,
                              cost_before=float(cost), evaluations=count[0] + 1, accepted=accepted,
                              message=str(message))
