"""The extended induction-motor model: the base model plus the unmodelled effects.

It is the physics behind both the synthetic plant that makes "real" data with an effect and
the augmented identification models of the sim-to-real diagnosis. With every effect term at its
neutral value it is the base model of :mod:`benchmark.problems.timedomain.motor` written in the
inverse-Gamma form (``L_sigma = Le``, ``L_M = Ls - Le``, ``R_R = Rr (Ls - Le)/Ls``), so the two
agree to rounding (tested). The states, branches, effect terms and the T mode are described in
``docs/extended_model.md``; the row format (one float row per parameter set, every effect's
fields) in :mod:`benchmark.problems.timedomain.extended_rows`.

Everything compiled lives in this file but the T mode's node solver
(:mod:`benchmark.problems.timedomain.extended_tnode`), the mechanical side's laws
(:mod:`benchmark.problems.timedomain.extended_mechanics`) and the input hold
(:func:`~benchmark.problems.timedomain.simulation.substep_voltages`): numba's on-disk cache is
keyed by the source file of each function, and a caller's cached code holds its callees' code,
so after editing one of those, touch this file too.
"""

from __future__ import annotations

import math

import numpy as np

from benchmark.problems.timedomain.compiled import compiled
from benchmark.problems.timedomain.extended_mechanics import (  # noqa: F401  (_brake_law: older free_coast.py, kernel_ab)
    _armature,
    _brake_law,
    _coupling_torque,
    _envelope,
    _loads,
    _resist,
)
from benchmark.problems.timedomain.extended_prefix import balanced, shared_starts
from benchmark.problems.timedomain.extended_rows import (  # noqa: F401  (the row API lives there)
    EXTENDED_FIELDS,
    IDX,
    N_EXT,
    base_row,
    base_rows,
    valid_rows,
)
from benchmark.problems.timedomain.extended_tnode import _t_constants, _t_mode, _t_solve
from benchmark.problems.timedomain.kernel_pool import kernel_threads, run_split
from benchmark.problems.timedomain.simulation import substep_voltages

N_STATES = 13
#: Length of the stepper's work rows: the states' derivatives, then the stator current (A).
N_WORK = N_STATES + 2
SQRT3_2 = math.sqrt(3.0) / 2.0


@compiled(_nrt=False, inline="always")
def _sat(x, k, ref, ex):
    if k == 0.0:
        return 1.0
    return 1.0 + k * (x / ref) ** ex


@compiled(_nrt=False, inline="always")
def _leak_constants(c):
    """A saturating leakage's ``1/ref^2`` (1/Wb^2) and half its exponent, for :func:`_stator_gain`."""
    return 1.0 / (c[11] * c[11]), 0.5 * c[12]


@compiled(_nrt=False, inline="always")
def _stator_gain(c, d2, inv_ref2, half_ex):
    """Stator current (A) per leakage flux linkage (Wb) whose squared magnitude is ``d2`` (Wb^2):
    ``1/L_sigma`` unless the leakage saturates, else ``s / (L_sigma (f s + 1 - f))`` with
    ``s = 1 + k (|psi|/ref)^ex`` and ``f`` the share that never saturates (``inv_ref2``,
    ``half_ex``: :func:`_leak_constants`). The power is taken as ``exp(ex/2 log(d2/ref^2))`` and
    the whole with one division: no square root, power or chain of three divisions on the
    stepper's latency path."""
    k = c[10]
    s = 1.0
    if k != 0.0:
        u = d2 * inv_ref2
        s = 1.0 + k * (math.exp(half_ex * math.log(u)) if u > 0.0 else (1.0 if half_ex == 0.0 else 0.0))
    fl = c[35]
    if fl > 0.0:
        return s / (c[1] * (fl * s + (1.0 - fl)))
    return s / c[1]


@compiled(_nrt=False, inline="always")
def _drop_sign(i, i0):
    if i0 > 0.0:
        return math.tanh(i / i0)
    if i > 0.0:
        return 1.0
    if i < 0.0:
        return -1.0
    return 0.0


