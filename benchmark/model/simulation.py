"""Compiled simulation of the induction-motor model: classical RK4 at the sample time.

The stepper integrates :func:`benchmark.model.motor.state_derivative`. The input voltage is
given at the sample instants; between samples it is either held (``zoh``, switch-state
voltages: the same voltage at all four RK4 stages) or interpolated linearly (``linear``,
sampled continuous voltages: stage voltages at ``t_k``, the midpoint and ``t_(k+1)``).

Populations are evaluated in one call, in parallel over candidates, with no allocation per
step. A candidate whose states become non-finite or absurdly large costs ``+inf``.
"""

from __future__ import annotations

import numba
import numpy as np

from benchmark.model.motor import state_derivative

#: Any state beyond this magnitude counts as a diverged simulation.
DIVERGENCE_LIMIT = 1e9

HOLDS = ("zoh", "linear")


@numba.njit(cache=True, inline="always")
def _rk4(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, vam, vbm, va1, vb1, h):
    d = 1.0 if w > 0.0 else (-1.0 if w < 0.0 else 0.0)
    k1 = state_derivative(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, d)
    hh = 0.5 * h
    k2 = state_derivative(
        c, i_a + hh * k1[0], i_b + hh * k1[1], psi_a + hh * k1[2], psi_b + hh * k1[3], w + hh * k1[4], vam, vbm, d
    )
    k3 = state_derivative(
        c, i_a + hh * k2[0], i_b + hh * k2[1], psi_a + hh * k2[2], psi_b + hh * k2[3], w + hh * k2[4], vam, vbm, d
    )
    k4 = state_derivative(
        c, i_a + h * k3[0], i_b + h * k3[1], psi_a + h * k3[2], psi_b + h * k3[3], w + h * k3[4], va1, vb1, d
    )
    h6 = h / 6.0
    n_ia = i_a + h6 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0])
    n_ib = i_b + h6 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1])
    n_pa = psi_a + h6 * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2])
    n_pb = psi_b + h6 * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3])
    n_w = w + h6 * (k1[4] + 2.0 * (k2[4] + k3[4]) + k4[4])
    # Coulomb friction cannot reverse the rotor: a sign change it would cause is a stop.
    fc = c[9]
    if fc > 0.0 and w != 0.0 and n_w * w <= 0.0:
        t_m = c[6] * (n_pa * n_ib - n_pb * n_ia)
        if abs(t_m) <= fc:
            n_w = 0.0
    return n_ia, n_ib, n_pa, n_pb, n_w


@numba.njit(cache=True, inline="always")
def _stage_voltages(v_a, v_b, k, linear):
    va0, vb0 = v_a[k], v_b[k]
    if linear:
        va1, vb1 = v_a[k + 1], v_b[k + 1]
        return va0, vb0, 0.5 * (va0 + va1), 0.5 * (vb0 + vb1), va1, vb1
    return va0, vb0, va0, vb0, va0, vb0


@numba.njit(cache=True, inline="always")
def _diverged(i_a, i_b, psi_a, psi_b, w):
    m = max(abs(i_a), abs(i_b), abs(psi_a), abs(psi_b), abs(w))
    return not (m < DIVERGENCE_LIMIT)  # also true for NaN


