"""The free stop's speed in closed form, for the diagnosis's joint residual (:mod:`.fit`).

After the supply is removed the shaft coasts, ``J dw/dt = -(A + B w + C w^2)``, with ``A``
Coulomb friction plus the passive load torques (N m), ``B = fv`` (N m s/rad) and ``C`` a fan
load's coefficient (N m s^2/rad^2). Its speed has a closed form: an exponential of time, or
with a fan load a tangent (or hyperbolic tangent) of time; the shaft stays at rest once
stopped (passive torques hold it).

The profiled start of the coast (:meth:`benchmark.problems.timedomain.diagnosis.fit.JointModel.recorded_stop`)
evaluates the coast of the same rows from three starting speeds; :class:`FreeCoast` computes
what does not depend on the start (the decay ``exp(-t/tau)`` over the whole record, the
costly part, and with a fan load the tangent's phase ``q t / (2 J)``) once per rows, and
:meth:`FreeCoast.speed` gives the speed from each start with the same operations as
evaluating the closed form afresh (the same numbers, bit for bit).
"""

from __future__ import annotations

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
        self.fan = C[:, 0] > 1e-15  # the complex closed form only where a fan load makes it quadratic
        if np.any(self.fan):
            self.fan_terms = (A[self.fan], C[self.fan], J[self.fan], fv[self.fan])
            with np.errstate(all="ignore"):
                Af, Cf, Jf, fvf = self.fan_terms
                self.q = np.sqrt((4 * Af * Cf - fvf**2).astype(complex))
                self.turn = self.q * self.t / (2 * Jf)  # the tangent's phase q t / (2 J), the same from every start

    def speed(self, w0: np.ndarray) -> np.ndarray:
        """Speed (n, N) rad/s from the speed ``w0`` (n, 1) at the coast's start, 0 from where it
        first reaches zero."""
        n = len(self.tau)
        w0 = np.broadcast_to(np.asarray(w0, float), (n, 1))
        with np.errstate(all="ignore"):
            w = _decayed(np.ascontiguousarray(w0[:, 0]), (self.tau * self.c)[:, 0], self.decay)
            if np.any(self.fan):
                _, Cf, _, fvf = self.fan_terms
                w0f, q = w0[self.fan], self.q
                phi0 = np.arctan((2 * Cf * w0f + fvf) / q)
                w[self.fan] = np.real((-fvf + q * np.tan(phi0 - self.turn)) / (2 * Cf))
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
