"""Reference frames: the amplitude-invariant Clarke transform used throughout the project,
``x_a = (2/3)(x_R - (x_S + x_T)/2)``, ``x_b = (x_S - x_T)/sqrt(3)`` (the paper's eq. 8 omits the
2/3 factor: its alpha-beta quantities are 3/2 times these), its inverse, the same from two
line-to-line voltages (:func:`line_to_line_clarke`), the rotation speed of an alpha-beta phasor
(:func:`phasor_speed`: the supply frequency from the voltages) and a channel's phasor at a
given speed (:func:`fundamental`)."""

from __future__ import annotations

import math

import numpy as np

SQRT3 = math.sqrt(3.0)


def clarke(x_r, x_s, x_t):
    """Amplitude-invariant Clarke transform: phase quantities -> (alpha, beta).

    ``x_a = (2/3)(x_R - (x_S + x_T)/2)``, ``x_b = (x_S - x_T)/sqrt(3)``. (The paper's eq. 8
    omits the 2/3: its alpha-beta quantities are 3/2 times these.)"""
    x_r, x_s, x_t = (np.asarray(x, dtype=float) for x in (x_r, x_s, x_t))
    return (2.0 / 3.0) * (x_r - 0.5 * (x_s + x_t)), (x_s - x_t) / SQRT3


def line_to_line_clarke(v_rs, v_st):
    """Two line-to-line voltages of a three-wire supply (``v_rs = v_R - v_S``, ``v_st = v_S -
    v_T``, V) -> the (alpha, beta) voltages of the equivalent star, as :func:`clarke` gives them
    from its phase voltages (a three-wire supply has no zero sequence to miss):
    ``v_a = (2 v_rs + v_st) / 3``, ``v_b = v_st / sqrt(3)``."""
    v_rs, v_st = np.asarray(v_rs, dtype=float), np.asarray(v_st, dtype=float)
    return (2.0 * v_rs + v_st) / 3.0, v_st / SQRT3


def inverse_clarke(x_a, x_b):
    """Inverse of :func:`clarke` for zero-sequence-free quantities -> (x_R, x_S, x_T)."""
    x_a, x_b = np.asarray(x_a, dtype=float), np.asarray(x_b, dtype=float)
    return x_a, -0.5 * x_a + 0.5 * SQRT3 * x_b, -0.5 * x_a - 0.5 * SQRT3 * x_b


def phasor_speed(x_a, x_b, t) -> float:
    """Signed rotation speed (rad/s) of the phasor ``x_a + j x_b`` sampled at the times ``t`` (s):
    the least-squares slope of its unwrapped angle; 0 for fewer than 8 samples. Positive for the
    positive phase sequence."""
    phase = np.unwrap(np.angle(np.asarray(x_a, dtype=float) + 1j * np.asarray(x_b, dtype=float)))
    if len(phase) < 8:
        return 0.0
    w = float(np.polyfit(np.asarray(t, dtype=float), phase, 1)[0])
    return w if math.isfinite(w) else 0.0


def fundamental(x, t, w) -> complex:
    """Phasor of the complex channel ``x`` (``x_a + j x_b``) at the speed ``w`` (rad/s) over the
    times ``t`` (s): the mean of ``x exp(-j w t)``. Its modulus is the alpha-beta amplitude (a
    phase quantity's peak)."""
    return complex(np.mean(np.asarray(x) * np.exp(-1j * w * np.asarray(t, dtype=float))))
