"""Mechanical pre-identification from the free stop (the free stop).

With no supply and the currents gone, ``dw_M/dt = -w_M/tau_m - fc/J`` for ``w_M > 0``
(mechanical speed; ``fc/J`` in rad/s^2).

* Case 1, Coulomb friction neglected: ``w = w0 exp(-t/tau_m)``; ``tau_m`` is the time at
  which ``w = w0/e``.
* Case 2, Coulomb friction included: least squares on the derivative-free linear form
  ``w(t) - w(0) = -(1/tau_m) integral(w) - (fc/J) t`` (``w(0)`` a third unknown), refined by
  nonlinear least squares on the closed-form solution.

Afterwards only the electromagnetic parameters and ``J`` are searched; ``fv = J/tau_m`` and
``fc = J (fc/J)`` follow for every candidate ``J``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize

from benchmark.core.errors import DataError
from benchmark.problems.timedomain.filters import free_motion_start, zero_phase_lowpass

#: Smallest ``1/tau_m`` (1/s) of the free-stop fit: a mechanical time constant of at most 1e9 s
#: (viscous friction of zero to the fit's resolution; it cannot be negative).
MIN_INV_TAU = 1e-9


@dataclass(frozen=True)
class MechanicalEstimate:
    """Result of the free-stop fit.

    Attributes: tau_m (s), fc_over_J (rad/s^2, 0 in case 1), w0 (rad/s, speed at the start
    of the free motion), t_free (s, when the free motion starts in the stop record), case.
    """

    tau_m: float
    fc_over_J: float
    w0: float
    t_free: float
    case: int

    def free_motion(self, t: np.ndarray) -> np.ndarray:
        """Model speed (rad/s) at times ``t`` measured from the start of the free motion."""
        a = self.tau_m * self.fc_over_J
        return np.maximum((self.w0 + a) * np.exp(-np.asarray(t) / self.tau_m) - a, 0.0)


def fit_free_stop(t: np.ndarray, speed: np.ndarray, case: int = 2, filter_speed: bool = True,
                  source: str = "stop record") -> MechanicalEstimate:
    """Fit the free motion of a stop record (t in s from supply removal, mechanical rad/s)."""
    t = np.asarray(t, float)
    w = np.asarray(speed, float)
    if len(t) < 20:
        raise DataError(source, "stop record too short for the mechanical pre-identification (< 20 rows)")
    dt = float(np.median(np.diff(t)))
    if filter_speed:
        w = zero_phase_lowpass(w, dt)
    k0 = free_motion_start(t, w)
    moving = np.flatnonzero(w[k0:] > 0.02 * w[k0]) + k0
    if len(moving) < 10:
        raise DataError(source, "the rotor does not coast in the stop record: no free motion to fit")
    k1 = moving[-1] + 1
    tt = t[k0:k1] - t[k0]
    ww = w[k0:k1]
    if case == 1:
        target = ww[0] / np.e
        below = np.flatnonzero(ww <= target)
        if len(below) == 0:
            # the record ends before w0/e: fit the exponential's log-linear slope instead
            slope = np.polyfit(tt, np.log(np.maximum(ww, 1e-12)), 1)[0]
            tau = -1.0 / slope
        else:
            j = below[0]
            tau = float(np.interp(target, [ww[j], ww[j - 1]], [tt[j], tt[j - 1]])) if j > 0 else tt[0]
        return MechanicalEstimate(tau_m=float(tau), fc_over_J=0.0, w0=float(ww[0]), t_free=float(t[k0]), case=1)
    if case != 2:
        raise ValueError(f"case must be 1 or 2, got {case}")
    integral = integrate.cumulative_trapezoid(ww, tt, initial=0.0)
    A = np.column_stack([np.ones_like(tt), -integral, -tt])
    (w0, inv_tau, c), *_ = np.linalg.lstsq(A, ww, rcond=None)
    inv_tau = max(inv_tau, 1e-9)

    def residual(q):
        w0_, inv_tau_, c_ = q
        a = c_ / inv_tau_
        return (w0_ + a) * np.exp(-tt * inv_tau_) - a - ww

    sol = optimize.least_squares(residual, [w0, inv_tau, c], x_scale=np.abs([w0, inv_tau, c]) + 1e-12)
    if sol.x[1] < MIN_INV_TAU or sol.x[2] < 0.0:
        # friction cannot drive the shaft: a coast that brakes harder as it slows (an eddy-current
        # brake left excited: viscous at low speed, falling above its critical speed) fits a negative
        # viscous term; fitted again within the physics (fv, fc >= 0), the coast model then misses it
        x0 = [sol.x[0], max(sol.x[1], 1.0 / max(tt[-1], 1e-9)), max(sol.x[2], 0.0)]
        sol = optimize.least_squares(residual, x0, x_scale=np.abs(x0) + 1e-12,
                                     bounds=([-np.inf, MIN_INV_TAU, 0.0], [np.inf, np.inf, np.inf]))
    w0, inv_tau, c = sol.x
    return MechanicalEstimate(tau_m=float(1.0 / inv_tau), fc_over_J=float(max(c, 0.0)), w0=float(w0),
                              t_free=float(t[k0]), case=2)
