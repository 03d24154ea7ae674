"""The free stop's speed in closed form, for the diagnosis's joint residual (:mod:`.fit`).

After the supply is removed the shaft coasts, ``J dw/dt = -(A + B w + C w^2)``, with ``A``
Coulomb friction plus the passive load torques (N m), ``B = fv`` (N m s/rad) and ``C`` a fan
load's coefficient (N m s^2/rad^2). Its speed has a closed form: an exponential of time, or
with a fan load ``w = (w0 - g (B w0 + 2 A)) / (1 + g (2 C w0 + B))``, ``g = tan(q t / (2 J)) / q``
with ``q^2 = 4 A C - B^2`` (``tanh(p t / (2 J)) / p`` with ``p^2 = -q^2`` where it is negative,
``t / (2 J)`` where it is 0): the Riccati equation's solution in real numbers, written without
the difference of near-equal terms that ``(-B + q tan(...)) / (2 C)`` takes where ``C`` is small;
the shaft stays at rest once stopped (passive torques hold it).

A DC generator still on its resistor brakes the coast through its armature circuit: its torque
``g`` follows ``B_a w`` with the armature's time constant ``tau_a`` (``tau_a g' = B_a w - g``,
``B_a`` its part of ``B``). Without a fan load the coast is then linear in ``(w, g)`` and its
speed is the sum of two exponentials of the system's eigenvalues (complex where the armature's
"electrical spring" and the inertia oscillate), from ``g = B_a w`` at the coast's start (the
record ends in a steady state). With a fan load as well the lag is left out.

An eddy-current brake still excited brakes with ``B_a w_ref h(u)``, ``h(u) = u (1 + r^2) / (1 +
(r u)^2)`` of its speed ``u`` over ``w_ref`` (through the same lag, ``r`` = ``w_ref`` over its
critical speed): the coast has no closed form, and :func:`_brake_coast` integrates it (where its dynamics are slow
beside the sampling, classical Runge-Kutta steps of a twentieth of the mechanical time constant
and a quarter of the lag's, the samples between by cubic Hermite interpolation; else Heun's
method on the record's own samples, sub-stepped to a tenth of the mechanical time constant, the
lag solved exactly over each sub-step for a speed linear across it, so that a lag shorter than
the stop's sampling, down to one sample of the start record, takes no sub-steps of its own).

The profiled start of the coast (:meth:`benchmark.problems.timedomain.diagnosis.fit.JointModel.recorded_stop`)
evaluates the coast of the same rows from three starting speeds; :class:`FreeCoast` computes
what does not depend on the start (the decay ``exp(-t/tau)`` over the whole record, the
costly part, and with a fan load ``g``, a tangent of every sample) once per rows, and
:meth:`FreeCoast.speed` gives the speed from each start with the same operations as
evaluating the closed form afresh (the same numbers, bit for bit).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from benchmark.problems.timedomain.extended_mechanics import _brake_law


class FreeCoast:
    """The coast of ``n`` rows at times ``t`` (N,) s from the supply's removal: ``J``, ``fv``,
    ``A`` and ``C`` are (n, 1) columns (kg m^2, N m s/rad, N m, N m s^2/rad^2); ``B_a`` (n, 1),
    N m s/rad, the part of ``fv`` that acts through an armature circuit of time constant
    ``tau_a`` (n, 1), s (None or 0: none)."""

    def __init__(self, t: np.ndarray, J: np.ndarray, fv: np.ndarray, A: np.ndarray, C: np.ndarray,
                 B_a: np.ndarray | None = None, tau_a: np.ndarray | None = None,
                 r_crit: np.ndarray | None = None, w_ref: np.ndarray | None = None):
        self.t = np.asarray(t, float)[None, :]
        self.brake = np.zeros(len(J), bool)  # an eddy-current brake's law: integrated (r_crit > 0)
        if B_a is not None and r_crit is not None and w_ref is not None:
            self.brake = (B_a[:, 0] > 0) & (r_crit[:, 0] > 0)
            if np.any(self.brake):
                m = self.brake
                tau_b = np.zeros_like(J[m]) if tau_a is None else tau_a[m]
                self.brake_terms = tuple(np.ascontiguousarray(v[:, 0], dtype=float) for v in
                                         (J[m], fv[m] - B_a[m], A[m], C[m], B_a[m] * w_ref[m], w_ref[m], r_crit[m],
                                          tau_b))
                B_a = np.where(self.brake[:, None], 0.0, B_a)  # the closed forms below leave these rows alone
        with np.errstate(all="ignore"):
            self.tau = J / fv
            self.c = A / J
            self.decay = np.exp(-self.t / self.tau)
        self.fan = C[:, 0] > 1e-15  # the complex closed form only where a fan load makes it quadratic
        self.armature = np.zeros(len(J), bool)
        if B_a is not None and tau_a is not None:
            self.armature = (B_a[:, 0] > 0) & (tau_a[:, 0] > 0) & ~self.fan
        if np.any(self.armature):
            m = self.armature
            self.lagged = _LaggedCoast(self.t, J[m], fv[m] - B_a[m], B_a[m], tau_a[m], A[m])
        if np.any(self.fan):
            m = self.fan
            self.fan_terms = tuple(np.ascontiguousarray(v[m, 0], dtype=float) for v in (A, C, fv))
            # g(t), the same from every start (the costly part: a tangent per sample)
            self.fan_g = _fan_g(self.t[0], *(np.ascontiguousarray(v[m, 0], dtype=float) for v in (A, C, J, fv)))

    def speed(self, w0: np.ndarray) -> np.ndarray:
        """Speed (n, N) rad/s from the speed ``w0`` (n, 1) at the coast's start, 0 from where it
        first reaches zero."""
        n = len(self.tau)
        w0 = np.broadcast_to(np.asarray(w0, float), (n, 1))
        with np.errstate(all="ignore"):
            w = _decayed(np.ascontiguousarray(w0[:, 0]), (self.tau * self.c)[:, 0], self.decay)
            if np.any(self.fan):
                w[self.fan] = _fan_coast(np.ascontiguousarray(w0[self.fan, 0], dtype=float), *self.fan_terms,
                                         self.fan_g)
            if np.any(self.armature):
                w[self.armature] = self.lagged.speed(w0[self.armature])
            if np.any(self.brake):
                w[self.brake] = _brake_coast(self.t[0], np.ascontiguousarray(w0[self.brake, 0], dtype=float),
                                             *self.brake_terms)
        return at_rest_once_stopped(w)


class _LaggedCoast:
    """The coast ``J w' = -A - fv w - g``, ``tau_a g' = B_a w - g`` of rows (each an (m, 1)
    column) from ``(w0, B_a w0)``: ``w = w* + c1 exp(l1 t) + c2 exp(l2 t)``, ``l1, l2`` the
    eigenvalues of the system's matrix, ``w* = -A/(fv + B_a)`` its rest point."""

    def __init__(self, t, J, fv, B_a, tau_a, A):
        with np.errstate(all="ignore"):
            m11, m12, m21, m22 = -fv / J, -1.0 / J, B_a / tau_a, -1.0 / tau_a
            half = 0.5 * (m11 + m22)
            det = m11 * m22 - m12 * m21
            root = np.sqrt((half * half - det).astype(complex))
            root = np.where(np.abs(root) > 1e-9 * np.abs(half), root, 1e-9 * np.abs(half))  # a double root
            self.l1, self.l2 = half + root, half - root
            self.w_rest = -A / (fv + B_a)
            self.m11, self.m12, self.B_a = m11, m12, B_a
            self.e1, self.e2 = np.exp(self.l1 * t), np.exp(self.l2 * t)

    def speed(self, w0):
        with np.errstate(all="ignore"):
            d_w = w0 - self.w_rest
            d_g = self.B_a * d_w  # g starts at B_a w0, its rest point is B_a w*
            slope = self.m11 * d_w + self.m12 * d_g
            c1 = (slope - self.l2 * d_w) / (self.l1 - self.l2)
            c2 = d_w - c1
            return np.real(self.w_rest + c1 * self.e1 + c2 * self.e2)


