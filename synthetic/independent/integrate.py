"""Fixed-step integrator of the plant (numba), and the free stop.

Classical 4th-order Runge-Kutta on all states (fluxes, speeds, angles, temperatures) with a
step ``h = Ts / M`` several times shorter than the output sample time ``Ts`` (``M`` is chosen
so that ``h |lambda_max| <= 2`` for the fastest linearised electrical mode, and at least the
requested oversampling). Steps in which a contactor pole is open while two are closed are
split into ``sub`` sub-steps, since the open pole's resistance makes that mode stiff. The
inverter's pole voltages are held over each step (exact volt-seconds of the gate pattern);
the grid EMF is evaluated at each Runge-Kutta stage time.

How this differs from the identification model: the states are the winding flux linkages
(not stator currents and rotor flux), the currents come from an algebraic solve, there can
be any number of rotor loops and extra windings, the step is a fraction of the sample time
(not the sample time) with the input applied as the physics dictates (gate patterns, a
continuous EMF), and the record is picked from this finer trajectory.

The trajectory is recorded at every step start (row ``j`` at ``t0 + j h``) in the columns
:data:`OUT_COLS`: stator current (A), recorded terminal voltage of grid steps (V; filled
later for the other modes), motor and sensed speed (rad/s), shaft and air-gap torque (N m),
sensed-shaft angle (rad), winding temperatures (C), stator flux (Wb), rotor current
magnitude (A), stator and rotor copper loss (W).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from synthetic.independent.electrical import W_IR, W_LOOPS, W_PSIM, flux_derivatives, rotor_loss, solve_currents, torque
from synthetic.independent.inverter import applied_voltage, clarke, phase_currents
from synthetic.independent.mechanics import N_MECH, mech_derivatives, run_free, stick
from synthetic.independent.plant import E_ALPHA, E_C, E_IH, E_INVLFE, E_P, E_PSIREF, E_RFE, E_RS, Plant
from synthetic.independent.supply import (
    G_IARC,
    G_RG,
    G_ROPEN,
    G_UARC,
    MODE_GRID,
    MODE_INVERTER,
    MODE_OPEN,
    Drive,
    grid_emf,
)
from synthetic.independent.thermal import resistance_factors, thermal_derivatives

OUT_COLS = ("i_a", "i_b", "v_a", "v_b", "w_m", "w_l", "T_sh", "T_e", "theta", "theta_s", "theta_r", "psi_a",
            "psi_b", "i_rotor", "P_s", "P_r")
COL = {name: k for k, name in enumerate(OUT_COLS)}


@njit(cache=True)
def _rhs(t, x, dx, mode, va, vb, closed, arc, gp, n, el, stat, rot, mag, Rr, Linv, wv, mech, therm, im, cw, e3):
    """All state derivatives; leaves currents, the applied voltage and torques in ``cw``."""
    open_st = mode == MODE_OPEN
    it = solve_currents(x, n, open_st, stat, rot, mag, Linv, wv, el[E_C], el[E_INVLFE], im, cw)
    b = 4 + 2 * n
    bt = b + N_MECH
    ks, kr = resistance_factors(x[bt], x[bt + 1], therm)
    Rs = el[E_RS] * ks
    isa = cw[0]
    isb = cw[1]
    if mode == MODE_GRID:
        grid_emf(t, gp, e3)
        i3 = phase_currents(isa, isb)
        for k in range(3):
            i = i3[k]
            drop = gp[G_RG] * i + (1.0 - closed[k]) * gp[G_ROPEN] * i
            if arc[k] != 0.0:
                drop += gp[G_UARC] * math.tanh(i / gp[G_IARC])
            e3[k] -= drop
        va, vb = clarke(e3[0], e3[1], e3[2])
    v = W_LOOPS + 2 * n
    cw[v] = va
    cw[v + 1] = vb
    ih = 0.0
    if el[E_IH] > 0.0:  # Steinmetz iron loss: the coercive current at this main flux
        ih = el[E_IH] * (math.hypot(cw[W_PSIM], cw[W_PSIM + 1]) / el[E_PSIREF]) ** (el[E_ALPHA] - 1.0)
    flux_derivatives(x, n, el[E_P] * x[b], va, vb, Rs, Rr, kr, el[E_RFE], ih, open_st, cw, dx)
    te = torque(el[E_P], cw)
    cw[v + 2] = te
    cw[v + 3] = mech_derivatives(t, x, b, te, mech, dx)
    cw[v + 4] = 1.5 * Rs * (isa * isa + isb * isb)
    cw[v + 5] = rotor_loss(n, Rr, kr, cw)
    thermal_derivatives(x, bt, cw[v + 4], cw[v + 5], therm, dx)
    return it


@njit(cache=True)
def run_steps(x, t0, h, mode, sub, u, nr, nf, closed, arc, gp, ip, n, el, stat, rot, mag, Rr, Linv, wv, mech,
              therm, im, out):
    """Integrate ``len(mode)`` steps from ``x`` (modified in place); ``out`` gets
    ``len(mode) + 1`` rows. Returns the number of algebraic solves that did not converge.

    One call site of the right-hand side (stage loop) keeps numba's compile time short."""
    N = mode.shape[0]
    ns = x.shape[0]
    k = np.zeros(ns)
    acc = np.zeros(ns)
    xs = np.zeros(ns)
    xo = np.zeros(ns)
    cw = np.zeros(W_LOOPS + 2 * n + 6)
    e3 = np.zeros(3)
    cs = np.array([0.0, 0.5, 0.5, 1.0])
    ws = np.array([1.0, 2.0, 2.0, 1.0]) / 6.0
    b = 4 + 2 * n
    bt = b + N_MECH
    v = W_LOOPS + 2 * n
    bad = 0
    for j in range(N + 1):
        jj = min(j, N - 1)
        m = mode[jj]
        t = t0 + j * h
        nsub = sub[jj] if j < N else 1
        hs = h / nsub
        va = 0.0
        vb = 0.0
        for q in range(nsub):
            for s in range(4):
                c = cs[s] * hs
                for i in range(ns):
                    xs[i] = x[i] + c * k[i]
                if s == 0:
                    xs[:] = x
                it = _rhs(t + q * hs + c, xs, k, m, va, vb, closed[jj], arc[jj], gp, n, el, stat, rot, mag, Rr, Linv,
                          wv, mech, therm, im, cw, e3)
                if q == 0 and s == 0:
                    if it < 0:
                        bad += 1
                    if m == MODE_OPEN:
                        # no stator current path: the stator flux is the main flux
                        x[0] = cw[W_PSIM]
                        x[1] = cw[W_PSIM + 1]
                    if m == MODE_INVERTER and j < N:
                        # pole voltages from the current at the step start, held over the step
                        va, vb = applied_voltage(u[j], nr[j], nf[j], cw[0], cw[1], ip, h)
                        k[0] += va
                        k[1] += vb
                        cw[v] = va
                        cw[v + 1] = vb
                    out[j, 0] = cw[0]
                    out[j, 1] = cw[1]
                    out[j, 2] = cw[v]
                    out[j, 3] = cw[v + 1]
                    out[j, 4] = x[b]
                    out[j, 5] = x[b + 1]
                    out[j, 6] = cw[v + 3]
                    out[j, 7] = cw[v + 2]
                    out[j, 8] = x[b + 3]
                    out[j, 9] = x[bt]
                    out[j, 10] = x[bt + 1]
                    out[j, 11] = x[0]
                    out[j, 12] = x[1]
                    out[j, 13] = math.hypot(cw[W_IR], cw[W_IR + 1])
                    out[j, 14] = cw[v + 4]
                    out[j, 15] = cw[v + 5]
                    if j == N:
                        break
                if s == 0:
                    for i in range(ns):
                        acc[i] = ws[0] * k[i]
                else:
                    for i in range(ns):
                        acc[i] += ws[s] * k[i]
            if j == N:
                break
            xo[:] = x
            for i in range(ns):
                x[i] += hs * acc[i]
            stick(xo, x, b, t + (q + 1) * hs, mech)
    return bad


