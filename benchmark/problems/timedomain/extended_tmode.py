"""The T mode of the extended model (:mod:`benchmark.problems.timedomain.extended`): a saturating
magnetising branch at the node of a T circuit.

With ``t_split > 0`` and a bending magnetising curve (and no saturating leakage) the currents
split at the T circuit's node, whose flux magnitude ``m`` solves the node's current balance
``m (1/Lls + 1/Llr + s(m)/Lm) = |psi_s/Lls + psi_r/Llr|`` (``s`` the curve's factor, at least 1)
at every evaluation of the derivative, by Newton's method. The circuit's constants are computed
once per trajectory (:func:`_t_constants`). The plant
(:func:`~benchmark.problems.timedomain.extended.simulate_extended`) solves from the unsaturated
solution, an upper bound; the identification model's batch kernel starts from the trajectory's
last root scaled with the balance's right side, with one power per curve term
(:func:`_t_node_flux_warm`): about half the time, the same root to the last digits (its
trajectories agree with the plant's to about 1e-11).
"""

from __future__ import annotations

import math

import numba


@numba.njit(cache=True, _nrt=False, inline="always")
def _t_mode(c):
    """The row's magnetising branch saturates at a T circuit's node: a split is set, the
    magnetising curve bends, and the leakage does not saturate (see the module docstring)."""
    return c[36] > 0.0 and (c[7] != 0.0 or c[23] != 0.0) and c[10] == 0.0


@numba.njit(cache=True, _nrt=False)
def _t_constants(c, tm, warm):
    """The T circuit of a T-mode row into ``tm``: ``Lm, Lls, Llr`` (H), the referral ``g0``,
    ``c0 = 1/Lls + 1/Llr`` and ``c0 + 1/Lm`` (1/H); ``tm[6]`` 1 when the node's flux may start
    from the previous solution (``warm``), ``tm[7]`` that solution (Wb, 0: none yet) and
    ``tm[8]`` the magnitude of its balance's right side (A)."""
    L_sig, LM, k = c[1], c[2], c[36]
    Ls_tot = L_sig + LM
    a = (1.0 - k) * LM
    Lm = 0.5 * (a + math.sqrt(a * a + 4.0 * k * Ls_tot * LM))
    Lls = Ls_tot - Lm
    Llr = k * Lls
    tm[0] = Lm
    tm[1] = Lls
    tm[2] = Llr
    tm[3] = Lm / (Lm + Llr)
    tm[4] = 1.0 / Lls + 1.0 / Llr
    tm[5] = tm[4] + 1.0 / Lm
    tm[6] = 1.0 if warm else 0.0
    tm[7] = 0.0
    tm[8] = 0.0


@numba.njit(cache=True, _nrt=False)
def _t_node_flux_warm(ms_k, ms_psi, ms_exp, k2, e2, Lm, c0, A, m):
    """The T node's flux magnitude (Wb) by Newton from ``m`` near the root: one power per curve
    term (``u^n`` as ``u^(n-1) u``), reciprocals instead of divisions, and a step tolerance of
    1e-10 (quadratic convergence: the next step would be far below the last digit)."""
    inv_psi = 1.0 / ms_psi
    inv_Lm = 1.0 / Lm
    for _ in range(30):
        u = m * inv_psi
        sat = 1.0
        dsat = 0.0
        if ms_k != 0.0:
            pd = u ** (ms_exp - 1.0)
            sat += ms_k * (pd * u)
            dsat += ms_k * ms_exp * pd
        if k2 != 0.0:
            pd = u if e2 == 2.0 else u ** (e2 - 1.0)
            sat += k2 * (pd * u)
            dsat += k2 * e2 * pd
        step = (m * (c0 + sat * inv_Lm) - A) / (c0 + (sat + u * dsat) * inv_Lm)
        m -= step
        if abs(step) <= 1e-10 * (m + 1e-300):
            break
    return m


@numba.njit(cache=True, _nrt=False)
def _t_solve(c, x, tm):
    """T mode: stator and total rotor currents (T units, A) and the referral ``Lm/(Lm + Llr)``
    (the circuit's constants in ``tm``, :func:`_t_constants`). The node's flux solves its
    current balance by Newton from the unsaturated solution (an upper bound), or with a warm
    ``tm`` from the last solution of the trajectory with one power per curve term (a step or
    two fewer, a third of the powers; the same root to the last digits: the identification
    model, not the plant, which keeps the cold solve)."""
    ms_k, ms_psi, ms_exp, k2, e2 = c[7], c[8], c[9], c[23], c[24]
    Lm, Lls, Llr, g0, c0 = tm[0], tm[1], tm[2], tm[3], tm[4]
    pr_a = x[2] / g0
    pr_b = x[3] / g0
    A_a = x[0] / Lls + pr_a / Llr
    A_b = x[1] / Lls + pr_b / Llr
    A = math.sqrt(A_a * A_a + A_b * A_b)
    m = A / tm[5]  # the unsaturated solution: an upper bound (s >= 1)
    if tm[6] > 0.0:
        if tm[7] > 0.0 and tm[8] > 0.0:  # the last root scaled with the balance's right side
            m = min(m, tm[7] * (A / tm[8]))
        m = _t_node_flux_warm(ms_k, ms_psi, ms_exp, k2, e2, Lm, c0, A, m)
        tm[8] = A
    else:
        for _ in range(30):
            u = m / ms_psi
            sat = 1.0
            dsat = 0.0
            if ms_k != 0.0:
                sat += ms_k * u**ms_exp
                dsat += ms_k * ms_exp * u ** (ms_exp - 1.0) / ms_psi
            if k2 != 0.0:
                sat += k2 * u**e2
                dsat += k2 * e2 * u ** (e2 - 1.0) / ms_psi
            f = m * (c0 + sat / Lm) - A
            step = f / (c0 + (sat + m * dsat) / Lm)
            m -= step
            if abs(step) <= 1e-13 * (m + 1e-300):
                break
    tm[7] = m
    if A > 0.0:
        pm_a = A_a * m / A
        pm_b = A_b * m / A
    else:
        pm_a = 0.0
        pm_b = 0.0
    return (x[0] - pm_a) / Lls, (x[1] - pm_b) / Lls, (pr_a - pm_a) / Llr, (pr_b - pm_b) / Llr, g0
