"""The induction machine's T-equivalent circuit and its referral to the project's parameters.

Conventions: stator-fixed alpha-beta frame, amplitude-invariant Clarke transform (alpha-beta
magnitudes are phase peak values), per-phase circuit quantities, SI units. Power and torque
carry the factor 3/2 of that transform: ``T = 3/2 p (psi_s x i_s)``.

Referral. Stator measurements see only ``Rs``, the stator inductance ``Ls = Lls + Lm``, the
transient inductance ``Le = Ls - Lm^2/Lr`` and the rotor branch up to a turns ratio. The
identification model fixes that ratio by ``Lr = Ls``; the same terminal behaviour then needs
the rotor resistance ``Rr * Ls / Lr`` (the rotor time constant ``Lr/Rr`` and
``Rr (Lm/Lr)^2`` are kept). ``J``, ``fv``, ``fc`` are not referred.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

PROJECT_NAMES = ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")


@dataclass(frozen=True)
class TMachine:
    """T-equivalent circuit of a cage induction machine (per phase, SI).

    Parameters
    ----------
    Rs : stator resistance, ohm, at ``theta_ref``.
    Lls : stator leakage inductance, H.
    Llr : rotor leakage inductance (referred to the stator), H.
    Lm : magnetising inductance (unsaturated), H.
    Rr : rotor resistance (referred to the stator), ohm, at ``theta_ref``.
    p : pole pairs.
    J : moment of inertia of the rotor (and rigidly coupled load), kg m^2.
    fv : viscous friction coefficient, N m s (torque ``fv * w_mech``).
    fc : Coulomb friction torque, N m (with stiction at standstill).
    theta_ref : winding temperature at which ``Rs`` and ``Rr`` are given, deg C.
    """

    Rs: float
    Lls: float
    Llr: float
    Lm: float
    Rr: float
    p: int
    J: float
    fv: float
    fc: float
    theta_ref: float = 20.0

    def __post_init__(self):
        for name in ("Rs", "Lls", "Llr", "Lm", "Rr", "J"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if self.fv < 0 or self.fc < 0 or int(self.p) != self.p or self.p < 1:
            raise ValueError("fv, fc must be >= 0 and p a positive integer")

    # --- derived quantities -------------------------------------------------------------
    @property
    def Ls(self) -> float:
        """Stator self inductance ``Lls + Lm``, H."""
        return self.Lls + self.Lm

    @property
    def Lr(self) -> float:
        """Rotor self inductance ``Llr + Lm``, H."""
        return self.Llr + self.Lm

    @property
    def Le(self) -> float:
        """Transient (total leakage) inductance ``Ls - Lm^2/Lr``, H."""
        return self.Ls - self.Lm**2 / self.Lr

    @property
    def Rr_referred(self) -> float:
        """Rotor resistance of the ``Lr = Ls`` parametrisation, ``Rr Ls/Lr``, ohm."""
        return self.Rr * self.Ls / self.Lr

    def referred(self) -> dict:
        """The project's parameters ``Rs, Ls, Le, Rr, J, fv, fc`` (ohm, H, H, ohm, kg m^2, N m s, N m)."""
        return {"Rs": self.Rs, "Ls": self.Ls, "Le": self.Le, "Rr": self.Rr_referred,
                "J": self.J, "fv": self.fv, "fc": self.fc}

    def as_dict(self) -> dict:
        d = asdict(self)
        d["p"] = int(self.p)
        return {k: (float(v) if k != "p" else v) for k, v in d.items()}

    # --- other parametrisations ---------------------------------------------------------
    @classmethod
    def from_referred(cls, Rs, Ls, Le, Rr, J, fv, fc, p, leakage_ratio: float = 1.0, theta_ref: float = 20.0):
        """The T circuit with ``Llr = leakage_ratio * Lls`` whose referred values are the
        given ``Rs, Ls, Le, Rr`` (``Rr`` of the ``Lr = Ls`` parametrisation).

        ``Lm`` solves ``Lm^2 - (1-k)(Ls-Le) Lm - k Ls (Ls-Le) = 0`` (``k`` = leakage_ratio);
        ``Rr_T = Rr Lr / Ls``.
        """
        if not 0 < Le < Ls:
            raise ValueError(f"need 0 < Le < Ls, got Le={Le}, Ls={Ls}")
        k = float(leakage_ratio)
        a = (1 - k) * (Ls - Le)
        Lm = 0.5 * (a + math.sqrt(a * a + 4 * k * Ls * (Ls - Le)))
        Lls = Ls - Lm
        Llr = k * Lls
        Lr = Llr + Lm
        return cls(Rs=Rs, Lls=Lls, Llr=Llr, Lm=Lm, Rr=Rr * Lr / Ls, p=int(p), J=J, fv=fv, fc=fc, theta_ref=theta_ref)

    @classmethod
    def from_reactances(cls, R1, X1, R2, X2, Xm, f, p, J, fv, fc, theta_ref: float = 20.0):
        """From per-phase reactances (ohm) at the frequency ``f`` (Hz)."""
        w = 2 * math.pi * f
        return cls(Rs=R1, Lls=X1 / w, Llr=X2 / w, Lm=Xm / w, Rr=R2, p=int(p), J=J, fv=fv, fc=fc, theta_ref=theta_ref)

    @classmethod
    def from_inverse_gamma(cls, Rs, RR, Lsgm, LM, p, J, fv, fc, leakage_ratio: float = 1.0, theta_ref: float = 20.0):
        """From inverse-Gamma parameters (``Ls = Lsgm + LM``, ``Le = Lsgm``,
        ``Rr (Lm/Lr)^2 = RR``)."""
        Ls = Lsgm + LM
        return cls.from_referred(Rs, Ls, Lsgm, RR * Ls / LM, J, fv, fc, p, leakage_ratio, theta_ref)

    # --- steady state ---------------------------------------------------------------------
    def steady_state(self, V: float, f: float, slip, Rc: float = math.inf) -> dict:
        """Phasor solution of the linear T circuit for a balanced sinusoidal supply.

        Parameters
        ----------
        V : phase voltage amplitude (peak = alpha-beta magnitude), V.
        f : supply frequency, Hz.
        slip : slip(s) ``(w_sync - p w_mech)/w_sync``.
        Rc : optional core-loss resistance across the magnetising branch, ohm.

        Returns
        -------
        dict of arrays: ``I`` stator current amplitude (A peak), ``phase`` (rad, current lag),
        ``Ir`` rotor current amplitude, ``torque`` (N m), ``P_in`` (W), ``P_mech`` (W),
        ``speed`` (mechanical rad/s).
        """
        s = np.atleast_1d(np.asarray(slip, float))
        w = 2 * math.pi * f
        Zm = 1j * w * self.Lm
        if math.isfinite(Rc):
            Zm = Zm * Rc / (Zm + Rc)
        with np.errstate(divide="ignore", invalid="ignore"):
            Z2 = np.where(s != 0, self.Rr / np.where(s != 0, s, 1.0) + 1j * w * self.Llr, np.inf)
            Zp = np.where(np.isfinite(Z2), Zm * Z2 / (Zm + Z2), Zm)
        Z = self.Rs + 1j * w * self.Lls + Zp
        Is = V / Z
        E = Is * Zp
        Ir = np.where(np.isfinite(Z2), E / np.where(np.isfinite(Z2), Z2, 1.0), 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            T = np.where(s != 0, 1.5 * self.p * np.abs(Ir) ** 2 * self.Rr / (np.where(s != 0, s, 1.0) * w), 0.0)
        speed = (1 - s) * w / self.p
        return {"I": np.abs(Is), "phase": -np.angle(Is), "Ir": np.abs(Ir), "torque": T,
                "P_in": 1.5 * np.real(V * np.conj(Is)), "P_mech": T * speed, "speed": speed}

    def friction_slip(self, V: float, f: float, load: float = 0.0) -> float:
        """Slip at which the air-gap torque equals ``fv w + fc + load`` (N m), on the stable
        (small-slip) side, from the phasor solution."""
        from scipy.optimize import brentq

        w_sync = 2 * math.pi * f / self.p

        def miss(s):
            return self.steady_state(V, f, s)["torque"][0] - (self.fv * (1 - s) * w_sync + self.fc + load)

        slips = np.linspace(1e-7, 1.0, 4001)
        T = self.steady_state(V, f, slips)["torque"]
        s_pull = slips[int(np.argmax(T))]
        return brentq(miss, 1e-9, s_pull, xtol=1e-15)

    def rated_point(self, V_line_rms: float, f: float, P_rated: float) -> dict:
        """The slip at which the shaft delivers ``P_rated`` (W, after friction) at rated
        voltage: ``slip``, ``current`` (A rms), ``speed`` (rpm), ``torque`` (N m)."""
        from scipy.optimize import brentq

        V = V_line_rms * math.sqrt(2.0 / 3.0)
        w_sync = 2 * math.pi * f / self.p

        def shaft(s):
            ss = self.steady_state(V, f, s)
            wm = (1 - s) * w_sync
            return ss["torque"][0] * wm - self.fv * wm**2 - self.fc * wm

        slips = np.linspace(1e-6, 0.5, 2001)
        P = np.array([shaft(x) for x in slips])
        k = int(np.argmax(P))
        if P[k] < P_rated:
            raise ValueError(f"the circuit cannot deliver {P_rated} W at {V_line_rms} V (max {P[k]:.0f} W)")
        s = brentq(lambda x: shaft(x) - P_rated, 1e-9, slips[k], xtol=1e-14)
        ss = self.steady_state(V, f, s)
        return {"slip": s, "current": float(ss["I"][0] / math.sqrt(2)), "speed": (1 - s) * w_sync * 30 / math.pi,
                "torque": P_rated / ((1 - s) * w_sync)}