@numba.njit(cache=True, parallel=True)
def startup_cost_batch(coef, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas, p, weights, exponent):
    """Eqs. 13-15 for a population: ``sum_j ka e(i_a) + kb e(i_b) + kw e(w_M)``.

    ``coef``: (n_pop, N_COEF) coefficient rows (NaN rows are invalid candidates).
    ``v_a, v_b``: stator voltages at the N sample instants, V. ``h``: sample time, s.
    ``*_meas``: measured currents (A) and mechanical speed (rad/s) at the same instants.
    ``weights``: (ka, kb, kw). ``exponent``: 2 (eq. 14, squares) or 1 (eq. 15, absolute).
    The simulation starts from rest with zero flux at the first sample. Returns (n_pop,).
    """
    n_pop = coef.shape[0]
    n = v_a.shape[0]
    ka, kb, kw = weights[0], weights[1], weights[2]
    inv_p = 1.0 / p
    out = np.empty(n_pop)
    for m in numba.prange(n_pop):
        c = coef[m]
        if not np.isfinite(c[0]):
            out[m] = np.inf
            continue
        i_a = 0.0
        i_b = 0.0
        psi_a = 0.0
        psi_b = 0.0
        w = 0.0
        total = 0.0
        for k in range(n):
            ea = i_a_meas[k] - i_a
            eb = i_b_meas[k] - i_b
            ew = speed_meas[k] - w * inv_p
            if exponent == 2:
                total += ka * ea * ea + kb * eb * eb + kw * ew * ew
            else:
                total += ka * abs(ea) + kb * abs(eb) + kw * abs(ew)
            if k == n - 1:
                break
            va0, vb0, vam, vbm, va1, vb1 = _stage_voltages(v_a, v_b, k, linear)
            i_a, i_b, psi_a, psi_b, w = _rk4(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, vam, vbm, va1, vb1, h)
            if _diverged(i_a, i_b, psi_a, psi_b, w):
                total = np.inf
                break
        out[m] = total if np.isfinite(total) else np.inf
    return out


@numba.njit(cache=True, parallel=True)
def startup_outputs_batch(coef, v_a, v_b, linear, h, p):
    """Simulated outputs for a population: (n_pop, 3, N) = i_a (A), i_b (A), mechanical speed
    (rad/s) at the N sample instants, from rest. Diverged candidates are NaN from the sample
    where they diverge."""
    n_pop = coef.shape[0]
    n = v_a.shape[0]
    out = np.full((n_pop, 3, n), np.nan)
    inv_p = 1.0 / p
    for m in numba.prange(n_pop):
        c = coef[m]
        if not np.isfinite(c[0]):
            continue
        i_a = 0.0
        i_b = 0.0
        psi_a = 0.0
        psi_b = 0.0
        w = 0.0
        for k in range(n):
            out[m, 0, k] = i_a
            out[m, 1, k] = i_b
            out[m, 2, k] = w * inv_p
            if k == n - 1:
                break
            va0, vb0, vam, vbm, va1, vb1 = _stage_voltages(v_a, v_b, k, linear)
            i_a, i_b, psi_a, psi_b, w = _rk4(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, vam, vbm, va1, vb1, h)
            if _diverged(i_a, i_b, psi_a, psi_b, w):
                break
    return out


@numba.njit(cache=True)
def simulate_states(c, v_a, v_b, linear, h, substeps, x0):
    """One trajectory with ``substeps`` RK4 steps per sample (the reference plant).

    Returns the five states (i_a, i_b, psi_a, psi_b, w electrical) at the N sample instants,
    shape (N, 5), starting from ``x0``. Between samples the input is held or interpolated
    linearly as for the identification model, so ``substeps = 1`` is that model exactly.
    """
    n = v_a.shape[0]
    out = np.empty((n, 5))
    i_a, i_b, psi_a, psi_b, w = x0[0], x0[1], x0[2], x0[3], x0[4]
    hs = h / substeps
    for k in range(n):
        out[k, 0] = i_a
        out[k, 1] = i_b
        out[k, 2] = psi_a
        out[k, 3] = psi_b
        out[k, 4] = w
        if k == n - 1:
            break
        va0, vb0 = v_a[k], v_b[k]
        dva = v_a[k + 1] - va0 if linear else 0.0
        dvb = v_b[k + 1] - vb0 if linear else 0.0
        for j in range(substeps):
            f0 = j / substeps
            fm = (j + 0.5) / substeps
            f1 = (j + 1.0) / substeps
            i_a, i_b, psi_a, psi_b, w = _rk4(
                c, i_a, i_b, psi_a, psi_b, w,
                va0 + f0 * dva, vb0 + f0 * dvb,
                va0 + fm * dva, vb0 + fm * dvb,
                va0 + f1 * dva, vb0 + f1 * dvb,
                hs,
            )
    return out


def hold_is_linear(input_hold: str) -> bool:
    if input_hold not in HOLDS:
        raise ValueError(f"input_hold must be one of {HOLDS}, got {input_hold!r}")
    return input_hold == "linear"
