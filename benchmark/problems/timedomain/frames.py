"""Reference frames: the amplitude-invariant Clarke transform used throughout the project,
``x_a = (2/3)(x_R - (x_S + x_T)/2)``, ``x_b = (x_S - x_T)/sqrt(3)`` (the paper's eq. 8 omits the
2/3 factor: its alpha-beta quantities are 3/2 times these), and its inverse."""

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


def inverse_clarke(x_a, x_b):
    """Inverse of :func:`clarke` for zero-sequence-free quantities -> (x_R, x_S, x_T)."""
    x_a, x_b = np.asarray(x_a, dtype=float), np.asarray(x_b, dtype=float)
    return x_a, -0.5 * x_a + 0.5 * SQRT3 * x_b, -0.5 * x_a - 0.5 * SQRT3 * x_b