@compiled(_nrt=False, inline="always")
def _loop_current(R, gain, p_a, p_b, pm_a, pm_b, L):
    """Current (A) of a rotor loop of resistance ``R`` (ohm; 0: absent, no current) and leakage
    ``L`` (H) whose flux linkage (Wb) is ``p`` over the magnetising node's ``pm``; ``gain``
    refers it (1 in inverse-Gamma units, the T circuit's g0 in T units)."""
    if R > 0.0:
        return gain * (p_a - pm_a) / L, gain * (p_b - pm_b) / L
    return 0.0, 0.0


@compiled(_nrt=False, inline="always")
def _loop_flux_rate(R, R_t, i_a, i_b, w, p_a, p_b):
    """d psi / dt (V) of a rotor loop (resistance ``R`` ohm, 0: absent; ``R_t`` at its
    temperature) carrying ``i`` (A) at the electrical rotor speed ``w`` (rad/s)."""
    if R > 0.0:
        return -R_t * i_a - w * p_b, -R_t * i_b + w * p_a
    return 0.0, 0.0


@compiled(_nrt=False, inline="always")
def _row_constants(c, th, pre):
    """What :func:`_derivative` computes from the row alone, once per trajectory, by the same
    operations (so the same numbers): the resistances at the temperature ``th`` (K), which stays
    put when ``h_th`` is 0, ``1/(1/R_r1 + g_fe)``, ``p/J``, the stator current per leakage flux
    when the leakage does not saturate (and a saturating leakage's constants,
    :func:`_leak_constants`, in ``pre[8:10]``) and the magnetising current per flux when the main
    flux does not; into ``pre``."""
    alpha = c[16]
    heat = 1.0 + alpha * th
    heat_r = 1.0 + alpha * th * (1.0 + c[38])
    pre[0] = c[0] * heat
    pre[1] = c[3] * heat_r
    pre[2] = c[4] * heat_r
    pre[3] = c[39] * heat_r
    pre[4] = 1.0 / (1.0 / pre[1] + c[6])
    pre[5] = c[20] / c[17]
    pre[8], pre[9] = _leak_constants(c)
    pre[6] = _stator_gain(c, 0.0, pre[8], pre[9])
    pre[7] = 1.0 / c[2]


