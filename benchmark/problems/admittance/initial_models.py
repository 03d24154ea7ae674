"""Lindsay and Barton's initial models from the data alone (no cost evaluation), behind the
problem's ``initial_guess`` hook (:mod:`plugins.lindsay_barton`):

* ``A``: a crude reading of the admittance at synchronous speed (``Z1 + Z0``) and at standstill
  (``Z1 + Z2``, magnetising branch neglected), split equally between stator and rotor; second-order
  terms set arbitrarily (``R2sigma = 0.05 R2``, ``X3 = 0.02 X2``).
* ``E``: the Sanathanan-Koerner regression of the bilinear form (8-parameter: in the warped slip,
  with an outer search over ``R2sigma/R2``, ``X3/R2``), mapped back to the circuit with ``X1``,
  ``X2`` free when that gives a circuit inside the bounds, else with the tie ``X1 = X2``; with
  temperature compensation the data are then referred to the reference temperature with that
  circuit and the regression repeated until the circuit stops changing (at most 10 passes).

The bilinear form holds at one frequency: readings at another (a locked-rotor test at reduced
frequency) are left out of the regression, and reading A's standstill is taken at rated frequency.
"""

from __future__ import annotations

import numpy as np

from benchmark.problems.admittance.circuit import input_admittance
from benchmark.problems.admittance.regression import bilinear_regression

__all__ = ["admittance_at", "model_a", "model_e"]


def _rated(problem) -> np.ndarray:
    """Readings at rated frequency (all of them for a sweep)."""
    k = problem.data.frequency_ratio
    return np.ones(len(problem._s), bool) if k is None else np.abs(np.asarray(k) - 1.0) < 1e-9


def admittance_at(problem, s0: float) -> complex:
    """The measured admittance at slip ``s0`` (mean of readings there, else interpolated; rated frequency)."""
    m = _rated(problem)
    s, Y = problem._s[m], problem._Ym[m]
    order = np.argsort(s, kind="stable")
    s_sorted, Y_sorted = s[order], Y[order]
    near = np.abs(s_sorted - s0) < 1e-9
    if near.any():
        return complex(Y_sorted[near].mean())
    return complex(np.interp(s0, s_sorted, Y_sorted.real) + 1j * np.interp(s0, s_sorted, Y_sorted.imag))


def model_a(problem) -> dict[str, float]:
    Z_nl = 1.0 / admittance_at(problem, 0.0)
    Z_sc = 1.0 / admittance_at(problem, 1.0)
    R = Z_sc.real / 2
    X = Z_sc.imag / 2
    return {
        "R1_total": R,
        "X1": X,
        "R2": R,
        "X2": X,
        "R0": Z_nl.real - R,
        "X0": Z_nl.imag - X,
        "R2sigma": 0.05 * R,
        "X3": 0.02 * X,
    }


def _pick_mapping(problem, reg: dict) -> dict:
    """The free mapping when it is physical and inside the bounds (and X1, X2 are not tied),
    else the tied one."""
    free = reg["free"]
    if not problem.tie_x1_x2:
        x = np.array([free[n] for n in problem.parameter_names])
        if np.all(np.isfinite(x)) and np.all(x >= problem.lower) and np.all(x <= problem.upper):
            return free | {"mapping": "free"}
    return reg["tied"] | {"mapping": "tied (X1 = X2)"}


def model_e(problem) -> dict[str, float]:
    m = _rated(problem)
    s, w = problem._s[m], problem._w[m]
    Y = problem._Ym[m]
    warp0 = (0.05, 0.02)
    x_prev = None
    out: dict = {}
    for _ in range(10 if problem.compensated else 1):
        reg = bilinear_regression(s, Y, w, model=problem.model, warp0=warp0)
        out = _pick_mapping(problem, reg)
        warp0 = (reg["rho"], reg["xi"])
        if not problem.compensated:
            break
        # refer the data to the reference temperature with this circuit, and fit again until the
        # circuit stops changing (a fixed point: the data corrected by the fitted circuit's own
        # temperature effect are fitted by that circuit)
        x = np.array([out[n] for n in problem.parameter_names])
        if x_prev is not None and np.all(np.abs(x - x_prev) <= 1e-10 * np.maximum(np.abs(x), 1e-12)):
            break
        x_prev = x
        c = problem.full_parameters(x)
        Y_ref = input_admittance(
            problem._s, c["R1_total"], c["X1"], c["R2"], c["X2"], c["R0"], c["X0"], c["R2sigma"], c["X3"]
        )[0]
        Y = (problem._Ym + (Y_ref - problem.admittance(x)[0]))[m]
    problem.last_mapping = out["mapping"]
    return out
