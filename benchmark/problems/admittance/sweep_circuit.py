"""The generalised sweep circuit: the equivalent circuit of a slip sweep whose branches the
effects of the sweep catalogue may replace (a rotor whose admittance depends on slip, a
magnetising branch that saturates or loses power in iron, resistances that follow the winding
temperature). With no effect it is the 8-parameter circuit of :mod:."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from benchmark.problems.admittance.circuit import rotor_admittance

# ----------------------------------------------------------------------------- the circuit


@dataclass(frozen=True)
class SweepCircuit:
    """The generalised per-phase circuit of a sweep (ohm at the test frequency, at the reference
    temperature). Hooks left at None are the 6/8-parameter circuit's constants.

    Attributes
    ----------
    R1t : stator series resistance ``R1 + R1sigma``, ohm (copper part ``R1t - R1sigma``).
    X1, R2, X2, R0, X0 : ohm.  R1sigma, R2sigma, X3 : L&B's 8-parameter terms, ohm.
    copper : copper factor ``R(theta)/R(theta_ref)`` per reading (1: no warming).
    rotor : ``rotor(s, R2, X2) -> Y2`` (S), R2 including the copper factor, X2 the leakage
        factor; None: single cage with ``R2sigma``, ``X3``.
    x0_of_e, r0_of_e : ``f(|E|) -> factor`` on X0, R0; None: 1.
    gfe_of_e : ``f(|E|) -> S``, a core-loss conductance across the magnetising branch; None: 0.
    leak_of_i : ``f(|I1|, |I2|) -> (k1, k2)`` factors on X1, X2; None: 1.
    """

    R1t: float
    X1: float
    R2: float
    X2: float
    R0: float
    X0: float
    R1sigma: float = 0.0
    R2sigma: float = 0.0
    X3: float = 0.0
    copper: np.ndarray | float = 1.0
    rotor: object = None
    x0_of_e: object = None
    r0_of_e: object = None
    gfe_of_e: object = None
    leak_of_i: object = None

    @classmethod
    def from_parameters(cls, p: dict) -> SweepCircuit:
        """From a parameter mapping: ``R1`` (+ ``R1sigma``) or ``R1_total``/``R1t``; ``X2``
        defaults to ``X1`` (the tie)."""
        R1s = float(p.get("R1sigma", 0.0))
        if "R1t" in p:
            R1t = float(p["R1t"])
        elif "R1_total" in p:
            R1t = float(p["R1_total"])
        else:
            R1t = float(p["R1"]) + R1s
        return cls(
            R1t=R1t,
            X1=float(p["X1"]),
            R2=float(p["R2"]),
            X2=float(p.get("X2", p["X1"])),
            R0=float(p["R0"]),
            X0=float(p["X0"]),
            R1sigma=R1s,
            R2sigma=float(p.get("R2sigma", 0.0)),
            X3=float(p.get("X3", 0.0)),
        )

    @property
    def nonlinear(self) -> bool:
        return any(h is not None for h in (self.x0_of_e, self.r0_of_e, self.gfe_of_e, self.leak_of_i))

    def with_(self, **kw) -> SweepCircuit:
        return replace(self, **kw)

    def solve(self, s, V, iterations: int = 30, tol: float = 1e-12):
        """Phasors at every reading: ``(Y, E, I1, I2)`` with V the reference (real) phasor."""
        s = np.asarray(s, float)
        V = np.broadcast_to(np.asarray(V, float), s.shape)
        k = np.broadcast_to(np.asarray(self.copper, float), s.shape)
        R1 = (self.R1t - self.R1sigma) * k + self.R1sigma
        R2 = self.R2 * k
        Eabs = np.abs(V)
        I1abs = np.zeros_like(s)
        I2abs = np.zeros_like(s)
        Y = None
        for _ in range(iterations if self.nonlinear else 1):
            kx1, kx2 = (1.0, 1.0) if self.leak_of_i is None else self.leak_of_i(I1abs, I2abs)
            X0 = self.X0 * (1.0 if self.x0_of_e is None else self.x0_of_e(Eabs))
            R0 = self.R0 * (1.0 if self.r0_of_e is None else self.r0_of_e(Eabs))
            Ym = 1.0 / (R0 + 1j * X0)
            if self.gfe_of_e is not None:
                Ym = Ym + self.gfe_of_e(Eabs)
            if self.rotor is None:
                Y2 = rotor_admittance(s, R2, self.X2 * kx2, self.R2sigma, self.X3)
            else:
                Y2 = self.rotor(s, R2, self.X2 * kx2)
            Zp = 1.0 / (Ym + Y2)
            Zin = R1 + 1j * self.X1 * kx1 + Zp
            Y_new = 1.0 / Zin
            I1 = V * Y_new
            E = I1 * Zp
            I2 = E * Y2
            done = Y is not None and np.max(np.abs(Y_new - Y)) <= tol * np.max(np.abs(Y_new))
            Y = Y_new
            Eabs, I1abs, I2abs = np.abs(E), np.abs(I1), np.abs(I2)
            if done:
                break
        return Y, E, I1, I2

    def admittance(self, s, V):
        return self.solve(s, V)[0]


@dataclass(frozen=True)
class SweepContext:
    """Scales of a sweep, from the data (diagnosis) or the schedule and base circuit (plant).

    Attributes
    ----------
    E_top : V, the highest air-gap voltage of the sweep (no-load at the top voltage level).
    I_stall : A, the stator current at standstill at the top voltage level.
    heat : per reading, the cumulative heat of the windings since the first reading, normalised
        to 1 at the last (the shape of a warming; see :func:`heat_profile`).
    frequency : Hz.
    """

    E_top: float
    I_stall: float
    heat: np.ndarray = field(default_factory=lambda: np.zeros(0))
    frequency: float = 60.0


def heat_profile(time, voltage, Y, sweep=None, cooling_rate=0.0):
    """Normalised winding heat along the readings from the data alone: the integral of
    ``|I1|^2 = |V Y|^2`` over the acquisition time (``time``, else the reading index), with an
    optional first-order cooling rate (1/s). 0 at the first reading, 1 at the last."""
    V = np.asarray(voltage, float)
    q = np.abs(V * np.asarray(Y)) ** 2
    t = np.arange(len(q), dtype=float) if time is None else np.asarray(time, float)
    out = np.zeros(len(q))
    for i in range(1, len(q)):
        dt = max(t[i] - t[i - 1], 0.0)
        decay = np.exp(-cooling_rate * dt)
        out[i] = out[i - 1] * decay + 0.5 * (q[i] + q[i - 1]) * dt
    return out / out[-1] if out[-1] > 0 else out
