"""The extended model's T mode: the magnetising branch saturating at a T circuit's node (the
node's flux solved each step). Compiled helpers of :mod:`benchmark.problems.timedomain.extended`'s
stepper; the T mode is described in ``docs/extended_model.md``.

numba's on-disk cache is keyed by each function's own source file: the stepper's cached code
holds these helpers' code, so an edit here is not seen by a cached stepper. After editing this
file, touch ``extended.py`` too (CI and wheels start from an empty cache).
"""

from __future__ import annotations

import math

from benchmark.problems.timedomain.compiled import compiled


@compiled(_nrt=False, inline="always")
def _t_mode(c):
    """The row's magnetising branch saturates at a T circuit's node: a split is set, the
    magnetising curve bends, and the leakage does not saturate (see the module docstring)."""
    return c[36] > 0.0 and (c[7] != 0.0 or c[23] != 0.0) and c[10] == 0.0


@compiled(_nrt=False)
def _t_constants(c, tm, warm):
    """The T circuit of a T-mode row into ``tm``: ``Lm, Lls, Llr`` (H), the referral ``g0``,
    ``c0 = 1/Lls + 1/Llr`` and ``c0 + 1/Lm`` (1/H); ``tm[6]`` 1 when the node's flux may start
    from the previous solution (``warm``), ``tm[7]`` (0: none yet), ``tm[9]`` and ``tm[10]`` the
    warm solver's last evaluation (:func:`_t_node_flux_warm`)."""
    L_sig, LM, k = c[1], c[2], c[36]
    Ls_tot = L_sig + LM
    a = (1.0 - k) * LM
    Lm = 0.5 * (a + math.sqrt(a * a + 4.0 * k * Ls_tot * LM))
    Lls = Ls_tot - Lm
    Llr = k * Lls
    tm[0], tm[1], tm[2], tm[3], tm[4] = Lm, Lls, Llr, Lm / (Lm + Llr), 1.0 / Lls + 1.0 / Llr
    tm[5], tm[6], tm[7] = tm[4] + 1.0 / Lm, 1.0 if warm else 0.0, 0.0


@compiled(_nrt=False)
def _t_node_flux_warm(ms_k, ms_psi, ms_exp, k2, e2, Lm, c0, A, m, tm):
    """The T node's flux magnitude (Wb) by Newton near the root: the first step from the last
    evaluation of the trajectory (``tm[7]`` flux, ``tm[9]`` curve factor, ``tm[10]`` its
    derivative times the flux, no power needed), then steps with one power per curve term
    (``u^n`` as ``u^(n-1) u``) and reciprocals, to a step of 1e-8 (quadratic convergence: the
    error left is below 1e-14). ``m``: the unsaturated bound."""
    inv_psi = 1.0 / ms_psi
    inv_Lm = 1.0 / Lm
    if tm[7] > 0.0:
        m0, sat, usat = tm[7], tm[9], tm[10]
        guess = m0 - (m0 * (c0 + sat * inv_Lm) - A) / (c0 + (sat + usat) * inv_Lm)
        if 0.0 < guess < m:
            m = guess
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
        tm[7], tm[9], tm[10] = m, sat, u * dsat
        step = (m * (c0 + sat * inv_Lm) - A) / (c0 + (sat + u * dsat) * inv_Lm)
        m -= step
        if abs(step) <= 1e-8 * (m + 1e-300):
            break
    return m


@compiled(_nrt=False)
def _t_solve(c, x, tm):
    """T mode: stator and total rotor currents (T units, A) and the referral ``Lm/(Lm + Llr)``
    (the circuit's constants in ``tm``, :func:`_t_constants`). The node's flux solves its
    current balance by Newton from the unsaturated solution (an upper bound; the plant), or
    with a warm ``tm`` by :func:`_t_node_flux_warm` (the identification model's batch kernel)."""
    ms_k, ms_psi, ms_exp, k2, e2 = c[7], c[8], c[9], c[23], c[24]
    Lm, Lls, Llr, g0, c0 = tm[0], tm[1], tm[2], tm[3], tm[4]
    pr_a = x[2] / g0
    pr_b = x[3] / g0
    A_a = x[0] / Lls + pr_a / Llr
    A_b = x[1] / Lls + pr_b / Llr
    A = math.sqrt(A_a * A_a + A_b * A_b)
    m = A / tm[5]  # the unsaturated solution: an upper bound (s >= 1)
    if tm[6] > 0.0:
        m = _t_node_flux_warm(ms_k, ms_psi, ms_exp, k2, e2, Lm, c0, A, m, tm)
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
    pm_a = A_a * m / A if A > 0.0 else 0.0
    pm_b = A_b * m / A if A > 0.0 else 0.0
    return (x[0] - pm_a) / Lls, (x[1] - pm_b) / Lls, (pr_a - pm_a) / Llr, (pr_b - pm_b) / Llr, g0