def at_rest_once_stopped(w: np.ndarray) -> np.ndarray:
    """``w`` (n, N) with every sample from the first one that is not positive (or NaN) on set to
    0 (in place; returned)."""
    _zero_from_first_stop(w)
    return w


@numba.njit(cache=True, nogil=True)
def _zero_from_first_stop(w):
    n, m = w.shape
    for r in range(n):
        stopped = False
        for k in range(m):
            if not stopped and not w[r, k] > 0.0:
                stopped = True
            if stopped:
                w[r, k] = 0.0


@numba.njit(cache=True, nogil=True)
def _fan_g(t, A, C, J, B):
    """``g`` (n, N) of the fan load's coast (module docstring) for rows of (n,) columns ``A``,
    ``C``, ``J``, ``B`` at times ``t`` (N,) s; inf from the tangent's pole on (the speed reaches
    zero before it)."""
    n, m = len(A), len(t)
    g = np.zeros((n, m))
    for r in range(n):
        d = 4.0 * A[r] * C[r] - B[r] * B[r]
        half = 0.5 / J[r]
        q = math.sqrt(abs(d))
        for k in range(m):
            x = q * t[k] * half
            if d > 0.0:
                g[r, k] = math.tan(x) / q if x < 0.5 * math.pi else math.inf
            elif d < 0.0:
                g[r, k] = math.tanh(x) / q
            else:
                g[r, k] = t[k] * half
    return g