@compiled(_nrt=False, inline="always")
def _derivative(c, x, v_a, v_b, direction, dir_l, env, out, tm, pre):
    """The states' derivatives at ``x`` into ``out`` (and the stator branch current); ``env``: the
    switched load's envelope at the time (:func:`_envelope`). Returns the motor's torque (N m)."""
    Rs, LM, R_r1, R_r2, Ls2 = c[0], c[2], c[3], c[4], c[5]
    gfe, ms_k, ms_psi, ms_exp = c[6], c[7], c[8], c[9]
    Ud, i0, h_th, alpha, J, fv, fc, p = c[13], c[14], c[15], c[16], c[17], c[18], c[19], c[20]
    ps_a, ps_b, pm_a, pm_b, p2_a, p2_b, w, th = x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]
    v_a = v_a - c[21]
    v_b = v_b - c[22]
    R_r3, Ls3 = c[39], c[40]
    if h_th > 0.0:
        heat = 1.0 + alpha * th
        heat_r = 1.0 + alpha * th * (1.0 + c[38])
        Rs_t = Rs * heat
        R_r1_t = R_r1 * heat_r
        R_r2_t = R_r2 * heat_r
        R_r3_t = R_r3 * heat_r
    else:
        Rs_t, R_r1_t, R_r2_t, R_r3_t = pre[0], pre[1], pre[2], pre[3]
    d_a = ps_a - pm_a
    d_b = ps_b - pm_b
    if c[10] == 0.0:
        g = pre[6]
    else:
        g = _stator_gain(c, d_a * d_a + d_b * d_b, pre[8], pre[9])
    is_a = d_a * g
    is_b = d_b * g
    p3_a, p3_b = x[10], x[11]
    i2_a, i2_b = _loop_current(R_r2, 1.0, p2_a, p2_b, pm_a, pm_b, Ls2)
    i3_a, i3_b = _loop_current(R_r3, 1.0, p3_a, p3_b, pm_a, pm_b, Ls3)
    if _t_mode(c):
        is_a, is_b, ir_a, ir_b, g0 = _t_solve(c, x, tm)
        # cage 2 and loop 3 on the rotor node, in T units
        i2_a, i2_b = _loop_current(R_r2, g0, p2_a, p2_b, pm_a, pm_b, Ls2)
        i3_a, i3_b = _loop_current(R_r3, g0, p3_a, p3_b, pm_a, pm_b, Ls3)
        e_a = -(R_r1_t / g0) * (ir_a - i2_a - i3_a) - w * pm_b
        e_b = -(R_r1_t / g0) * (ir_b - i2_b - i3_b) + w * pm_a
        if R_r2 > 0.0:  # back to inverse-Gamma units for the cage equations below
            i2_a = i2_a / g0
            i2_b = i2_b / g0
        if R_r3 > 0.0:
            i3_a = i3_a / g0
            i3_b = i3_b / g0
    else:
        if ms_k == 0.0 and c[23] == 0.0:
            gm = pre[7]
        else:
            pm = math.sqrt(pm_a * pm_a + pm_b * pm_b)
            sm = _sat(pm, ms_k, ms_psi, ms_exp)
            if c[23] != 0.0:
                sm += c[23] * (pm / ms_psi) ** c[24]
            gm = sm / LM
        im_a = pm_a * gm
        im_b = pm_b * gm
        inv_g = 1.0 / (1.0 / R_r1_t + gfe) if h_th > 0.0 else pre[4]
        e_a = (is_a + i2_a + i3_a - w * pm_b / R_r1_t - im_a) * inv_g
        e_b = (is_b + i2_b + i3_b + w * pm_a / R_r1_t - im_b) * inv_g
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
    gs = c[34]
    if gs > 0.0:
        out[0] = (v_a - Rs_t * is_a) / (1.0 + Rs_t * gs)
        out[1] = (v_b - Rs_t * is_b) / (1.0 + Rs_t * gs)
    else:
        out[0] = v_a - Rs_t * is_a
        out[1] = v_b - Rs_t * is_b
    out[2] = e_a
    out[3] = e_b
    out[N_STATES] = is_a  # the stator branch current at x, for the stepper's output
    out[N_STATES + 1] = is_b
    out[4], out[5] = _loop_flux_rate(R_r2, R_r2_t, i2_a, i2_b, w, p2_a, p2_b)
    out[10], out[11] = _loop_flux_rate(R_r3, R_r3_t, i3_a, i3_b, w, p3_a, p3_b)
    t_m = 1.5 * p * (ps_a * is_b - ps_b * is_a)
    J_l = c[31]
    if J_l > 0.0:
        # two-mass shaft: friction on the motor side, the load on the load side
        wm = w / p
        wl = x[8]
        t_sh = _coupling_torque(x[9], wm - wl, c[32], c[33], c[37], c[44])
        drive_m = t_m - t_sh - fv * wm
        out[6] = pre[5] * (drive_m - _resist(direction, drive_m, fc))
        t_pass, t_dyn = _loads(c, env, wl, x[12])
        drive_l = t_sh - t_dyn
        out[8] = (drive_l - _resist(dir_l, drive_l, t_pass)) / J_l
        out[9] = wm - wl
    else:
        t_pass, t_dyn = _loads(c, env, w / p, x[12])
        fct = fc + t_pass
        t_d = t_m - t_dyn
        if direction != 0.0:
            out[6] = -w * fv / J + pre[5] * (t_d - fct * direction)
        elif t_d > fct:
            out[6] = -w * fv / J + pre[5] * (t_d - fct)
        elif t_d < -fct:
            out[6] = -w * fv / J + pre[5] * (t_d + fct)
        else:
            out[6] = 0.0
        out[8] = 0.0
        out[9] = 0.0
    if _armature(c):  # the armature's lag of the load speed (over w_ref)
        out[12] = ((x[8] if J_l > 0.0 else w / p) / c[27] - x[12]) / c[42]
    else:
        out[12] = 0.0
    if h_th > 0.0:
        i1_a = (-w * pm_b - e_a) / R_r1_t
        i1_b = (w * pm_a - e_b) / R_r1_t
        p_cu = 1.5 * (Rs_t * (is_a * is_a + is_b * is_b) + R_r1_t * (i1_a * i1_a + i1_b * i1_b)
                      + R_r2_t * (i2_a * i2_a + i2_b * i2_b) + R_r3_t * (i3_a * i3_a + i3_b * i3_b))
        out[7] = h_th * p_cu
    else:
        out[7] = 0.0
    return t_m