@dataclass
class Trajectory:
    """Rows at every internal step start (columns :data:`OUT_COLS`), the final state and
    the solver's warm start."""

    out: np.ndarray
    x: np.ndarray
    im: np.ndarray
    h: float
    t0: float
    unconverged: int

    def col(self, name: str) -> np.ndarray:
        return self.out[:, COL[name]]


def simulate(plant: Plant, drive: Drive, x0: np.ndarray | None = None, t0: float = 0.0,
             im: np.ndarray | None = None, packed: dict | None = None) -> Trajectory:
    """Integrate the plant over the drive's steps; voltages of stator-open steps are the
    stator flux's rate of change (the terminal voltage with no current)."""
    pk = packed if packed is not None else plant.pack()
    x = plant.initial_state() if x0 is None else np.array(x0, float)
    im = np.zeros(4) if im is None else np.array(im, float)
    out = np.zeros((drive.n + 1, len(OUT_COLS)))
    bad = run_steps(x, float(t0), float(drive.h), drive.mode, drive.sub, drive.u, drive.nr, drive.nf, drive.closed,
                    drive.arc, drive.grid, drive.inverter, pk["n"], pk["el"], pk["stat"], pk["rot"], pk["mag"],
                    pk["Rr"], pk["Linv"], pk["wv"], pk["mech"], pk["therm"], im, out)
    opened = np.flatnonzero(drive.mode == MODE_OPEN)
    if len(opened):
        dpsi = np.diff(out[:, [COL["psi_a"], COL["psi_b"]]], axis=0) / drive.h
        out[opened, COL["v_a"]] = dpsi[opened, 0]
        out[opened, COL["v_b"]] = dpsi[opened, 1]
    return Trajectory(out, x, im, float(drive.h), float(t0), int(bad))


