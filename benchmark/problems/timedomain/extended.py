"""The extended induction-motor model: the base model plus the unmodelled effects.

It is the physics behind both the synthetic plant that makes "real" data with an effect and
the augmented identification models of the sim-to-real diagnosis (MODEL.md section 6). With
every effect term at its neutral value it is the base model of :mod:`benchmark.problems.timedomain.motor`
written in the inverse-Gamma form (``L_sigma = Le``, ``L_M = Ls - Le``,
``R_R = Rr (Ls - Le)/Ls``), so the two agree to rounding (tested).

States (stator frame, amplitude-invariant, SI): stator flux ``psi_s`` (2), magnetising flux
``psi_M`` (2), flux of the second rotor branch ``psi_2`` (2), electrical speed ``w``, winding
temperature rise ``theta`` (K).

Branches on the magnetising node (KCL ``i_M(psi_M) = i_s + i_1 + i_2 + i_fe``):

* stator: ``d psi_s/dt = v - v_drop(i_s) - Rs(theta) i_s``,
  ``i_s = (psi_s - psi_M)/L_sigma * (1 + ls_k (|psi_s - psi_M|/ls_psi)^ls_exp)`` (leakage saturation);
* magnetising: ``i_M = psi_M/L_M * (1 + ms_k (|psi_M|/ms_psi)^ms_exp)`` (main saturation);
* rotor cage 1 (no leakage): ``0 = R_r1 i_1 + e - j w psi_M`` with ``e = d psi_M/dt``;
* rotor cage 2 (double cage / deep bar): ``d psi_2/dt = -R_r2 i_2 + j w psi_2``,
  ``i_2 = (psi_2 - psi_M)/L_sigma2`` (absent when ``R_r2 = 0``);
* iron: a stationary loss conductance ``g_fe`` on the node: ``i_fe = -g_fe e``.

So ``e = (i_s + i_2 + j w psi_M/R_r1 - i_M)/(1/R_r1 + g_fe)``. Torque
``T = 1.5 p (psi_s x i_s)``; mechanics as in the base model (viscous ``fv``, Coulomb ``fc``
with stiction). Resistances follow the copper law ``R (1 + alpha theta)``, with the
temperature rise driven by the copper losses: ``d theta/dt = h_th * P_cu`` (``h_th`` = 1/heat
capacity, K/J). Inverter drop: each phase loses ``U_d tanh(i_x/i_0)`` (``i_0 = 0``: a hard
sign), transformed to alpha-beta.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from benchmark.core.constants import COPPER_INFERRED_ZERO_C
from benchmark.problems.timedomain.motor import InductionMotor

#: Fields of an extended parameter row, in order. Neutral values make the base model.
EXTENDED_FIELDS = (
    "Rs",  # ohm, stator resistance
    "L_sigma",  # H, leakage inductance (= Le)
    "L_M",  # H, magnetising inductance of the inverse-Gamma model (= Ls - Le)
    "R_r1",  # ohm, rotor cage 1 (inverse-Gamma referred)
    "R_r2",  # ohm, rotor cage 2; 0 = absent
    "L_sigma2",  # H, leakage of cage 2
    "g_fe",  # S, iron-loss conductance on the magnetising node; 0 = none
    "ms_k",  # -, main saturation: extra magnetising current at ms_psi (fraction)
    "ms_psi",  # Wb, main saturation reference flux
    "ms_exp",  # -, main saturation exponent
    "ls_k",  # -, leakage saturation: extra stator current at ls_psi (fraction)
    "ls_psi",  # Wb, leakage saturation reference flux linkage
    "ls_exp",  # -, leakage saturation exponent
    "U_d",  # V, inverter voltage drop per phase
    "i_0",  # A, current scale of the drop's sign change (0: hard sign)
    "h_th",  # K/J, temperature rise per joule of copper loss; 0 = constant temperature
    "alpha_th",  # 1/K, copper temperature coefficient 1/(234.5 + theta_ref)
    "J",  # kg m^2
    "fv",  # N m s
    "fc",  # N m
    "p",  # pole pairs
)
N_EXT = len(EXTENDED_FIELDS)
IDX = {name: k for k, name in enumerate(EXTENDED_FIELDS)}
N_STATES = 8
SQRT3_2 = math.sqrt(3.0) / 2.0


def base_row(motor: InductionMotor | dict) -> np.ndarray:
    """Extended parameter row of a base-model parameter set (every effect neutral)."""
    m = motor if isinstance(motor, dict) else motor.as_dict()
    row = np.zeros(N_EXT)
    Ls, Le = m["Ls"], m["Le"]
    row[IDX["Rs"]] = m["Rs"]
    row[IDX["L_sigma"]] = Le
    row[IDX["L_M"]] = Ls - Le
    row[IDX["R_r1"]] = m["Rr"] * (Ls - Le) / Ls
    row[IDX["ms_psi"]] = 1.0
    row[IDX["ms_exp"]] = 2.0
    row[IDX["ls_psi"]] = 1.0
    row[IDX["ls_exp"]] = 2.0
    row[IDX["alpha_th"]] = 1.0 / (COPPER_INFERRED_ZERO_C + 20.0)
    row[IDX["J"]] = m["J"]
    row[IDX["fv"]] = m["fv"]
    row[IDX["fc"]] = m["fc"]
    row[IDX["p"]] = m.get("p", 1)
    return row


def base_rows(theta: np.ndarray, p: int) -> np.ndarray:
    """Vectorised :func:`base_row` for physical parameter rows (n, 7) in PARAMETER_NAMES order."""
    theta = np.atleast_2d(theta)
    Rs, Ls, Le, Rr, J, fv, fc = theta.T
    rows = np.zeros((len(theta), N_EXT))
    rows[:, IDX["Rs"]] = Rs
    rows[:, IDX["L_sigma"]] = Le
    rows[:, IDX["L_M"]] = Ls - Le
    with np.errstate(all="ignore"):
        rows[:, IDX["R_r1"]] = Rr * (Ls - Le) / Ls
    rows[:, IDX["ms_psi"]] = 1.0
    rows[:, IDX["ms_exp"]] = 2.0
    rows[:, IDX["ls_psi"]] = 1.0
    rows[:, IDX["ls_exp"]] = 2.0
    rows[:, IDX["alpha_th"]] = 1.0 / (COPPER_INFERRED_ZERO_C + 20.0)
    rows[:, IDX["J"]] = J
    rows[:, IDX["fv"]] = fv
    rows[:, IDX["fc"]] = fc
    rows[:, IDX["p"]] = p
    bad = ~((Le > 0) & (Ls > Le) & (Rs > 0) & (Rr > 0) & (J > 0) & (fv >= 0) & (fc >= 0))
    rows[bad] = np.nan
    return rows


def valid_rows(rows: np.ndarray) -> np.ndarray:
    """Mask of physically valid extended rows."""
    r = rows
    ok = np.all(np.isfinite(r), axis=1)
    for name in ("Rs", "L_sigma", "L_M", "R_r1", "J", "ms_psi", "ls_psi"):
        ok &= r[:, IDX[name]] > 0
    for name in ("R_r2", "g_fe", "ms_k", "ls_k", "U_d", "i_0", "h_th", "fv", "fc"):
        ok &= r[:, IDX[name]] >= 0
    ok &= (r[:, IDX["R_r2"]] == 0) | (r[:, IDX["L_sigma2"]] > 0)
    return ok


@numba.njit(cache=True, inline="always")
def _sat(x, k, ref, ex):
    if k == 0.0:
        return 1.0
    return 1.0 + k * (x / ref) ** ex


@numba.njit(cache=True, inline="always")
def _drop_sign(i, i0):
    if i0 > 0.0:
        return math.tanh(i / i0)
    if i > 0.0:
        return 1.0
    if i < 0.0:
        return -1.0
    return 0.0


@numba.njit(cache=True)
def _derivative(c, x, v_a, v_b, direction, out):
    Rs, Ls_, LM, R_r1, R_r2, Ls2 = c[0], c[1], c[2], c[3], c[4], c[5]
    gfe, ms_k, ms_psi, ms_exp, ls_k, ls_psi, ls_exp = c[6], c[7], c[8], c[9], c[10], c[11], c[12]
    Ud, i0, h_th, alpha, J, fv, fc, p = c[13], c[14], c[15], c[16], c[17], c[18], c[19], c[20]
    ps_a, ps_b, pm_a, pm_b, p2_a, p2_b, w, th = x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]
    heat = 1.0 + alpha * th
    Rs_t = Rs * heat
    R_r1_t = R_r1 * heat
    R_r2_t = R_r2 * heat
    d_a = ps_a - pm_a
    d_b = ps_b - pm_b
    g = _sat(math.sqrt(d_a * d_a + d_b * d_b), ls_k, ls_psi, ls_exp) / Ls_
    is_a = d_a * g
    is_b = d_b * g
    if R_r2 > 0.0:
        i2_a = (p2_a - pm_a) / Ls2
        i2_b = (p2_b - pm_b) / Ls2
    else:
        i2_a = 0.0
        i2_b = 0.0
    gm = _sat(math.sqrt(pm_a * pm_a + pm_b * pm_b), ms_k, ms_psi, ms_exp) / LM
    im_a = pm_a * gm
    im_b = pm_b * gm
    inv_g = 1.0 / (1.0 / R_r1_t + gfe)
    e_a = (is_a + i2_a - w * pm_b / R_r1_t - im_a) * inv_g
    e_b = (is_b + i2_b + w * pm_a / R_r1_t - im_b) * inv_g
    # inverter drop: per phase, then amplitude-invariant Clarke
    if Ud > 0.0:
        i_r = is_a
        i_s = -0.5 * is_a + SQRT3_2 * is_b
        i_t = -0.5 * is_a - SQRT3_2 * is_b
        s_r = _drop_sign(i_r, i0)
        s_s = _drop_sign(i_s, i0)
        s_t = _drop_sign(i_t, i0)
        v_a = v_a - Ud * (2.0 / 3.0) * (s_r - 0.5 * (s_s + s_t))
        v_b = v_b - Ud * (s_s - s_t) / (2.0 * SQRT3_2)
    out[0] = v_a - Rs_t * is_a
    out[1] = v_b - Rs_t * is_b
    out[2] = e_a
    out[3] = e_b
    if R_r2 > 0.0:
        out[4] = -R_r2_t * i2_a - w * p2_b
        out[5] = -R_r2_t * i2_b + w * p2_a
    else:
        out[4] = 0.0
        out[5] = 0.0
    t_m = 1.5 * p * (ps_a * is_b - ps_b * is_a)
    if direction != 0.0:
        out[6] = -w * fv / J + p / J * (t_m - fc * direction)
    elif t_m > fc:
        out[6] = -w * fv / J + p / J * (t_m - fc)
    elif t_m < -fc:
        out[6] = -w * fv / J + p / J * (t_m + fc)
    else:
        out[6] = 0.0
    if h_th > 0.0:
        i1_a = (-w * pm_b - e_a) / R_r1_t
        i1_b = (w * pm_a - e_b) / R_r1_t
        p_cu = 1.5 * (Rs_t * (is_a * is_a + is_b * is_b) + R_r1_t * (i1_a * i1_a + i1_b * i1_b)
                      + R_r2_t * (i2_a * i2_a + i2_b * i2_b))
        out[7] = h_th * p_cu
    else:
        out[7] = 0.0
    return t_m


@numba.njit(cache=True)
def _stator_current(c, x):
    d_a = x[0] - x[2]
    d_b = x[1] - x[3]
    g = _sat(math.sqrt(d_a * d_a + d_b * d_b), c[10], c[11], c[12]) / c[1]
    return d_a * g, d_b * g


@numba.njit(cache=True)
def _simulate_one(c, v_a, v_b, linear, h, substeps, x0, out):
    """Outputs (3, N): i_alpha, i_beta (A), mechanical speed (rad/s); final state in x0."""
    n = v_a.shape[0]
    x = x0.copy()
    k1 = np.empty(N_STATES)
    k2 = np.empty(N_STATES)
    k3 = np.empty(N_STATES)
    k4 = np.empty(N_STATES)
    xt = np.empty(N_STATES)
    hs = h / substeps
    p = c[20]
    fc = c[19]
    for k in range(n):
        ia, ib = _stator_current(c, x)
        out[0, k] = ia
        out[1, k] = ib
        out[2, k] = x[6] / p
        if k == n - 1:
            break
        va0, vb0 = v_a[k], v_b[k]
        dva = v_a[k + 1] - va0 if linear else 0.0
        dvb = v_b[k + 1] - vb0 if linear else 0.0
        for j in range(substeps):
            f0 = j / substeps
            fm = (j + 0.5) / substeps
            f1 = (j + 1.0) / substeps
            w0 = x[6]
            d = 1.0 if w0 > 0.0 else (-1.0 if w0 < 0.0 else 0.0)
            _derivative(c, x, va0 + f0 * dva, vb0 + f0 * dvb, d, k1)
            for s in range(N_STATES):
                xt[s] = x[s] + 0.5 * hs * k1[s]
            _derivative(c, xt, va0 + fm * dva, vb0 + fm * dvb, d, k2)
            for s in range(N_STATES):
                xt[s] = x[s] + 0.5 * hs * k2[s]
            _derivative(c, xt, va0 + fm * dva, vb0 + fm * dvb, d, k3)
            for s in range(N_STATES):
                xt[s] = x[s] + hs * k3[s]
            _derivative(c, xt, va0 + f1 * dva, vb0 + f1 * dvb, d, k4)
            for s in range(N_STATES):
                x[s] = x[s] + hs / 6.0 * (k1[s] + 2.0 * (k2[s] + k3[s]) + k4[s])
            if fc > 0.0 and w0 != 0.0 and x[6] * w0 <= 0.0:
                ia2, ib2 = _stator_current(c, x)
                t_m = 1.5 * p * (x[0] * ib2 - x[1] * ia2)
                if abs(t_m) <= fc:
                    x[6] = 0.0
        m = 0.0
        for s in range(N_STATES):
            m = max(m, abs(x[s]))
        if not m < 1e9:
            for kk in range(k + 1, n):
                out[0, kk] = np.nan
                out[1, kk] = np.nan
                out[2, kk] = np.nan
            break
    for s in range(N_STATES):
        x0[s] = x[s]


@numba.njit(cache=True, parallel=True)
def simulate_extended_batch(rows, v_a, v_b, linear, h, substeps):
    """Outputs of a population of extended rows from rest: (n_pop, 3, N) i_alpha, i_beta (A),
    mechanical speed (rad/s); NaN from where a candidate diverges (or for invalid rows)."""
    n_pop = rows.shape[0]
    n = v_a.shape[0]
    out = np.full((n_pop, 3, n), np.nan)
    for m in numba.prange(n_pop):
        c = rows[m]
        if not np.isfinite(c[0]):
            continue
        x0 = np.zeros(N_STATES)
        _simulate_one(c, v_a, v_b, linear, h, substeps, x0, out[m])
    return out


@numba.njit(cache=True)
def simulate_extended(row, v_a, v_b, linear, h, substeps, x0):
    """One trajectory from state ``x0`` (modified in place to the final state): (3, N)."""
    out = np.empty((3, v_a.shape[0]))
    _simulate_one(row, v_a, v_b, linear, h, substeps, x0, out)
    return out