@numba.njit(cache=True, nogil=True)
def _fan_coast(w0, A, C, B, g):
    """Speed (n, N) of the fan load's coast from ``w0`` (n,) with ``g`` of :func:`_fan_g`."""
    n, m = g.shape
    w = np.empty((n, m))
    for r in range(n):
        a = B[r] * w0[r] + 2.0 * A[r]
        b = 2.0 * C[r] * w0[r] + B[r]
        for k in range(m):
            w[r, k] = (w0[r] - g[r, k] * a) / (1.0 + g[r, k] * b)
    return w


@numba.njit(cache=True, nogil=True)
def _decayed(w0, offset, decay):
    """``(w0 + offset) decay - offset`` row by row (the exponential coast, ``offset = tau c``),
    the same operations as the array expression."""
    n, m = decay.shape
    w = np.empty((n, m))
    for r in range(n):
        a = w0[r] + offset[r]
        for k in range(m):
            w[r, k] = a * decay[r, k] - offset[r]
    return w


#: Heun's step on the record's samples, at most the fastest mechanical time constant over this
#: (the law's slope is at most ``1 + r^2`` at ``u = 0``), and no more than :data:`MAX_SUBSTEPS`
#: per sample (a stiff row); the field's lag, solved exactly over a step, sets no step.
HEUN_STEPS_PER_TIME_CONSTANT = 10
MAX_SUBSTEPS = 200
#: A row whose Heun step is the sample interval takes classical Runge-Kutta steps instead, of the
#: fastest mechanical time constant over this and a quarter of the lag, where they span two samples
#: or more.
STEPS_PER_TIME_CONSTANT = 20
STEPS_PER_LAG = 4


#: Rows of a brake coast taking Heun's steps integrated side by side (their chains of operations
#: overlap in the core).
LANES = 8


