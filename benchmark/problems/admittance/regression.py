"""Lindsay and Barton's "quadratic curve fit": the modified Morris model's coefficients from a
linear (bilinear, Sanathanan-Koerner iterated) regression of the admittance on slip, mapped
back to the physical circuit (their initial model E)."""

from __future__ import annotations

import numpy as np
from scipy import optimize

from benchmark.problems.admittance.circuit import (
    bilinear_to_circuit,
    warped_slip,
)
from benchmark.problems.admittance.thermal import TemperatureProfile, _piecewise_inputs, estimate_temperatures  # noqa: F401

# ----------------------------------------------------------------------------- regression


def _sk_fit(s_w, Y, weight, iterations=6):
    """Sanathanan-Koerner fit of ``Y = (a + b s')/(1 + c s')``: ``a + b s' - c s'Y = Y`` by complex
    least squares, each row re-weighted by ``1/|1 + c_prev s'|``."""
    M = np.stack([np.ones_like(s_w), s_w, -s_w * Y], axis=1)
    c = 0.0
    coef = None
    for _ in range(iterations):
        w = weight / np.abs(1.0 + c * s_w)
        coef, *_ = np.linalg.lstsq(M * w[:, None], Y * w, rcond=None)
        converged = abs(coef[2] - c) <= 1e-14 * (1 + abs(coef[2]))
        c = coef[2]
        if converged:
            break
    return coef


def bilinear_regression(s, Y, weight=None, model: int = 6, warp0=(0.05, 0.02)) -> dict:
    """The "E" route: Sanathanan-Koerner regression of the bilinear form, mapped back to the circuit.

    For ``model=8`` the warp ratios ``rho = R2sigma/R2`` and ``xi = X3/R2`` are found by an outer
    least-squares search around the linear fit (variable projection). Returns
    ``{"free": circuit, "tied": circuit, "rho", "xi", "rms"}``: the circuit (keys ``R1_total, X1, R2,
    X2, R0, X0, R2sigma, X3``) from the exact mapping with ``X1``, ``X2`` free (it reproduces the fitted
    curve, but leans on the small ``R0`` and is ill-conditioned with noise; it may be non-physical)
    and from the mapping with the usual tie ``X1 = X2``; ``rms`` is the weighted RMS output error of the
    fitted curve (per component)."""
    s = np.asarray(s, float)
    Y = np.asarray(Y, complex)
    weight = np.ones_like(s) if weight is None else np.asarray(weight, float)

    def fit(rho, xi):
        sw = warped_slip(s, 1.0, rho, xi)
        a, b, c = _sk_fit(sw, Y, weight)
        return (a, b, c), weight * (Y - (a + b * sw) / (1.0 + c * sw))

    def resid(z):
        _, e = fit(z[0], z[1])
        return np.concatenate([e.real, e.imag])

    rho = xi = 0.0
    if model == 8:
        sol = optimize.least_squares(
            resid, np.asarray(warp0, float), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000
        )
        rho, xi = float(sol.x[0]), float(sol.x[1])
    (a, b, c), e = fit(rho, xi)
    out = {"rho": rho, "xi": xi, "rms": float(np.sqrt(np.mean(np.abs(e) ** 2) / 2))}
    for key, tie in (("free", False), ("tied", True)):
        circ = bilinear_to_circuit(a, b, c, tie_x1_x2=tie)
        R2 = circ["R2"]
        out[key] = {
            "R1_total": circ["R1t"],
            "X1": circ["X1"],
            "R2": R2,
            "X2": circ["X2"],
            "R0": circ["R0"],
            "X0": circ["X0"],
            "R2sigma": rho * R2,
            "X3": xi * R2,
        }
    return out