@compiled(_nrt=False)
def _stator_current(c, x, tm):
    if _t_mode(c):
        ia, ib, _, _, _ = _t_solve(c, x, tm)
        return ia, ib
    d_a = x[0] - x[2]
    d_b = x[1] - x[3]
    # the leakage's constants only where it saturates (the gain reads them only there): no division
    # added to a stator-side iron loss's recorded current, computed here at every sample
    inv_ref2, half_ex = _leak_constants(c) if c[10] != 0.0 else (1.0, 0.0)
    g = _stator_gain(c, d_a * d_a + d_b * d_b, inv_ref2, half_ex)
    return d_a * g, d_b * g


@compiled(_nrt=False)
def _terminal_current(c, x, v_a, v_b, tm):
    """Recorded stator current: the branch current plus the stator-side iron-loss current."""
    ia, ib = _stator_current(c, x, tm)
    gs = c[34]
    if gs == 0.0:
        return ia, ib
    rs = c[0] * (1.0 + c[16] * x[7])
    v_a = v_a - c[21]
    v_b = v_b - c[22]
    Ud = c[13]
    if Ud > 0.0:
        s_r = _drop_sign(ia, c[14])
        s_s = _drop_sign(-0.5 * ia + SQRT3_2 * ib, c[14])
        s_t = _drop_sign(-0.5 * ia - SQRT3_2 * ib, c[14])
        v_a = v_a - Ud * (2.0 / 3.0) * (s_r - 0.5 * (s_s + s_t))
        v_b = v_b - Ud * (s_s - s_t) / (2.0 * SQRT3_2)
    k = gs / (1.0 + rs * gs)
    return ia + k * (v_a - rs * ia), ib + k * (v_b - rs * ib)


@compiled(_nrt=False, inline="always")
def _sign(v):
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@compiled(_nrt=False)
def _stick(c, x, w0, wl0, env, tm):
    """After a step: a speed that crossed zero against its Coulomb torque sticks at zero (``env``:
    the switched load's envelope at the step's end, :func:`_envelope`)."""
    p = c[20]
    fc = c[19]
    two = c[31] > 0.0
    if two:
        t_pass, t_dyn = _loads(c, env, x[8], x[12])
        if fc > 0.0 and w0 != 0.0 and x[6] * w0 <= 0.0:
            ia2, ib2 = _stator_current(c, x, tm)
            t_m = 1.5 * p * (x[0] * ib2 - x[1] * ia2)
            t_sh = c[32] * x[9] + c[33] * (x[6] / p - x[8])
            if abs(t_m - t_sh) <= fc:
                x[6] = 0.0
        if t_pass > 0.0 and wl0 != 0.0 and x[8] * wl0 <= 0.0:
            t_sh = c[32] * x[9] + c[33] * (x[6] / p - x[8])
            if abs(t_sh - t_dyn) <= t_pass:
                x[8] = 0.0
        return
    t_pass, t_dyn = _loads(c, env, 0.0, x[12])
    fct = fc + t_pass
    if fct > 0.0 and w0 != 0.0 and x[6] * w0 <= 0.0:
        ia2, ib2 = _stator_current(c, x, tm)
        t_m = 1.5 * p * (x[0] * ib2 - x[1] * ia2)
        if abs(t_m) <= fct:
            x[6] = 0.0