def oversampling(plant: Plant, Ts: float, requested: int) -> int:
    """Steps per sample: the requested count, or more when the plant's fastest electrical
    mode needs a shorter step for RK4 stability."""
    need = math.ceil(Ts * plant.fastest_rate() / 2.0)
    return max(int(requested), need, 1)


def coast(plant: Plant, x: np.ndarray, t0: float, duration: float, dt_out: float) -> np.ndarray:
    """Mechanics only (no electromagnetic torque) for ``duration`` s from state ``x``;
    returns rows ``(w_l, theta)`` every ``dt_out`` s, the first at ``t0``. The RK4 step is
    ``dt_out`` or less: 1/40 of the coupling's resonance period, 1/20 of the shortest
    mechanical time constant and 1/10 of a DC generator's armature time constant."""
    m = plant.machine
    mech = plant.mechanics.pack(m.J, m.fv, m.fc)
    h = dt_out
    f_res = plant.mechanics.resonance(m.J)
    if f_res > 0:
        h = min(h, 1.0 / (40 * f_res))
        if plant.mechanics.damping > 0:
            Jr = 1 / (1 / m.J + 1 / plant.mechanics.J_load)
            h = min(h, 0.05 * Jr / plant.mechanics.damping)
    if plant.mechanics.armature_time_constant() > 0:
        h = min(h, 0.1 * plant.mechanics.armature_time_constant())
    every = max(1, math.ceil(dt_out / h))
    h = dt_out / every
    steps = int(round(duration / dt_out)) * every
    b = plant.mech_offset()
    x4 = np.array(x[b:b + N_MECH], float)
    out = np.zeros((steps // every + 1, 2))
    run_free(x4, float(t0), h, steps, every, mech, out)
    return out