@numba.njit(cache=True, nogil=True)
def _brake_coast(t, w0, J, fv, A, C, T_b, w_ref, r, tau):
    """Speed (n, N) of the coast ``J w' = -(A + fv w + C w^2 + T_b h(u))`` at times ``t`` (N,)
    from ``w0`` (n,), ``u`` the speed over ``w_ref`` through a first-order lag ``tau`` (0: none)
    starting at ``w0 / w_ref``, ``h`` the kernel's law (``extended_mechanics._brake_law``); 0 once
    stopped (each argument but ``t`` an (n,) column of the rows). A row whose dynamics are slow
    beside the sampling takes classical Runge-Kutta steps spanning several samples
    (:func:`_brake_rk4_row`); the others take ``sub`` Heun steps per sample, and rows with the same
    ``sub`` are integrated side by side in groups of :data:`LANES` (:func:`_brake_lanes`), each by
    its own operations, so a row's speed does not depend on the others."""
    n, m = len(w0), len(t)
    w = np.zeros((n, m))
    dt_max = 0.0
    for j in range(1, m):
        dt_max = max(dt_max, t[j] - t[j - 1])
    subs = np.empty(n, np.int64)
    for k in range(n):
        inv_J, inv_w = 1.0 / J[k], 1.0 / w_ref[k]
        rate = (fv[k] + T_b[k] * (1.0 + r[k] * r[k]) * inv_w + 2.0 * C[k] * max(w0[k], 0.0)) * inv_J
        # Heun's sub-steps: a tenth of the fastest mechanical time constant (the lag sets none)
        sub = max(1, int(math.ceil(HEUN_STEPS_PER_TIME_CONSTANT * dt_max * rate)))
        subs[k] = min(sub, MAX_SUBSTEPS)
        h_need = 1.0 / (STEPS_PER_TIME_CONSTANT * rate) if rate > 0.0 else math.inf
        if tau[k] > 0.0:
            h_need = min(h_need, tau[k] / STEPS_PER_LAG)
        span = m if h_need == math.inf else int(min(h_need / dt_max, m))
        if subs[k] == 1 and span >= 2:
            _brake_rk4_row(t, span, w0[k], J[k], fv[k], A[k], C[k], T_b[k], w_ref[k], r[k], tau[k], w[k])
            subs[k] = 0  # done
    order = np.argsort(subs, kind="mergesort")
    i = 0
    while i < n and subs[order[i]] == 0:
        i += 1
    while i < n:
        e = i + 1
        while e < n and e - i < LANES and subs[order[e]] == subs[order[i]]:
            e += 1
        _brake_lanes(t, order[i:e], subs[order[i]], w0, J, fv, A, C, T_b, w_ref, r, tau, w)
        i = e
    return w


@numba.njit(cache=True, nogil=True, inline="always")
def _brake_slopes(x, u, J, fv, A, C, T_b, inv_w, r, tau):
    """``(w', u')`` of the brake coast at speed ``x`` and lagged speed ``u`` (``tau`` 0: ``u``
    is ``x / w_ref``, and ``u'`` 0)."""
    if tau > 0.0:
        return -(A + fv * x + C * x * x + T_b * _brake_law(u, r)) / J, (x * inv_w - u) / tau
    return -(A + fv * x + C * x * x + T_b * _brake_law(x * inv_w, r)) / J, 0.0


@numba.njit(cache=True, nogil=True)
def _brake_rk4_row(t, span, w0, J, fv, A, C, T_b, w_ref, r, tau, out):
    """Classical Runge-Kutta steps of ``span`` samples, the samples between by cubic Hermite
    interpolation; the rest stays 0 from the first speed that is not positive."""
    m = len(t)
    inv_w = 1.0 / w_ref
    x, u = w0, w0 * inv_w
    out[0] = x
    if not x > 0.0:
        return
    k1x, k1u = _brake_slopes(x, u, J, fv, A, C, T_b, inv_w, r, tau)  # a step's first stage: the last one's end
    j = 0
    while j < m - 1:
        e = min(j + span, m - 1)
        h = t[e] - t[j]
        xs, dxs = x, k1x
        k2x, k2u = _brake_slopes(x + 0.5 * h * k1x, u + 0.5 * h * k1u, J, fv, A, C, T_b, inv_w, r, tau)
        k3x, k3u = _brake_slopes(x + 0.5 * h * k2x, u + 0.5 * h * k2u, J, fv, A, C, T_b, inv_w, r, tau)
        k4x, k4u = _brake_slopes(x + h * k3x, u + h * k3u, J, fv, A, C, T_b, inv_w, r, tau)
        x += h / 6.0 * (k1x + 2.0 * (k2x + k3x) + k4x)
        u += h / 6.0 * (k1u + 2.0 * (k2u + k3u) + k4u)
        k1x, k1u = _brake_slopes(x, u, J, fv, A, C, T_b, inv_w, r, tau)
        for i in range(j + 1, e + 1):
            if i == e:
                v = x
            else:  # cubic Hermite between the step's ends
                s = (t[i] - t[j]) / h
                s2, s3 = s * s, s * s * s
                v = ((2.0 * s3 - 3.0 * s2 + 1.0) * xs + (s3 - 2.0 * s2 + s) * h * dxs
                     + (3.0 * s2 - 2.0 * s3) * x + (s3 - s2) * h * k1x)
            if not v > 0.0:
                return  # stopped: the rest stays 0
            out[i] = v
        j = e