@compiled(_nrt=False)
def _simulate_one(c, v_a, v_b, linear, h, substeps, x0, out, t0, work, warm, k_first, snap_at, snaps):
    """Outputs (3, N): i_alpha, i_beta (A), mechanical speed (rad/s) (the load side's on a
    two-mass shaft); final state in x0. ``t0``: time of the first sample (load steps).
    ``work``: (8, N_WORK) scratch (row 7: :func:`_row_constants`); ``warm``: a T-mode row's
    node flux solved from the last solution (:func:`_t_solve`). ``k_first``: the sample it starts
    at, from the state ``x0`` and (a T-mode row's node) ``work[6]`` there, the outputs before it
    left as they are (0: from the start, ``work[6]`` set here). At each sample of ``snap_at``
    (ascending) the state and ``work[6]`` go to the next row of ``snaps``
    (:mod:`.extended_prefix`)."""
    n = v_a.shape[0]
    tm = work[6]
    pre = work[7]
    if _t_mode(c) and k_first == 0:
        _t_constants(c, tm, warm)
    x = work[0]
    for s in range(N_STATES):
        x[s] = x0[s]
    k1 = work[1]
    k2 = work[2]
    k3 = work[3]
    k4 = work[4]
    xt = work[5]
    hs = h / substeps
    p = c[20]
    two = c[31] > 0.0
    ns = N_STATES if _armature(c) else N_STATES - 1  # the armature's state only where it moves
    xt[N_STATES - 1] = x[N_STATES - 1]
    _row_constants(c, x[7], pre)
    q = 0
    for k in range(k_first, n):
        while q < snap_at.shape[0] and snap_at[q] == k:
            for s in range(N_STATES):
                snaps[q, s] = x[s]
            for s in range(N_WORK):
                snaps[q, N_STATES + s] = tm[s]
            q += 1
        # without a stator-side iron loss the recorded current is the stator branch current at
        # x, which the step's first derivative computes (the same operations): taken from there
        own = c[34] > 0.0 or k == n - 1
        if own:
            if linear:
                ia, ib = _terminal_current(c, x, v_a[k], v_b[k], tm)
            elif k > 0:  # a held input: the sample closes the previous interval
                ia, ib = _terminal_current(c, x, v_a[k - 1], v_b[k - 1], tm)
            else:
                ia, ib = _terminal_current(c, x, 0.0, 0.0, tm)
            out[0, k] = ia
            out[1, k] = ib
        out[2, k] = x[8] if two else x[6] / p
        if k == n - 1:
            break
        for j in range(substeps):
            f0, va0, vb0, vam, vbm, va1, vb1 = substep_voltages(v_a, v_b, k, linear, j, substeps)
            ts = t0 + (k + f0) * h
            w0 = x[6]
            wl0 = x[8]
            d = _sign(w0)
            dl = _sign(wl0)
            env0 = _envelope(c, ts)
            envm = _envelope(c, ts + 0.5 * hs)
            env1 = _envelope(c, ts + hs)
            # the four stages through one (inlined) call of the derivative: k1 at x, k2 and k3 at
            # xt = x + 0.5 hs k1 and x + 0.5 hs k2 (the middle), k4 at xt = x + hs k3 (the end)
            for st in range(4):
                y, va, vb, e = x, va0, vb0, env0
                if st > 0:
                    kp = work[st]  # the previous stage's derivative
                    f = hs if st == 3 else 0.5 * hs
                    for s in range(ns):
                        xt[s] = x[s] + f * kp[s]
                    y, va, vb, e = (xt, va1, vb1, env1) if st == 3 else (xt, vam, vbm, envm)
                _derivative(c, y, va, vb, d, dl, e, work[st + 1], tm, pre)
                if st == 0 and j == 0 and not own:
                    out[0, k] = k1[N_STATES]
                    out[1, k] = k1[N_STATES + 1]
            for s in range(ns):
                x[s] = x[s] + hs / 6.0 * (k1[s] + 2.0 * (k2[s] + k3[s]) + k4[s])
            _stick(c, x, w0, wl0, env1, tm)
        m = 0.0
        for s in range(ns):
            m = max(m, abs(x[s]))
        if not m < 1e9:
            for kk in range(k + 1, n):
                out[0, kk] = np.nan
                out[1, kk] = np.nan
                out[2, kk] = np.nan
            break
    for s in range(N_STATES):
        x0[s] = x[s]


