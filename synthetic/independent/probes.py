"""Current probes that saturate by their own physics: held-out forms of the probe effect.

Both act on the phase current ``i`` (A) at the sample instants, channel by channel, before
the noise, and keep a memory (the core's magnetic state), so they are written as loops.

``hall_core``
    An open-loop Hall sensor: the Hall element sits in the air gap of a magnetic concentrator
    (a gapped core around the conductor). The primary ampere-turns drive the gap and the core,
    ``i - i_c q = r + 0.1 L (|r|/L)^S sign(r)``: the reading ``r`` (the gap flux density) is
    the current less the core's ampere-turns, a power law of exponent ``S`` beyond the knee
    (the log-log slope of a steel's magnetisation curve above its knee), 10 % of the reading
    at the level ``L``; it keeps rising, slower and slower, instead of flattening at ``L``.
    ``q`` is the core's coercive state, a stop operator (Prandtl-Ishlinskii) that swings from
    -1 to 1 over a current change of ``4 i_c``: the magnetic offset ``i_c q`` an overload
    leaves in such sensors (specified by makers as the offset after an overload).
``current_transformer``
    A current transformer (gapless core) with a resistive burden, referred to the primary:
    the core flux over the burden resistance ``m`` (A s) obeys ``dm/dt = i - i_e(m)`` with the
    exciting current ``i_e = m/T_s + i_k (|m|/m_k)^S sign(m)`` (secondary time constant
    ``T_s``; excitation curve of log-log slope ``1/S`` above the knee ``m_k = L/w``, so that a
    sinusoid of amplitude ``L`` at the rated frequency ``w`` reaches the knee, where it draws
    ``i_k = 0.05 L``); the reading is ``i - i_e``. The core starts with a remanent flux
    ``m_0`` from an earlier use. This is the CT model of the IEEE PSRC's CT saturation
    calculator (Swift; Zocholl), for the asymmetric (DC-offset) currents of a motor start:
    the DC part drives the core into saturation within a few cycles, then the reading
    collapses in alternate half-cycles and recovers as the offset decays. A CT passes no DC,
    so it is drawn only for the fixed-frequency starts.

Integration of the CT: one step per sample, the primary current by the trapezoidal rule and
the exciting current implicitly (a safeguarded Newton on the monotone equation).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: The core's share of the ampere-turns at the level ``L`` of a ``hall_core`` probe.
HALL_IRON_SHARE = 0.1
#: Exciting current at the knee of a ``current_transformer``, a share of its level ``L``.
CT_KNEE_CURRENT = 0.05


@njit(cache=True)
def _hall_channel(i, level, S, coercive, out):
    q = 0.0
    prev = 0.0
    for k in range(i.shape[0]):
        x = i[k]
        if coercive > 0.0:
            q = min(1.0, max(-1.0, q + (x - prev) / (2.0 * coercive)))
        prev = x
        y = abs(x - coercive * q)
        r = y  # Newton from above on a convex increasing function: monotone
        for _ in range(100):
            p = HALL_IRON_SHARE * (r / level) ** (S - 1.0)
            step = (r * (1.0 + p) - y) / (1.0 + S * p)
            r -= step
            if abs(step) <= 1e-13 * (1.0 + y):
                break
        out[k] = r if x - coercive * q >= 0.0 else -r


def hall_core(i: np.ndarray, level: float, exponent: float, coercive: float) -> np.ndarray:
    """Readings of ``hall_core`` probes (see module docstring) of the currents ``i`` (K, c)."""
    i = np.ascontiguousarray(i, float)
    out = np.empty_like(i)
    for c in range(i.shape[1]):
        col = np.empty(i.shape[0])
        _hall_channel(np.ascontiguousarray(i[:, c]), float(level), float(exponent), float(coercive), col)
        out[:, c] = col
    return out


@njit(cache=True)
def _exciting(m, inv_Ts, ik, mk, S):
    a = abs(m) / mk
    ie = m * inv_Ts + ik * a**S * (1.0 if m >= 0.0 else -1.0)
    return ie, inv_Ts + ik * S * a ** (S - 1.0) / mk


@njit(cache=True)
def _ct_channel(i, dt, mk, ik, S, inv_Ts, m0, out):
    m = m0
    prev = 0.0
    for k in range(i.shape[0]):
        rhs = m + 0.5 * dt * (prev + i[k])
        prev = i[k]
        # solve g(x) = x + dt i_e(x) - rhs = 0 (increasing); the root lies between 0 and rhs
        lo, hi = min(0.0, rhs), max(0.0, rhs)
        x = min(max(m, lo), hi)
        for _ in range(200):
            ie, d = _exciting(x, inv_Ts, ik, mk, S)
            g = x + dt * ie - rhs
            if g > 0.0:
                hi = x
            else:
                lo = x
            xn = x - g / (1.0 + dt * d)
            if not (lo <= xn <= hi):
                xn = 0.5 * (lo + hi)
            if abs(xn - x) <= 1e-14 * (abs(x) + mk):
                x = xn
                break
            x = xn
        m = x
        out[k] = i[k] - _exciting(m, inv_Ts, ik, mk, S)[0]


def current_transformer(i: np.ndarray, dt: float, level: float, w_rated: float, exponent: float,
                        secondary_time_constant: float, remanence) -> np.ndarray:
    """Readings of current transformers (see module docstring) of the currents ``i`` (K, c)
    sampled every ``dt`` s: knee at a sinusoid of amplitude ``level`` (A) at ``w_rated``
    (rad/s), excitation exponent, secondary time constant (s) and each core's remanent flux
    as a signed share of its knee flux."""
    i = np.ascontiguousarray(i, float)
    out = np.empty_like(i)
    mk = level / w_rated
    for c in range(i.shape[1]):
        col = np.empty(i.shape[0])
        _ct_channel(np.ascontiguousarray(i[:, c]), float(dt), mk, CT_KNEE_CURRENT * level, float(exponent),
                    1.0 / float(secondary_time_constant), float(remanence[c]) * mk, col)
        out[:, c] = col
    return out