@numba.njit(cache=True, nogil=True)
def _brake_lanes(t, rows, sub, w0, J, fv, A, C, T_b, w_ref, r, tau, w):
    """Rows ``rows`` of :func:`_brake_coast` (into ``w``), ``sub`` Heun steps per sample, side by side: each
    row's chain of operations is its own. The lag ``tau u' = x / w_ref - u`` is solved exactly over a
    step ``h`` for a speed ``x`` linear across it, ``u(h) = a u + (x_0 (1 - a) + (x_h - x_0) b) / w_ref``
    with ``a = exp(-h/tau)`` and ``b = 1 - tau (1 - a) / h`` (computed again only when ``h``
    changes): exact for any ``h`` beside ``tau``, where an input held at the step's mean lags it by
    ``h/2`` instead of ``tau`` (1e-3 rad/s off on a brake's 1 ms steps, 1e-4 and 1e-5 this way)."""
    L = len(rows)
    x = np.empty(L)
    ul = np.empty(L)
    inv_J = np.empty(L)
    inv_w = np.empty(L)
    a = np.zeros(L)
    b = np.zeros(L)
    lag = np.empty(L, np.bool_)
    alive = np.ones(L, np.bool_)
    for l in range(L):
        k = rows[l]
        x[l], ul[l] = w0[k], w0[k] / w_ref[k]
        inv_J[l], inv_w[l] = 1.0 / J[k], 1.0 / w_ref[k]
        lag[l] = tau[k] > 0.0
        w[k, 0] = x[l]
    h_was = -1.0
    m = len(t)
    for j in range(1, m):
        h = (t[j] - t[j - 1]) / sub
        if h != h_was:
            for l in range(L):
                if lag[l]:
                    a[l] = math.exp(-h / tau[rows[l]])
                    b[l] = (h - tau[rows[l]] * (1.0 - a[l])) / h
            h_was = h
        left = 0
        for l in range(L):
            if alive[l] and not x[l] > 0.0:
                alive[l] = False
            left += alive[l]
        if left == 0:
            break
        for _ in range(sub):
            for l in range(L):
                if not alive[l]:
                    continue
                k = rows[l]
                xl = x[l]
                u0 = ul[l] if lag[l] else xl * inv_w[l]
                d0 = -(A[k] + fv[k] * xl + C[k] * xl * xl + T_b[k] * _brake_law(u0, r[k])) * inv_J[l]
                xp = xl + h * d0
                u1 = ((ul[l] * a[l] + (xl * (1.0 - a[l]) + (xp - xl) * b[l]) * inv_w[l]) if lag[l]
                      else xp * inv_w[l])
                d1 = -(A[k] + fv[k] * xp + C[k] * xp * xp + T_b[k] * _brake_law(u1, r[k])) * inv_J[l]
                x_new = xl + 0.5 * h * (d0 + d1)
                if lag[l]:
                    ul[l] = ul[l] * a[l] + (xl * (1.0 - a[l]) + (x_new - xl) * b[l]) * inv_w[l]
                x[l] = x_new
        for l in range(L):
            if alive[l]:
                w[rows[l], j] = x[l]


def switched_at_end(col: dict, t_end: float) -> np.ndarray:
    """(n, 1) envelope of the switched load (``T_s``) at the start-up record's end ``t_end`` (s):
    on (1) when a step came on before it; with a first-order rise (``tau_s > 0``) its value there,
    and after a switch-off (``t_step_off``) the decay since (the stop record starts from it)."""
    t_on, tau, t_off = col["t_step"], col["tau_s"], col["t_step_off"]
    with np.errstate(all="ignore"):
        safe = np.where(tau > 0, tau, 1.0)
        off = (t_off > t_on) & (t_off <= t_end)
        rise = 1.0 - np.exp(-(np.where(off, t_off, t_end) - t_on) / safe)
        env = np.where(off, rise * np.exp(-(t_end - t_off) / safe), rise)
    return np.where(tau > 0, np.where(t_on < t_end, env, 0.0), (t_on < t_end).astype(float))