@compiled(nogil=True)
def _simulate_block(start, stop, rows, v_a, v_b, linear, h, substeps, out, reps, first, branch, snaps):
    """Representatives ``reps[start..stop-1]`` from rest into ``out`` (every entry written: NaN
    for invalid rows), each keeping its state at the branch samples of its members
    (``first[j]:first[j + 1]`` of ``branch`` and ``snaps``, :mod:`.extended_prefix`); releases
    the GIL."""
    work = np.empty((8, N_WORK))
    x0 = np.empty(N_STATES)
    for j in range(start, stop):
        r = reps[j]
        c = rows[r]
        if not np.isfinite(c[0]):
            out[r] = np.nan
            continue
        x0[:] = 0.0
        a, b = first[j], first[j + 1]
        _simulate_one(c, v_a, v_b, linear, h, substeps, x0, out[r], 0.0, work, True, 0, branch[a:b], snaps[a:b])


@compiled(nogil=True)
def _resume_block(start, stop, rows, v_a, v_b, linear, h, substeps, out, order, members, source, branch, snaps):
    """Members ``members[order[start..stop-1]]`` from their representative's state at their branch
    sample, its outputs before it copied (all of them where it diverged before: no state was
    kept); releases the GIL."""
    work = np.empty((8, N_WORK))
    x0 = np.empty(N_STATES)
    none = np.empty(0, dtype=np.int64)
    kept = np.empty((0, N_STATES + N_WORK))
    for i in range(start, stop):
        m = order[i]
        r, src, k = members[m], source[m], branch[m]
        s = snaps[m]
        if not np.isfinite(s[0]):
            out[r] = out[src]
            continue
        out[r, :, :k] = out[src, :, :k]
        x0[:] = s[:N_STATES]
        work[6, :] = s[N_STATES:]
        _simulate_one(rows[r], v_a, v_b, linear, h, substeps, x0, out[r], 0.0, work, True, k, none, kept)


def simulate_extended_batch(rows, v_a, v_b, linear, h, substeps):
    """Outputs of a population of extended rows from rest: (n_pop, 3, N) i_alpha, i_beta (A),
    mechanical speed (rad/s); NaN from where a candidate diverges (or for invalid rows). The
    rows run in parallel blocks (:func:`~benchmark.problems.timedomain.kernel_pool.run_split`),
    rows that differ only in a switched load from where it may act, from the state of the one
    that switches last (:mod:`.extended_prefix`); a row's outputs depend on neither."""
    rows, v_a, v_b = (np.ascontiguousarray(a, dtype=float) for a in (rows, v_a, v_b))
    out = np.empty((rows.shape[0], 3, v_a.shape[0]))  # the blocks write every entry
    plan = shared_starts(rows, float(h), v_a.shape[0])
    snaps = np.full((len(plan.members), N_STATES + N_WORK), np.nan)
    args = (rows, v_a, v_b, bool(linear), float(h), int(substeps), out)
    run_split(_simulate_block, len(plan.representatives), *args, plan.representatives, plan.first, plan.branch, snaps)
    if len(plan.members):
        order = balanced(plan.branch, kernel_threads())
        run_split(_resume_block, len(order), *args, order, plan.members, plan.source, plan.branch, snaps)
    return out


@compiled()
def simulate_extended(row, v_a, v_b, linear, h, substeps, x0, t0=0.0):
    """One trajectory from state ``x0`` (modified in place to the final state) starting at time
    ``t0`` (s): (3, N)."""
    out = np.empty((3, v_a.shape[0]))
    _simulate_one(row, v_a, v_b, linear, h, substeps, x0, out, t0, np.empty((8, N_WORK)), False, 0,
                  np.empty(0, dtype=np.int64), np.empty((0, N_STATES + N_WORK)))
    return out
