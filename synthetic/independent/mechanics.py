"""Shaft mechanics: one rigid mass, or motor and load coupled by a torsional spring.

States (mechanical rad/s and rad): ``w_m`` motor speed, ``w_l`` load speed (the speed the
sensor sees), ``twist`` coupling angle ``theta_m - theta_l``, ``theta`` angle of the sensed
shaft (for ripple at the rotation frequency).

Friction on the motor shaft: viscous ``fv w_m`` and Coulomb ``fc sign(w_m)``. Stiction: a
shaft at standstill stays put while the torque driving it is within its Coulomb torque
(the resisting torque is the driving torque clipped to ``+-fc``); after each integration
step a speed that crossed zero is set to zero, so that it sticks or breaks away again.

Load torque (on the load side, or on the single mass): ``constant`` (passive: it opposes
motion and acts like Coulomb friction), ``quadratic`` ``T_L (w/w_ref)^2`` (fan, pump) or
``step`` (a passive constant torque applied from ``t_step`` on).

Two-mass coupling torque ``T_sh = k dz(twist) + c (w_m - w_l)`` with ``dz`` a dead zone of
half-width ``backlash`` (rad; 0 = linear spring); no damping torque in the free play.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

LOADS = ("none", "constant", "quadratic", "step")
M_JM, M_JL, M_FV, M_FC, M_K, M_C, M_BL, M_TWO, M_LOAD, M_TL, M_WREF, M_TSTEP = range(12)


@dataclass(frozen=True)
class Mechanics:
    """Shaft model.

    Parameters
    ----------
    J_load : load inertia, kg m^2 (two-mass only; the motor's is the machine's ``J``).
    stiffness : torsional stiffness ``k``, N m/rad; 0 = rigid (single mass).
    damping : coupling damping ``c``, N m s/rad.
    backlash : half-width of the coupling's free play, rad.
    load : one of :data:`LOADS`.
    load_torque : ``T_L``, N m.
    w_ref : speed at which the quadratic load reaches ``T_L``, mechanical rad/s.
    t_step : instant of a step load, s.
    """

    J_load: float = 0.0
    stiffness: float = 0.0
    damping: float = 0.0
    backlash: float = 0.0
    load: str = "none"
    load_torque: float = 0.0
    w_ref: float = 1.0
    t_step: float = 0.0

    def __post_init__(self):
        if self.load not in LOADS:
            raise ValueError(f"load must be one of {LOADS}, got {self.load!r}")
        if self.stiffness > 0 and not self.J_load > 0:
            raise ValueError("a two-mass shaft needs J_load > 0")

    @property
    def two_mass(self) -> bool:
        return self.stiffness > 0

    def resonance(self, J_motor: float) -> float:
        """Torsional resonance ``sqrt(k (1/J_m + 1/J_l)) / 2 pi``, Hz (0 when rigid)."""
        if not self.two_mass:
            return 0.0
        return math.sqrt(self.stiffness * (1 / J_motor + 1 / self.J_load)) / (2 * math.pi)

    def pack(self, J: float, fv: float, fc: float) -> np.ndarray:
        out = np.zeros(12)
        out[M_JM], out[M_JL], out[M_FV], out[M_FC] = J, self.J_load, fv, fc
        out[M_K], out[M_C], out[M_BL], out[M_TWO] = self.stiffness, self.damping, self.backlash, float(self.two_mass)
        out[M_LOAD], out[M_TL] = LOADS.index(self.load), self.load_torque
        out[M_WREF], out[M_TSTEP] = self.w_ref, self.t_step
        return out


@njit(cache=True)
def _resist(w, drive, tc):
    """Coulomb torque opposing motion; at standstill the driving torque clipped to +-tc."""
    if w > 0.0:
        return tc
    if w < 0.0:
        return -tc
    if drive > tc:
        return tc
    if drive < -tc:
        return -tc
    return drive


@njit(cache=True)
def _loads(t, w, mech):
    """(passive Coulomb-like load torque magnitude, speed-dependent load torque)."""
    code = int(mech[M_LOAD])
    if code == 1:
        return mech[M_TL], 0.0
    if code == 2:
        q = w / mech[M_WREF]
        return 0.0, mech[M_TL] * q * abs(q)
    if code == 3 and t >= mech[M_TSTEP]:
        return mech[M_TL], 0.0
    return 0.0, 0.0


@njit(cache=True)
def mech_derivatives(t, x, b, Te, mech, dx):
    """Write the derivatives of ``x[b:b+4]`` (w_m, w_l, twist, theta) into ``dx``; return the
    shaft torque transmitted to the load, N m."""
    wm = x[b]
    fv = mech[M_FV]
    fc = mech[M_FC]
    if mech[M_TWO] == 0.0:
        tcl, tdyn = _loads(t, wm, mech)
        drive = Te - tdyn
        res = _resist(wm, drive - fv * wm, fc + tcl)
        dw = (drive - fv * wm - res) / mech[M_JM]
        dx[b] = dw
        dx[b + 1] = dw
        dx[b + 2] = 0.0
        dx[b + 3] = wm
        share = tcl / (fc + tcl) if fc + tcl > 0.0 else 0.0
        return tdyn + share * res
    wl = x[b + 1]
    tw = x[b + 2]
    bl = mech[M_BL]
    if tw > bl:
        tsh = mech[M_K] * (tw - bl) + mech[M_C] * (wm - wl)
    elif tw < -bl:
        tsh = mech[M_K] * (tw + bl) + mech[M_C] * (wm - wl)
    else:
        tsh = 0.0
    drive_m = Te - tsh - fv * wm
    dx[b] = (drive_m - _resist(wm, drive_m, fc)) / mech[M_JM]
    tcl, tdyn = _loads(t, wl, mech)
    drive_l = tsh - tdyn
    dx[b + 1] = (drive_l - _resist(wl, drive_l, tcl)) / mech[M_JL]
    dx[b + 2] = wm - wl
    dx[b + 3] = wl
    return tsh


@njit(cache=True)
def stick(x_old, x, b, t, mech):
    """After a step: a speed that crossed zero against a Coulomb torque is set to zero."""
    if mech[M_TWO] == 0.0:
        tcl, tdyn = _loads(t, x[b], mech)
        if mech[M_FC] + tcl > 0.0 and x_old[b] * x[b] < 0.0:
            x[b] = 0.0
            x[b + 1] = 0.0
        return
    if mech[M_FC] > 0.0 and x_old[b] * x[b] < 0.0:
        x[b] = 0.0
    tcl, tdyn = _loads(t, x[b + 1], mech)
    if tcl > 0.0 and x_old[b + 1] * x[b + 1] < 0.0:
        x[b + 1] = 0.0


@njit(cache=True)
def run_free(x4, t0, h, nsteps, every, mech, out):
    """Coast with no electromagnetic torque: RK4 on ``x4`` = (w_m, w_l, twist, theta) with
    step ``h``; ``out[k] = (w_l, theta)`` every ``every`` steps (``out[0]`` the start)."""
    k1 = np.zeros(4)
    k2 = np.zeros(4)
    k3 = np.zeros(4)
    k4 = np.zeros(4)
    xs = np.zeros(4)
    xo = np.zeros(4)
    m = 0
    for j in range(nsteps + 1):
        if j % every == 0:
            out[m, 0] = x4[1]
            out[m, 1] = x4[3]
            m += 1
        if j == nsteps:
            break
        t = t0 + j * h
        if x4[0] == 0.0 and x4[1] == 0.0 and x4[2] == 0.0 and mech[M_LOAD] != 3.0:
            continue  # at rest with nothing driving it: stays at rest
        xo[:] = x4
        mech_derivatives(t, x4, 0, 0.0, mech, k1)
        for i in range(4):
            xs[i] = x4[i] + 0.5 * h * k1[i]
        mech_derivatives(t + 0.5 * h, xs, 0, 0.0, mech, k2)
        for i in range(4):
            xs[i] = x4[i] + 0.5 * h * k2[i]
        mech_derivatives(t + 0.5 * h, xs, 0, 0.0, mech, k3)
        for i in range(4):
            xs[i] = x4[i] + h * k3[i]
        mech_derivatives(t + h, xs, 0, 0.0, mech, k4)
        for i in range(4):
            x4[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        stick(xo, x4, 0, t + h, mech)
    return m
