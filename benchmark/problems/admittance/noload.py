"""What a no-load test at several voltages gives: the friction and windage loss (the constant
loss extrapolated to zero voltage) and the magnetising curve (the magnetising reactance against
the air-gap flux), per phase of the winding as connected.

The separation follows the classical procedure of IEEE 112 (clause 5.3, no-load test) and IEC
60034-2-1 (constant losses): the input power less the stator copper loss at each voltage is the
core loss plus friction and windage; plotted against the voltage squared it is nearly a straight
line at low voltage (core loss ~ V^2), whose intercept at zero voltage is the friction and windage
loss. The line is fitted through the readings at or below 60 % of the highest voltage (at least
three; else the three lowest).

The magnetising curve: at no load (after friction and windage are taken out of the input power)
the rotor carries no current, so ``1/Y = Z1 + Z0`` and the magnetising branch is ``Z0 = 1/Y - Z1``,
at the air-gap voltage ``E = V - I1 Z1``. Its parallel form ``1/Z0 = G_fe - j/X_m`` gives the
magnetising reactance ``X_m`` at that flux. The flux of a reading at frequency ratio ``k = f/f_rated``
is measured by ``psi = |E|/k`` (the air-gap voltage it would have at rated frequency).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FrictionWindage", "friction_windage", "MagnetisingCurve", "magnetising_curve"]

#: Share of the highest no-load voltage at or below which readings fit the friction line.
LOW_VOLTAGE_SHARE = 0.6
#: Smallest relative standard error of a friction and windage loss: the separation assumes a
#: constant loss, but the no-load speed and the stray loss change with voltage (about 2 %).
FRICTION_FLOOR = 0.02


@dataclass(frozen=True)
class FrictionWindage:
    """Friction and windage loss at no-load speed, W (three phases), its standard error (W) and
    how it was obtained."""

    power: float
    how: str
    sigma: float = 0.0


def friction_windage(V, I, P, R1) -> FrictionWindage | None:
    """The constant-loss line of a no-load series (per phase V, I in V and A RMS; P the three-phase
    input power, W; R1 the stator resistance per phase at each reading's temperature, ohm).

    Returns None when the series has fewer than three voltages (no line to extrapolate)."""
    V, I, P = (np.asarray(a, float) for a in (V, I, P))
    R1 = np.broadcast_to(np.asarray(R1, float), V.shape)
    if len(np.unique(np.round(V, 6))) < 3:
        return None
    constant = P - 3.0 * I**2 * R1
    low = V <= LOW_VOLTAGE_SHARE * V.max()
    if low.sum() < 3:
        low = np.argsort(V)[:3]
    x, y = V[low] ** 2, constant[low]
    A = np.stack([np.ones_like(x), x], axis=1)
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    intercept = float(coef[0])
    dof = len(x) - 2
    se = 0.0
    if dof > 0:
        r = y - A @ coef
        se = float(np.sqrt(r @ r / dof * np.linalg.inv(A.T @ A)[0, 0]))
    sigma = max(se, FRICTION_FLOOR * abs(intercept))
    return FrictionWindage(
        power=max(intercept, 0.0),
        how=f"no-load input less stator copper loss against V^2, straight line through the {len(x)} readings "
        f"at the lowest voltages extrapolated to zero voltage (IEEE 112 5.3.4): {intercept:.4g} W "
        f"(standard error {sigma:.2g} W)",
        sigma=sigma,
    )


@dataclass(frozen=True)
class MagnetisingCurve:
    """The magnetising reactance against flux from a no-load series (per phase).

    Attributes
    ----------
    psi : V, the flux of each no-load reading as an air-gap voltage at rated frequency.
    Xm : ohm, the parallel magnetising reactance at each reading (rated frequency).
    G_fe : S, the parallel core-loss conductance at each reading.
    voltage : V per phase at the terminals.  psi_ref : V, the reference flux (the reading at the
    voltage of the load test).  Xm_ref : ohm, ``Xm`` at ``psi_ref``.
    """

    psi: np.ndarray
    Xm: np.ndarray
    G_fe: np.ndarray
    voltage: np.ndarray
    psi_ref: float
    Xm_ref: float

    def factor(self, psi) -> np.ndarray:
        """``Xm(psi)/Xm(psi_ref)``, linear between readings, held at the end values beyond them."""
        order = np.argsort(self.psi)
        return np.interp(np.asarray(psi, float), self.psi[order], self.Xm[order] / self.Xm_ref)

    def rows(self, frequency: float) -> list[dict]:
        """The curve as table rows: terminal and air-gap voltage, Xm, magnetising inductance."""
        return [
            {"voltage_V": float(v), "psi_V": float(p), "Xm_ohm": float(x), "Lm_H": float(x / (2 * np.pi * frequency)),
             "Xm_over_ref": float(x / self.Xm_ref)}
            for v, p, x in sorted(zip(self.voltage, self.psi, self.Xm, strict=True))
        ]


def air_gap_flux(V, Y, R1, X1, k=1.0):
    """``|V - V Y (R1 + j k X1)| / k``: the flux (as an air-gap voltage at rated frequency, V) of
    readings of phase voltage V (V), input admittance Y (S) at frequency ratio k."""
    V = np.asarray(V, float)
    k = np.asarray(k, float)
    return np.abs(V - V * np.asarray(Y) * (np.asarray(R1, float) + 1j * k * X1)) / k


def magnetising_curve(V, Y, R1, X1, V_ref: float) -> MagnetisingCurve | None:
    """The curve of a no-load series at rated frequency: phase voltages ``V`` (V), admittances
    ``Y`` (S, friction and windage removed), stator resistance ``R1`` per reading and leakage
    reactance ``X1`` (ohm); the reference is the reading whose voltage is nearest ``V_ref``.
    None for fewer than two distinct voltages or a non-physical branch (X1 too large)."""
    V = np.asarray(V, float)
    Y = np.asarray(Y, complex)
    if len(np.unique(np.round(V, 6))) < 2:
        return None
    R1 = np.broadcast_to(np.asarray(R1, float), V.shape)
    Y0 = 1.0 / (1.0 / Y - (R1 + 1j * X1))
    if np.any(Y0.imag >= 0):
        return None
    Xm = -1.0 / Y0.imag
    psi = air_gap_flux(V, Y, R1, X1)
    ref = int(np.argmin(np.abs(V - V_ref)))
    return MagnetisingCurve(psi=psi, Xm=Xm, G_fe=Y0.real, voltage=V, psi_ref=float(psi[ref]), Xm_ref=float(Xm[ref]))
