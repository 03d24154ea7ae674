"""The free stop's speed in closed form, for the diagnosis's joint residual (:mod:`.fit`).

After the supply is removed the shaft coasts, ``J dw/dt = -(A + B w + C w^2)``, with ``A``
Coulomb friction plus the passive load torques (N m), ``B = fv`` (N m s/rad) and ``C`` a fan
load's coefficient (N m s^2/rad^2). Its speed has a closed form: an exponential of time, or
with a fan load a tangent (or hyperbolic tangent) of time; the shaft stays at rest once
stopped (passive torques hold it).

The profiled start of the coast (:meth:`benchmark.problems.timedomain.diagnosis.fit.JointModel.recorded_stop`)
evaluates the coast of the same rows from three starting speeds; :class:`FreeCoast` computes
what does not depend on the start once per rows (the decay ``exp(-t/tau)`` over the whole
record, and with a fan load the tangent of the phase ``q t / (2 J)``), and
:meth:`FreeCoast.speed` gives the speed from each start: the exponential with the same
operations as evaluating it afresh, the fan load's tangent by the addition theorem in real
arithmetic (``tan(phi0 - b) = (tan phi0 - tan b) / (1 + tan phi0 tan b)``, with ``tan phi0``
the start's own ratio, no arctangent): where ``q^2 = 4 A C - B^2 < 0`` (the quadratic has
real roots) ``q = i r`` and the tangents are hyperbolic, ``tan(i s) = i tanh(s)``. The same
speeds as the complex closed form to rounding, without its complex tangent over every sample of
every start (a sixth of a diagnosis's CPU time on records where a load torque is a candidate).
"""

from __future__ import annotations

import math

import numba
import numpy as np


class FreeCoast:
    """The coast of ``n`` rows at times ``t`` (N,) s from the supply's removal: ``J``, ``fv``,
    ``A`` and ``C`` are (n, 1) columns (kg m^2, N m s/rad, N m, N m s^2/rad^2)."""

    def __init__(self, t: np.ndarray, J: np.ndarray, fv: np.ndarray, A: np.ndarray, C: np.ndarray):
        self.t = np.asarray(t, float)[None, :]
        with np.errstate(all="ignore"):
            self.tau = J / fv
            self.c = A / J
            self.decay = np.exp(-self.t / self.tau)
        self.fan = C[:, 0] > 1e-15  # the tangent form only where a fan load makes it quadratic
        if np.any(self.fan):
            Af, Cf, Jf, fvf = (np.ascontiguousarray(a[self.fan][:, 0], dtype=float) for a in (A, C, J, fv))
            self.fan_terms = (Cf, fvf, 4 * Af * Cf - fvf**2)
            self.fan_phase = _fan_phase(self.fan_terms[2], Cf, Jf, np.ascontiguousarray(self.t[0]))

    def speed(self, w0: np.ndarray) -> np.ndarray:
        """Speed (n, N) rad/s from the speed ``w0`` (n, 1) at the coast's start, 0 from where it
        first reaches zero."""
        n = len(self.tau)
        w0 = np.broadcast_to(np.asarray(w0, float), (n, 1))
        with np.errstate(all="ignore"):
            w = _decayed(np.ascontiguousarray(w0[:, 0]), (self.tau * self.c)[:, 0], self.decay)
            if np.any(self.fan):
                w[self.fan] = _fan_speed(np.ascontiguousarray(w0[self.fan, 0]), *self.fan_terms, self.fan_phase)
        return at_rest_once_stopped(w)


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


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _fan_phase(q2, C, J, t):
    """Per fan-loaded row, what its coast's tangent form needs of the time ``t`` (N,) s whatever
    the start: ``tan(q t / (2 J))`` where ``q^2 = 4 A C - B^2 > 0``, ``tanh(r t / (2 J))``
    where ``q^2 = -r^2 < 0``, and ``C t / J`` where ``q^2 = 0`` (a double root)."""
    n, m = q2.shape[0], t.shape[0]
    out = np.empty((n, m))
    for r in range(n):
        if q2[r] > 0.0:
            a = math.sqrt(q2[r]) / (2.0 * J[r])
            for k in range(m):
                out[r, k] = math.tan(a * t[k])
        elif q2[r] < 0.0:
            a = math.sqrt(-q2[r]) / (2.0 * J[r])
            for k in range(m):
                out[r, k] = math.tanh(a * t[k])
        else:
            a = C[r] / J[r]
            for k in range(m):
                out[r, k] = a * t[k]
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _fan_speed(w0, C, B, q2, phase):
    """The coast's speed (n, N) rad/s with a fan load from the speeds ``w0`` (n,) at its start:
    ``J dw/dt = -(A + B w + C w^2)`` solved with ``phase`` of :func:`_fan_phase`;
    ``(-B + q tan(phi0 - q t / (2 J))) / (2 C)`` with ``tan phi0 = (2 C w0 + B) / q``, by the
    addition theorem (module docstring)."""
    n, m = phase.shape
    w = np.empty((n, m))
    for r in range(n):
        two_c = 2.0 * C[r]
        a = two_c * w0[r] + B[r]
        if q2[r] > 0.0:
            q = math.sqrt(q2[r])
            u = a / q
            for k in range(m):
                tb = phase[r, k]
                w[r, k] = (-B[r] + q * (u - tb) / (1.0 + u * tb)) / two_c
        elif q2[r] < 0.0:
            q = math.sqrt(-q2[r])
            u = a / q
            for k in range(m):
                tb = phase[r, k]
                w[r, k] = (-B[r] + q * (u + tb) / (1.0 + u * tb)) / two_c
        else:  # a double root: 1 / (w + B / (2 C)) grows as C t / J
            for k in range(m):
                w[r, k] = -B[r] / two_c + 1.0 / (two_c / a + phase[r, k])
    return w
