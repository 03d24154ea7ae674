"""Supplies (test scenarios): grid direct-on-line start, six-step inverter, open-loop V/f PWM.

Each scenario turns into a :class:`Drive`: per internal integration step, what the supply
does. Inverter scenarios give each phase's gate on-fraction and edge counts per step (the
switch pattern, exact in volt-seconds per step); the grid gives its EMF parameters and each
contactor pole's state per step.

``dol``
    Phase EMFs ``e_k = V (1 + u_k) cos(th - 2 pi k/3) + sum_h a_h V cos(h (th - 2 pi k/3) + phi_h)``,
    ``th = w t + phi_0``; the 5th harmonic comes out negative-sequence and the 7th positive, as
    on a real grid. A source impedance ``R_g + j w L_g`` (sized by the voltage dip at
    locked-rotor current) sits in series. The contactor's poles close at staggered instants
    after an optional pre-trigger of zero voltage; with fewer than two poles closed no current
    can flow (stator open); with two closed the third pole is a large resistance; each pole
    bounces after closing, carrying the current through an arc (a voltage ``U_arc`` opposing
    it) for its bounce time. Recorded: the terminal phase voltages (motor side of the
    contactor and source impedance), ``input_hold: linear``; at the internal step where the
    contactor changes, the value just after the change (a floating open terminal sits at the
    motor's back-EMF, not at the grid's EMF that the open pole's resistance shows before its
    current has moved: :func:`synthetic.independent.dataset.terminal_voltage`).
``six_step``
    Switch states ``100, 110, 010, 011, 001, 101``, each for ``Nc`` samples, ``cycles`` times;
    the supply frequency is ``1/(6 Nc Ts)``. Recorded: switch-state voltages, ``zoh``.
``pwm``
    Open-loop V/f: frequency ramped linearly from 0 to ``f`` in ``ramp`` s, phase voltage
    amplitude ``boost V_r + (1 - boost) V_r f/f_r`` (at most ``Ed/2``), regular-sampled
    sine-triangle modulation with one symmetric carrier period per sample. Recorded: the
    per-sample mean of the switch-state voltages (= the sampled reference), ``zoh``.

Free stop: inverters apply the zero vector ``111``; the grid opens the contactor (stator
current zero at once).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numba import njit

from synthetic.independent.inverter import N_INVERTER

SCENARIOS = ("dol", "six_step", "pwm")
SIX_STEP_STATES = np.array([(1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1), (1, 0, 1)], float)
MODE_INVERTER, MODE_GRID, MODE_OPEN = 0, 1, 2
G_V, G_W, G_PHI, G_U, G_RG, G_ROPEN, G_UARC, G_IARC, G_NH, G_H = 0, 1, 2, 3, 6, 7, 8, 9, 10, 11


@dataclass
class Drive:
    """Per-step supply description for the integrator (``n`` steps of ``h`` seconds).

    ``mode`` (0 inverter, 1 grid, 2 stator open), ``sub`` sub-steps per step, inverter
    ``u``/``nr``/``nf`` (n, 3), grid ``closed``/``arc`` (n, 3), parameter arrays ``grid`` and
    ``inverter``, and ``v_ideal`` (n, 2): recorded alpha-beta voltage per step (inverter).
    """

    h: float
    mode: np.ndarray
    sub: np.ndarray
    u: np.ndarray
    nr: np.ndarray
    nf: np.ndarray
    closed: np.ndarray
    arc: np.ndarray
    grid: np.ndarray
    inverter: np.ndarray
    v_ideal: np.ndarray | None = None

    @property
    def n(self) -> int:
        return len(self.mode)


def _empty(n: int, h: float, mode: int, grid=None, inverter=None) -> Drive:
    z = np.zeros((n, 3))
    inverter = np.zeros(N_INVERTER) if inverter is None else inverter
    return Drive(h, np.full(n, mode, np.int64), np.ones(n, np.int64), z.copy(), z.copy(), z.copy(), z.copy(),
                 z.copy(), np.zeros(G_H) if grid is None else grid, inverter)


def _clarke_rows(v3: np.ndarray) -> np.ndarray:
    return np.column_stack([(2 / 3) * (v3[:, 0] - 0.5 * (v3[:, 1] + v3[:, 2])), (v3[:, 1] - v3[:, 2]) / math.sqrt(3)])


def gates_from_intervals(starts, ends, h: float, n: int):
    """On-fraction and edge counts per step of one gate given its on-intervals (s)."""
    starts = np.asarray(starts, float)
    ends = np.asarray(ends, float)
    grid = np.arange(n + 1) * h
    lengths = np.concatenate([[0.0], np.cumsum(ends - starts)])
    k = np.searchsorted(ends, grid, side="right")
    on = lengths[k]
    partial = np.zeros(n + 1)
    inside = k < len(starts)
    kk = np.minimum(k, max(len(starts) - 1, 0))
    if len(starts):
        partial = np.where(inside & (starts[kk] < grid), grid - starts[kk], 0.0)
    u = np.diff(on + partial) / h
    nr = np.bincount(np.floor(starts / h + 1e-7).astype(int), minlength=n + 1)[:n].astype(float)
    nf = np.bincount(np.floor(ends / h + 1e-7).astype(int), minlength=n + 1)[:n].astype(float)
    return np.clip(u, 0.0, 1.0), nr, nf


def _merge(starts, ends, eps):
    if len(starts) == 0:
        return starts, ends
    keep = np.ones(len(starts), bool)
    keep[1:] = starts[1:] > ends[:-1] + eps
    grp = np.cumsum(keep) - 1
    new_ends = np.zeros(int(keep.sum()))
    np.maximum.at(new_ends, grp, ends)
    return starts[keep], new_ends


@dataclass(frozen=True)
class SixStep:
    """Six-step inverter start (DC link ``Ed`` V, ``Nc`` samples per state, ``cycles``)."""

    Ed: float = 300.0
    Nc: int = 40
    cycles: int = 50
    kind: str = "six_step"

    def samples(self) -> int:
        return 6 * self.Nc * self.cycles

    def frequency(self, Ts: float) -> float:
        return 1.0 / (6 * self.Nc * Ts)

    def meta(self, Ts: float) -> dict:
        return {"input_hold": "zoh", "dc_link_voltage": float(self.Ed), "supply_frequency": self.frequency(Ts)}

    def gates(self, K: int) -> np.ndarray:
        return SIX_STEP_STATES[(np.arange(K) // self.Nc) % 6]

    def startup(self, Ts: float, M: int, K: int, inverter: np.ndarray) -> Drive:
        S = self.gates(K)
        return _sample_gates(S, Ts, M, inverter)

    def describe(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Pwm:
    """Open-loop V/f sine-triangle PWM start (see module docstring).

    Parameters: ``Ed`` V, ``f`` final frequency Hz, ``V_rated`` line rms V at ``f_rated`` Hz,
    ``ramp`` s, ``boost`` fraction of the rated phase amplitude at 0 Hz, ``duration`` s.
    """

    Ed: float = 560.0
    f: float = 50.0
    V_rated: float = 400.0
    f_rated: float = 50.0
    ramp: float = 0.3
    boost: float = 0.03
    duration: float = 1.0
    kind: str = "pwm"

    def meta(self, Ts: float) -> dict:
        return {"input_hold": "zoh", "dc_link_voltage": float(self.Ed), "supply_frequency": float(self.f)}

    def samples(self, Ts: float) -> int:
        return int(round(self.duration / Ts))

    def reference(self, t: np.ndarray) -> np.ndarray:
        """Phase voltage references (V, relative to the DC midpoint), shape (len(t), 3)."""
        t = np.asarray(t, float)
        if self.ramp > 0:
            f = self.f * np.minimum(t / self.ramp, 1.0)
            angle = np.where(t < self.ramp, np.pi * self.f * t**2 / self.ramp,
                             np.pi * self.f * self.ramp + 2 * np.pi * self.f * (t - self.ramp))
        else:
            f = np.full_like(t, self.f)
            angle = 2 * np.pi * self.f * t
        Vr = self.V_rated * math.sqrt(2 / 3)
        amp = np.minimum(self.boost * Vr + (1 - self.boost) * Vr * f / self.f_rated, 0.5 * self.Ed)
        k = np.arange(3)
        return amp[:, None] * np.cos(angle[:, None] - 2 * np.pi * k / 3)

    def startup(self, Ts: float, M: int, K: int, inverter: np.ndarray) -> Drive:
        h = Ts / M
        n = K * M
        d = np.clip(0.5 + self.reference(np.arange(K) * Ts) / self.Ed, 0.0, 1.0)
        drv = _empty(n, h, MODE_INVERTER, inverter=inverter)
        tk = np.arange(K) * Ts
        for ph in range(3):
            dk = d[:, ph]
            use = dk > 0
            a = tk[use] + 0.5 * (1 - dk[use]) * Ts
            b = tk[use] + 0.5 * (1 + dk[use]) * Ts
            a, b = _merge(a, b, 1e-9 * Ts)
            drv.u[:, ph], drv.nr[:, ph], drv.nf[:, ph] = gates_from_intervals(a, b, h, n)
        drv.v_ideal = _clarke_rows(inverter[0] * drv.u)
        return drv

    def describe(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Grid:
    """Direct-on-line start from the grid (see module docstring).

    Parameters
    ----------
    V : line-line rms voltage, V.   f : frequency, Hz.
    h5, h7 : 5th and 7th harmonic amplitudes, fraction of the fundamental.
    phase5, phase7 : their phases, rad.
    unbalance : per-phase fundamental amplitude deviations (fractions).
    phase0 : angle of phase R's EMF at t = 0, rad.
    pre_trigger : recorded time before the first pole closes, s.
    stagger : closing delay of each pole after ``pre_trigger``, s.
    bounce : arcing time of each pole after it closes, s.   arc_voltage : arc voltage, V.
    dip : source-impedance voltage drop at locked-rotor current, fraction of the phase voltage.
    x_over_r : reactance-to-resistance ratio of the source impedance.
    duration : recorded time after the first pole closes, s.
    """

    V: float = 400.0
    f: float = 50.0
    h5: float = 0.0
    h7: float = 0.0
    phase5: float = 0.0
    phase7: float = 0.0
    unbalance: tuple = (0.0, 0.0, 0.0)
    phase0: float = 0.0
    pre_trigger: float = 0.0
    stagger: tuple = (0.0, 0.0, 0.0)
    bounce: tuple = (0.0, 0.0, 0.0)
    arc_voltage: float = 30.0
    dip: float = 0.0
    x_over_r: float = 3.0
    duration: float = 1.0
    kind: str = "dol"

    def meta(self, Ts: float) -> dict:
        return {"input_hold": "linear", "supply_frequency": float(self.f)}

    def samples(self, Ts: float) -> int:
        return int(round((self.pre_trigger + self.duration) / Ts))

    def source_impedance(self, Z_locked: float) -> tuple[float, float]:
        """``(R_g, L_g)`` (ohm, H) giving the dip at the locked-rotor impedance magnitude."""
        Z = self.dip * Z_locked
        phi = math.atan(self.x_over_r)
        return Z * math.cos(phi), Z * math.sin(phi) / (2 * math.pi * self.f)

    def pack(self, R_g: float, R_open: float, i_arc: float) -> np.ndarray:
        harm = [(5.0, self.h5, self.phase5), (7.0, self.h7, self.phase7)]
        harm = [h for h in harm if h[1] != 0]
        out = np.zeros(G_H + 3 * len(harm))
        out[G_V], out[G_W], out[G_PHI] = self.V * math.sqrt(2 / 3), 2 * math.pi * self.f, self.phase0
        out[G_U:G_U + 3] = self.unbalance
        out[G_RG], out[G_ROPEN], out[G_UARC], out[G_IARC], out[G_NH] = R_g, R_open, self.arc_voltage, i_arc, len(harm)
        for k, (order, amp, ph) in enumerate(harm):
            out[G_H + 3 * k:G_H + 3 * k + 3] = order, amp, ph
        return out

    def close_times(self) -> np.ndarray:
        return self.pre_trigger + np.asarray(self.stagger, float)

    def startup(self, Ts: float, M: int, K: int, grid: np.ndarray, sub_open: int) -> Drive:
        h = Ts / M
        n = K * M
        t = np.arange(n) * h
        drv = _empty(n, h, MODE_GRID, grid=grid)
        tc = self.close_times()
        drv.closed[:] = (t[:, None] >= tc[None, :] - 1e-9 * h).astype(float)
        drv.arc[:] = drv.closed * (t[:, None] < (tc + np.asarray(self.bounce, float))[None, :]).astype(float)
        nclosed = drv.closed.sum(axis=1)
        drv.mode[nclosed < 2] = MODE_OPEN
        drv.sub[nclosed == 2] = sub_open
        return drv

    def describe(self) -> dict:
        d = asdict(self)
        for k in ("unbalance", "stagger", "bounce"):
            d[k] = [float(x) for x in d[k]]
        return d


def _sample_gates(S: np.ndarray, Ts: float, M: int, inverter: np.ndarray) -> Drive:
    """Drive of gate states held per sample (S: K x 3, 0/1); gates are off before t = 0."""
    K = len(S)
    n = K * M
    drv = _empty(n, Ts / M, MODE_INVERTER, inverter=inverter)
    drv.u[:] = np.repeat(S, M, axis=0)
    prev = np.vstack([np.zeros((1, 3)), S[:-1]])
    ch = S - prev
    idx = np.arange(K) * M
    drv.nr[idx] = (ch > 0).astype(float)
    drv.nf[idx] = (ch < 0).astype(float)
    drv.v_ideal = _clarke_rows(inverter[0] * drv.u)
    return drv


def stop_drive(scenario, Ts: float, M: int, K: int, last_gates, inverter: np.ndarray, grid: np.ndarray) -> Drive:
    """The free stop: zero vector 111 for inverters (edges for the phases that were off),
    open contactor for the grid."""
    n = K * M
    if scenario.kind == "dol":
        return _empty(n, Ts / M, MODE_OPEN, grid=grid)
    S = np.ones((K, 3))
    drv = _sample_gates(S, Ts, M, inverter)
    drv.nr[0] = (np.asarray(last_gates) < 0.5).astype(float)
    return drv


@njit(cache=True)
def grid_emf(t, gp, e):
    """Phase EMFs (V) of the grid at time ``t`` into ``e`` (3,)."""
    nh = int(gp[G_NH])
    for k in range(3):
        ang = gp[G_W] * t + gp[G_PHI] - 2.0 * math.pi * k / 3.0
        val = (1.0 + gp[G_U + k]) * math.cos(ang)
        for q in range(nh):
            o = G_H + 3 * q
            val += gp[o + 1] * math.cos(gp[o] * ang + gp[o + 2])
        e[k] = gp[G_V] * val
