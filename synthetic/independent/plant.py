"""The plant: a machine with its rotor, magnetic curves, iron loss, thermal model, shaft,
inverter and grid source impedance, packed into the arrays the integrator reads.

A plain :class:`Plant` (only a :class:`~synthetic.independent.machine.TMachine`) is the linear
single-cage T circuit: the effects of :mod:`~synthetic.independent.effects` replace its parts.

State vector layout (``n`` rotor loops): ``psi_s`` (2), ``psi_r`` (2n), ``psi_fe`` (2), then
``w_m, w_l, twist, theta, i_a`` (mechanics, with a DC generator load's armature current) and
``theta_s, theta_r, theta_c`` (winding and stator core temperatures, C).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from synthetic.independent.curves import LeakageCurve, MagnetisingCurve
from synthetic.independent.inverter import Inverter
from synthetic.independent.machine import TMachine
from synthetic.independent.mechanics import N_MECH, Mechanics
from synthetic.independent.rotor import RotorCage
from synthetic.independent.thermal import Thermal

#: RK4 is stable for real eigenvalues with ``h |lambda| < 2.78``; the step keeps this margin.
STABLE_H_LAMBDA = 2.0
E_P, E_RS, E_RG, E_INVLFE, E_RFE, E_C, E_IH, E_ALPHA, E_PSIREF = range(9)
N_THERMAL = 3


@dataclass(frozen=True)
class IronLoss:
    """Iron loss as a short-circuited stator-fixed winding linked by the main flux
    (eddy currents in the laminations).

    Parameters
    ----------
    R : winding resistance, ohm (referred, per phase).
    L : its leakage inductance, H; ``L/R`` is the eddy-current time constant. With
        ``w L/R << 1`` it acts as the resistance ``R (1 + (w L/R)^2)`` across the
        magnetising branch.
    coercive : held-out ``steinmetz`` form: coercive current at the flux ``psi_ref``, A
        (0 = eddy currents only; see :mod:`~synthetic.independent.electrical`).
    alpha : Steinmetz exponent of the hysteresis loss per cycle.
    psi_ref : flux at which ``coercive`` is given, Wb.
    """

    R: float
    L: float
    coercive: float = 0.0
    alpha: float = 2.0
    psi_ref: float = 1.0

    @classmethod
    def steinmetz(cls, E: float, w: float, P: float, share: float, tau: float, alpha: float, psi_ref: float):
        """The ``steinmetz`` winding (eddy time constant ``tau`` s) that dissipates ``P`` W
        at the EMF amplitude ``E`` (V, flux ``psi_ref = E/w`` Wb) and angular frequency ``w``
        (rad/s), and ``(share/2 + (1 - share)/4) P`` at ``w/2`` and the same flux: the
        two-frequency separation of iron loss into a hysteresis share ``share`` (loss per
        cycle independent of frequency) and eddy currents (per cycle proportional to it)."""
        from scipy.optimize import fsolve

        def miss(x):
            R, ih = np.exp(x)
            return [np.log(_steady_loss(R, tau * R, ih, E, w) / P),
                    np.log(_steady_loss(R, tau * R, ih, E / 2, w / 2) / (P * (share / 2 + (1 - share) / 4)))]

        start = np.log([1.5 * E**2 / ((1 - share) * P), share * P / (1.5 * E)])
        R, ih = np.exp(fsolve(miss, start, xtol=1e-12))
        return cls(float(R), float(tau * R), float(ih), float(alpha), float(psi_ref))

    def equivalent_resistance(self, f: float) -> float:
        """Parallel core-loss resistance giving the same loss at frequency ``f``, ohm."""
        x = 2 * math.pi * f * self.L
        return self.R * (1 + (x / self.R) ** 2)


def _steady_loss(R: float, L: float, ih: float, E: float, w: float) -> float:
    """Loss (W) of the dead-zone iron-loss winding (resistance ``R`` ohm, leakage ``L`` H,
    coercive current ``ih`` A) under a rotating EMF of amplitude ``E`` V at ``w`` rad/s: its
    current of magnitude ``m > ih`` solves ``(w L m)^2 + (R (m - ih))^2 = E^2`` and it
    dissipates ``3/2 R (m - ih) m``."""
    a, b, c = (w * L) ** 2 + R**2, -2 * R**2 * ih, (R * ih) ** 2 - E**2
    m = (-b + np.sqrt(b * b - 4 * a * c)) / (2 * a)
    return 1.5 * R * (m - ih) * m


@dataclass(frozen=True)
class Plant:
    """Everything the integrator simulates, except the supply and the sensors."""

    machine: TMachine
    rotor: RotorCage | None = None
    magnetising: MagnetisingCurve | None = None
    stator_leakage: LeakageCurve | None = None
    iron: IronLoss | None = None
    thermal: Thermal = field(default_factory=Thermal)
    mechanics: Mechanics = field(default_factory=Mechanics)
    inverter: Inverter = field(default_factory=Inverter)
    source_R: float = 0.0
    source_L: float = 0.0

    def cage(self) -> RotorCage:
        return self.rotor if self.rotor is not None else RotorCage.single(self.machine.Rr, self.machine.Llr)

    def mag_curve(self) -> MagnetisingCurve:
        return self.magnetising if self.magnetising is not None else MagnetisingCurve("linear", self.machine.Lm)

    def leak_curve(self) -> LeakageCurve:
        return self.stator_leakage if self.stator_leakage is not None else LeakageCurve("none", self.machine.Lls, 0.0)

    @property
    def n_loops(self) -> int:
        return self.cage().n

    @property
    def n_states(self) -> int:
        return 4 + 2 * self.n_loops + N_MECH + N_THERMAL

    def mech_offset(self) -> int:
        return 4 + 2 * self.n_loops

    def check(self) -> None:
        cage = self.cage()
        c = float(np.sum(np.linalg.inv(cage.L_array)))
        if not self.leak_curve().monotone(self.source_L):
            raise ValueError("stator leakage curve: the flux must rise with current")
        if not cage.common.monotone(1.0 / c):
            raise ValueError("rotor common leakage curve: the flux must rise with current")

    def pack(self) -> dict:
        """Arrays for :func:`synthetic.independent.integrate.run_steps`."""
        self.check()
        m = self.machine
        cage = self.cage()
        Linv = np.linalg.inv(cage.L_array)
        wv = Linv @ np.ones(cage.n)
        stat = self.leak_curve().params()
        stat[1] += self.source_L
        el = np.zeros(9)
        el[E_P], el[E_RS], el[E_RG] = m.p, m.Rs, self.source_R
        el[E_INVLFE] = 1.0 / self.iron.L if self.iron is not None else 0.0
        el[E_RFE] = self.iron.R if self.iron is not None else 0.0
        if self.iron is not None:
            el[E_IH], el[E_ALPHA], el[E_PSIREF] = self.iron.coercive, self.iron.alpha, self.iron.psi_ref
        el[E_C] = float(wv.sum())
        return {"n": cage.n, "el": el, "stat": stat, "rot": cage.common.params(), "mag": self.mag_curve().params(),
                "Rr": cage.R_array.copy(), "Linv": Linv, "wv": wv,
                "mech": self.mechanics.pack(m.J, m.fv, m.fc), "therm": self.thermal.pack(m.theta_ref)}

    def initial_state(self) -> np.ndarray:
        x = np.zeros(self.n_states)
        th = self.thermal.theta_start if self.thermal.theta_start is not None else self.machine.theta_ref
        x[self.mech_offset() + N_MECH:] = th
        return x

    def inductance_matrix(self, saturated: bool) -> tuple[np.ndarray, np.ndarray]:
        """Per-axis winding inductance and resistance matrices (stator, loops, iron winding)
        of the linearised machine at standstill: unsaturated, or with every curve at its
        smallest incremental inductance (for the step-size bound)."""
        cage = self.cage()
        n = cage.n
        lk = self.leak_curve()
        mc = self.mag_curve()
        if saturated:
            Lm = mc.Linf if mc.form != "linear" else mc.Lm0
            dmin = -1.0 / 8.0 if lk.form == "lorentzian" else 0.0
            Lls = lk.L_lin + dmin * lk.L_sat
            cm = cage.common
            Lc = cm.L_lin + (-1.0 / 8.0 if cm.form == "lorentzian" else 0.0) * cm.L_sat
        else:
            Lm, Lls, Lc = mc.Lm0, lk.L0, cage.common.L0
        size = 1 + n + (1 if self.iron is not None else 0)
        L = np.full((size, size), Lm)
        L[0, 0] += Lls + self.source_L
        L[1:1 + n, 1:1 + n] += cage.L_array + max(Lc, 0.0)
        R = np.zeros(size)
        R[0] = self.machine.Rs + self.source_R
        R[1:1 + n] = cage.R_array
        if self.iron is not None:
            L[-1, -1] += self.iron.L
            R[-1] = self.iron.R
        return L, np.diag(R)

    def fastest_rate(self, extra_stator_R: float = 0.0) -> float:
        """Largest ``|eigenvalue|`` (1/s) of the linearised electrical system (both the
        unsaturated and the most saturated inductances), with ``extra_stator_R`` ohm added
        to the stator (an open contactor pole)."""
        out = 0.0
        for sat in (False, True):
            L, R = self.inductance_matrix(sat)
            R = R.copy()
            R[0, 0] += extra_stator_R
            out = max(out, float(np.max(np.abs(np.linalg.eigvals(np.linalg.solve(L, R))))))
        return out

    def locked_rotor_impedance(self, f: float) -> float:
        """Magnitude of the standstill impedance at ``f`` Hz (unsaturated), ohm."""
        w = 2 * math.pi * f
        m = self.machine
        Zr = complex(self.cage().impedance(w)[0])
        Zm = 1j * w * self.mag_curve().Lm0
        return abs(m.Rs + 1j * w * self.leak_curve().L0 + Zm * Zr / (Zm + Zr))
