"""Rotor forms of the slip-sweep double-cage effect: rotor admittances ``Y2(s)`` of two cages,
a deep bar and a quadratic resistance law, and the rise of the rotor's effective resistance with
slip (:class:`benchmark.problems.admittance.effects.DoubleCage` draws among them).
"""

from __future__ import annotations

import numpy as np


def _two_cages(a: float, s_c: float, X_series: float | None = None):
    """Rotor ``jX_c + (R_A/s) || (R_B/s + jX_B)`` with ``R_A || R_B = R2`` (low-slip resistance),
    ``R_A = (1 + a) R2`` (high-frequency resistance) and cage B blocking above ``s_c = R_B/X_B``.
    The series leakage ``X_c`` is the rest of X2 at low slip (``X_series`` overrides)."""

    def rotor(s, R2, X2):
        R_A = (1.0 + a) * R2
        R_B = (1.0 + a) / a * R2
        X_B = R_B / s_c
        share = R_A / (R_A + R_B)  # low-slip current share of cage B, squared below
        X_c = X2 - X_B * share**2 if X_series is None else X_series
        s = np.asarray(s, float)
        Yr = s / R_A + s / (R_B + 1j * s * X_B)
        return Yr / (1.0 + 1j * X_c * Yr)

    return rotor


def _deep_bar_factors(xi):
    """Field's resistance and reactance factors of a rectangular bar at reduced height ``xi``."""
    xi = np.maximum(np.asarray(xi, float), 1e-6)
    x2 = 2.0 * xi
    small = xi < 0.05
    with np.errstate(over="ignore", invalid="ignore"):
        den = np.cosh(x2) - np.cos(x2)
        kr = xi * (np.sinh(x2) + np.sin(x2)) / den
        kx = 1.5 / xi * (np.sinh(x2) - np.sin(x2)) / den
    kr = np.where(small, 1.0 + xi**4 * 4.0 / 45.0, kr)
    kx = np.where(small, 1.0 - xi**4 * 8.0 / 315.0, kx)
    kr = np.where(np.isfinite(kr), kr, xi)  # large xi: kr -> xi, kx -> 3/(2 xi)
    kx = np.where(np.isfinite(kx), kx, 1.5 / xi)
    return kr, kx


def _deep_bar(h: float, bar_r: float, bar_x: float):
    """Rotor with a rectangular deep bar: the bar's share ``bar_r`` of R2 and ``bar_x`` of X2
    follow Field's factors at ``xi = h sqrt(|s|)``; the end rings and the rest do not."""

    def rotor(s, R2, X2):
        s = np.asarray(s, float)
        kr, kx = _deep_bar_factors(h * np.sqrt(np.abs(s)))
        R = R2 * (1.0 - bar_r + bar_r * kr)
        X = X2 * (1.0 - bar_x + bar_x * kx)
        return s / (R + 1j * s * X)

    return rotor


def _quadratic_rotor(r: float):
    """L&B's signature-table form ``R2 (1 + r s^2)``, ``X2/(1 + r s^2/4)``."""

    def rotor(s, R2, X2):
        s = np.asarray(s, float)
        return s / (R2 * (1.0 + r * s**2) + 1j * s * X2 / (1.0 + 0.25 * r * s**2))

    return rotor


def _rotor_resistance_rise(rotor, R2=1.0, X2=2.0, s=1.0):
    """``Re(Z2(s))*s/R2 - 1``: the rise of the rotor's effective resistance at slip ``s``."""
    Y2 = rotor(np.array([s]), R2, X2)[0]
    return float(np.real(1.0 / Y2) * s / R2 - 1.0)
