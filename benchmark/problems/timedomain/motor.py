"""Induction-motor model of Alonge et al. (1998), the model.

Conventions, stated once: stator-fixed alpha-beta frame with the amplitude-invariant Clarke
transform (peak-valued quantities), SI units, ``w`` is the *electrical* rotor speed
(pole pairs x mechanical speed), ``w_M`` the mechanical one. The rotor is referred so that
``Lr = Ls`` (only stator-side combinations are observable), and the leakage inductance ``Le``
is a free parameter with ``Lm = sqrt(Lr*(Ls - Le))``.

The equations are pure functions of state and input (:func:`state_derivative`); the stepper
that integrates them lives in :mod:`benchmark.problems.timedomain.simulation`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

import numpy as np

from benchmark.problems.timedomain.compiled import compiled

#: Order of the physical parameters everywhere a vector of them is used.
PARAMETER_NAMES = ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")
#: Unit of each parameter (fv per mechanical rad/s).
PARAMETER_UNITS = {"Rs": "ohm", "Ls": "H", "Le": "H", "Rr": "ohm", "J": "kg m^2", "fv": "N m s/rad", "fc": "N m"}

#: Columns of the coefficient matrix the compiled simulation reads, in this order.
COEFFICIENT_NAMES = ("a11", "a13", "c1", "c2", "a31", "a33", "kt", "inv_tau_m", "b_m", "fc")
N_COEF = len(COEFFICIENT_NAMES)


@dataclass(frozen=True)
class InductionMotor:
    """Parameters of the single-cage model with ``Lr = Ls``.

    Attributes
    ----------
    Rs : stator resistance, ohm.
    Ls : stator (= rotor) self-inductance, H.
    Le : leakage inductance ``Ls - Lm^2/Lr``, H.
    Rr : rotor resistance, ohm.
    J : rotor inertia, kg m^2.
    fv : viscous friction coefficient, N m s (per mechanical rad/s).
    fc : Coulomb friction torque, N m.
    p : pole pairs.
    """

    Rs: float
    Ls: float
    Le: float
    Rr: float
    J: float
    fv: float
    fc: float
    p: int = 1

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if not np.isfinite(v):
                raise ValueError(f"{f.name} must be finite, got {v}")
        if not 0 < self.Le < self.Ls:
            raise ValueError(f"need 0 < Le < Ls, got Le={self.Le}, Ls={self.Ls}")
        if min(self.Rs, self.Rr, self.J) <= 0 or self.fv < 0 or self.fc < 0 or self.p < 1:
            raise ValueError("need Rs, Rr, J > 0, fv, fc >= 0 and p >= 1")

    @property
    def Lr(self) -> float:
        """Rotor self-inductance, H (tied to Ls)."""
        return self.Ls

    @property
    def Lm(self) -> float:
        """Magnetising inductance, H."""
        return math.sqrt(self.Lr * (self.Ls - self.Le))

    @property
    def tau_m(self) -> float:
        """Mechanical time constant J/fv, s."""
        return self.J / self.fv if self.fv > 0 else math.inf

    def vector(self) -> np.ndarray:
        """The parameters in :data:`PARAMETER_NAMES` order."""
        return np.array([getattr(self, n) for n in PARAMETER_NAMES], dtype=float)

    def as_dict(self) -> dict[str, float]:
        return {k: (int(v) if k == "p" else float(v)) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, d: dict) -> InductionMotor:
        return cls(**{n: float(d[n]) for n in PARAMETER_NAMES}, p=int(d.get("p", 1)))


def coefficients(theta: np.ndarray, p: int) -> np.ndarray:
    """Model coefficients for a population of parameter vectors.

    ``theta`` has shape ``(n_pop, 7)`` in :data:`PARAMETER_NAMES` order. Returns ``(n_pop,
    N_COEF)`` in :data:`COEFFICIENT_NAMES` order; rows of non-physical candidates (Le >= Ls,
    non-positive resistances or inertia) are NaN, which the simulation scores as +inf.
    """
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    Rs, Ls, Le, Rr, J, fv, fc = theta.T
    Lr = Ls
    with np.errstate(all="ignore"):
        Lm = np.sqrt(Lr * (Ls - Le))
        k = Lm / Lr
        Re = Rs + k * k * Rr
        a33 = Rr / Lr
        c2 = Lm / (Le * Lr)
        out = np.stack(
            [
                Re / Le,  # a11
                a33 * c2,  # a13
                1.0 / Le,  # c1
                c2,  # c2
                Rr * Lm / Lr,  # a31
                a33,  # a33
                1.5 * p * k,  # kt: torque per unit flux-current product
                fv / J,  # 1/tau_m
                p / J,  # b_m
                fc,
            ],
            axis=1,
        )
    bad = ~((Le > 0) & (Ls > Le) & (Rs > 0) & (Rr > 0) & (J > 0) & (fv >= 0) & (fc >= 0))
    bad |= ~np.all(np.isfinite(out), axis=1)
    out[bad] = np.nan
    return np.ascontiguousarray(out)


@compiled(inline="always")
def electromagnetic_torque(kt, i_a, i_b, psi_a, psi_b):
    """Air-gap torque, N m: ``(3/2) p (Lm/Lr) (psi_a i_b - psi_b i_a)`` (``kt`` holds the factor)."""
    return kt * (psi_a * i_b - psi_b * i_a)


@compiled(inline="always")
def state_derivative(c, i_a, i_b, psi_a, psi_b, w, v_a, v_b, direction):
    """Time derivatives of the five states for coefficient row ``c``; load torque is zero.

    Coulomb friction opposes the motion: ``fc*direction`` while turning, where ``direction``
    is the sign of the speed at the start of the integration step (holding it over the step
    keeps RK4's stages from chattering around w = 0). At rest (``direction = 0``) the rotor
    stays put while the motor torque does not exceed ``fc`` (stiction), else it breaks away.
    """
    a11, a13, c1, c2, a31, a33, kt, inv_tau, b_m, fc = (
        c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9]
    )
    di_a = -a11 * i_a + a13 * psi_a + c2 * w * psi_b + c1 * v_a
    di_b = -a11 * i_b + a13 * psi_b - c2 * w * psi_a + c1 * v_b
    dpsi_a = a31 * i_a - a33 * psi_a - w * psi_b
    dpsi_b = a31 * i_b - a33 * psi_b + w * psi_a
    t_m = electromagnetic_torque(kt, i_a, i_b, psi_a, psi_b)
    if direction != 0.0:
        dw = -w * inv_tau + b_m * (t_m - fc * direction)
    elif t_m > fc:
        dw = -w * inv_tau + b_m * (t_m - fc)
    elif t_m < -fc:
        dw = -w * inv_tau + b_m * (t_m + fc)
    else:
        dw = 0.0
    return di_a, di_b, dpsi_a, dpsi_b, dw
