"""Shaft mechanics: one rigid mass, or motor and load coupled by a torsional spring.

States (mechanical rad/s and rad): ``w_m`` motor speed, ``w_l`` load speed (the speed the
sensor sees), ``twist`` coupling angle ``theta_m - theta_l``, ``theta`` angle of the sensed
shaft (for ripple at the rotation frequency), and ``i_a`` the armature current of a DC
generator load (A; zero for the other loads).

Friction on the motor shaft: viscous ``fv w_m`` and Coulomb ``fc sign(w_m)``. Stiction: a
shaft at standstill stays put while the torque driving it is within its Coulomb torque
(the resisting torque is the driving torque clipped to ``+-fc``); after each integration
step a speed that crossed zero is set to zero, so that it sticks or breaks away again.
Held-out form ``bearing``: the friction of rolling bearings and seals, a load-dependent
torque ``fc`` plus Palmgren's hydrodynamic term ``c_p |w|^(2/3)`` (Palmgren, Ball and Roller
Bearing Engineering, 1959; the SKF catalogue's ``M_0 ~ (nu n)^(2/3)``), with a Stribeck
breakaway at standstill: the level ``fc + (fs - fc) exp(-(w/w_s)^2) + c_p |w|^(2/3)``
(Stribeck's curve as in Armstrong-Helouvry, Dupont, Canudas de Wit, Automatica 30(7),
1994); standstill holds up to ``fs``.

Load torque (on the load side, or on the single mass): ``constant`` (passive: it opposes
motion and acts like Coulomb friction), ``quadratic`` ``T_L (w/w_ref)^2`` (fan, pump),
``step`` (a passive constant torque applied from ``t_step`` on) or, held out,
``dc_generator``: a separately excited DC machine whose armature is closed on a resistor at
``t_step``; torque ``k_e i_a`` with ``L_a di_a/dt = k_e w - R_a i_a - U_b tanh(i_a/i_b)``
(EMF, circuit resistance, brush drop; e.g. Fitzgerald, Kingsley, Umans, Electric Machinery,
ch. 7). At standstill (no EMF) it gives no torque; after the switch its torque rises with
the armature time constant ``L_a/R_a`` towards ``k_e^2 w/R_a``. Retired from the held-out forms
(the diagnosis's DC machine has the armature's lag since); held out in its place,
``eddy_brake``: an eddy-current brake (a test bench's dynamometer), its excitation switched on
at ``t_step``, ``T = T_k (i_f/I_f)^2 2 (w/w_k)/(1 + (w/w_k)^2)``: the torque-speed law of an
eddy-current brake with a critical speed ``w_k`` where its torque peaks at ``T_k`` (Wouterse,
IEE Proc. B 138(4), 1991), times the square of the excitation current, which rises with the
field winding's time constant ``tau_f`` (``i_f/I_f = 1 - exp(-(t - t_step)/tau_f)``).
Retired too (the diagnosis's load has the brake's law since); held out in its place,
``battery_charger``: a permanent-magnet generator charging a battery through a diode bridge,
connected at ``t_step``. Its EMF ``k_e w`` drives a current only above the battery's voltage
plus the diodes' drop, ``U_c = k_e w_c``; then ``i = (k_e |w| - U_c)/R`` through the
circuit's resistance, so ``T = T_L (|w| - w_c)/(w_ref - w_c)`` above the cut-in speed ``w_c``
and 0 below it (the generator's inductance neglected: its time constant is short beside a
start's; e.g. a small wind turbine's charging curve, Manwell, McGowan, Rogers, Wind Energy
Explained, 2009, ch. 5).

Two-mass coupling torque ``T_sh = k dz(twist) + c (w_m - w_l)`` with ``dz`` a dead zone of
half-width ``backlash`` (rad; 0 = linear spring); no damping torque in the free play.
Held-out form ``elastomer`` (``twist_ref`` > 0): a progressive elastomer coupling (jaw
coupling with a polyurethane spider, whose dynamic stiffness rises with the transmitted
torque), ``T_sh = k (z + z^3/(3 z_r^2)) + c sqrt(1 + (z/z_r)^2) (w_m - w_l)``: the
incremental stiffness ``k (1 + (z/z_r)^2)`` hardens with the twist and the damping follows
its square root (a constant damping ratio, i.e. the material's loss factor); retired (the
diagnosis's coupling has this hardening since). Held-out form ``slip_clutch``
(``slip_torque`` > 0): a friction torque limiter (slip hub) in series with the spring, set at
``T_lim``: the spring's torque ``k z`` cannot pass it; while it is there and the halves keep
moving apart, the hub slips and the twist stays (a Jenkins element: ``dz/dt = w_m - w_l``
unless ``|k z| >= T_lim`` with the slip in its direction, then 0), the damper across the whole
coupling, ``T_sh = min(max(k z, -T_lim), T_lim) + c (w_m - w_l)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

LOADS = ("none", "constant", "quadratic", "step", "dc_generator", "eddy_brake", "battery_charger")
(M_JM, M_JL, M_FV, M_FC, M_K, M_C, M_BL, M_TWO, M_LOAD, M_TL, M_WREF, M_TSTEP, M_FS, M_WS, M_KE, M_RA, M_LA, M_UB,
 M_IB, M_ZR, M_PG, M_TS, M_BK, M_BW, M_BF, M_WC) = range(26)
N_MECH = 5  # states: w_m, w_l, twist, theta, i_a


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
    t_step : instant of a step load (or of a DC generator's armature switch), s.
    breakaway : Stribeck breakaway torque ``fs``, N m (0: plain Coulomb friction).
    stribeck_speed : Stribeck speed ``w_s``, mechanical rad/s.
    palmgren : Palmgren coefficient ``c_p``, N m (rad/s)^(-2/3).
    generator : DC generator ``(k_e V s/rad, R_a ohm, L_a H, U_b V, i_b A)`` (load ``dc_generator``).
    twist_ref : elastomer hardening twist ``z_r``, rad (0: linear spring).
    slip_torque : torque ``T_lim`` at which a slip hub in series with the spring slips, N m (0: none).
    brake : eddy-current brake ``(T_k N m, w_k rad/s, tau_f s)``: peak torque, critical speed,
        field time constant (load ``eddy_brake``).
    cut_in_speed : speed ``w_c`` below which a battery charger's diodes block, mechanical rad/s
        (load ``battery_charger``; ``load_torque`` is then its torque at ``w_ref``).
    """

    J_load: float = 0.0
    stiffness: float = 0.0
    damping: float = 0.0
    backlash: float = 0.0
    load: str = "none"
    load_torque: float = 0.0
    w_ref: float = 1.0
    t_step: float = 0.0
    breakaway: float = 0.0
    stribeck_speed: float = 1.0
    palmgren: float = 0.0
    generator: tuple = (0.0, 1.0, 1.0, 0.0, 1.0)
    twist_ref: float = 0.0
    slip_torque: float = 0.0
    brake: tuple = (0.0, 1.0, 1.0)
    cut_in_speed: float = 0.0

    def __post_init__(self):
        if self.load not in LOADS:
            raise ValueError(f"load must be one of {LOADS}, got {self.load!r}")
        if self.stiffness > 0 and not self.J_load > 0:
            raise ValueError("a two-mass shaft needs J_load > 0")
        if self.load == "battery_charger" and not 0.0 <= self.cut_in_speed < self.w_ref:
            raise ValueError(f"battery_charger: cut_in_speed must be in [0, w_ref = {self.w_ref:.4g} rad/s), "
                             f"got {self.cut_in_speed:.4g} (its torque is linear from the cut-in to w_ref)")

    @property
    def two_mass(self) -> bool:
        return self.stiffness > 0

    def resonance(self, J_motor: float) -> float:
        """Torsional resonance ``sqrt(k (1/J_m + 1/J_l)) / 2 pi``, Hz (0 when rigid)."""
        if not self.two_mass:
            return 0.0
        return math.sqrt(self.stiffness * (1 / J_motor + 1 / self.J_load)) / (2 * math.pi)

    def pack(self, J: float, fv: float, fc: float) -> np.ndarray:
        out = np.zeros(26)
        out[M_JM], out[M_JL], out[M_FV], out[M_FC] = J, self.J_load, fv, fc
        out[M_K], out[M_C], out[M_BL], out[M_TWO] = self.stiffness, self.damping, self.backlash, float(self.two_mass)
        out[M_LOAD], out[M_TL] = LOADS.index(self.load), self.load_torque
        out[M_WREF], out[M_TSTEP] = self.w_ref, self.t_step
        out[M_FS], out[M_WS], out[M_PG] = self.breakaway, self.stribeck_speed, self.palmgren
        out[M_KE:M_IB + 1] = self.generator
        out[M_ZR] = self.twist_ref
        out[M_TS] = self.slip_torque
        out[M_BK:M_BF + 1] = self.brake
        out[M_WC] = self.cut_in_speed
        return out

    def armature_time_constant(self) -> float:
        """``L_a/R_a`` of a DC generator load, s (0 for the other loads)."""
        return self.generator[2] / self.generator[1] if self.load == "dc_generator" else 0.0


@njit(cache=True)
def _coulomb(w, mech):
    """Coulomb torque level of the motor shaft at speed ``w`` (the ``bearing`` law when
    ``breakaway`` is set), N m."""
    if mech[M_FS] == 0.0:
        return mech[M_FC]
    q = w / mech[M_WS]
    return mech[M_FC] + (mech[M_FS] - mech[M_FC]) * math.exp(-q * q) + mech[M_PG] * abs(w) ** (2.0 / 3.0)


@njit(cache=True)
def _generator(t, w, ia, mech, dx, k):
    """Torque of a DC generator load (N m) at load speed ``w`` and armature current ``ia``;
    writes ``d i_a/dt`` into ``dx[k]`` (zero before the armature switch, or another load)."""
    if int(mech[M_LOAD]) != 4 or t < mech[M_TSTEP]:
        dx[k] = 0.0
        return 0.0
    ke = mech[M_KE]
    dx[k] = (ke * w - mech[M_RA] * ia - mech[M_UB] * math.tanh(ia / mech[M_IB])) / mech[M_LA]
    return ke * ia


@njit(cache=True)
def _spring(tw, dw, mech):
    """Coupling torque at twist ``tw`` (rad) and speed difference ``dw`` (rad/s), N m."""
    bl = mech[M_BL]
    zr = mech[M_ZR]
    if zr > 0.0:
        q = tw / zr
        return mech[M_K] * tw * (1.0 + q * q / 3.0) + mech[M_C] * math.sqrt(1.0 + q * q) * dw
    ts = mech[M_TS]
    if ts > 0.0:
        return min(max(mech[M_K] * tw, -ts), ts) + mech[M_C] * dw
    if tw > bl:
        return mech[M_K] * (tw - bl) + mech[M_C] * dw
    if tw < -bl:
        return mech[M_K] * (tw + bl) + mech[M_C] * dw
    return 0.0


@njit(cache=True)
def _twist_rate(tw, dw, mech):
    """``d twist/dt`` (rad/s) at twist ``tw`` and speed difference ``dw``: ``dw``, or 0 while a
    slip hub slips (its spring at the limit and the halves moving further apart)."""
    ts = mech[M_TS]
    if ts > 0.0:
        tk = mech[M_K] * tw
        if (tk >= ts and dw > 0.0) or (tk <= -ts and dw < 0.0):
            return 0.0
    return dw


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
    if code == 5 and t >= mech[M_TSTEP]:  # eddy-current brake: its law times the excitation squared
        field = 1.0 - math.exp(-(t - mech[M_TSTEP]) / mech[M_BF])
        q = w / mech[M_BW]
        return 0.0, mech[M_BK] * field * field * 2.0 * q / (1.0 + q * q)
    if code == 6 and t >= mech[M_TSTEP]:  # battery charger: no current below the cut-in speed, then linear
        over = abs(w) - mech[M_WC]
        if over > 0.0:
            return 0.0, math.copysign(mech[M_TL] * over / (mech[M_WREF] - mech[M_WC]), w)
    return 0.0, 0.0


@njit(cache=True)
def mech_derivatives(t, x, b, Te, mech, dx):
    """Write the derivatives of ``x[b:b+5]`` (w_m, w_l, twist, theta, i_a) into ``dx``;
    return the shaft torque transmitted to the load, N m."""
    wm = x[b]
    fv = mech[M_FV]
    fc = _coulomb(wm, mech)
    if mech[M_TWO] == 0.0:
        tcl, tdyn = _loads(t, wm, mech)
        tdyn += _generator(t, wm, x[b + 4], mech, dx, b + 4)
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
    tsh = _spring(x[b + 2], wm - wl, mech)
    drive_m = Te - tsh - fv * wm
    dx[b] = (drive_m - _resist(wm, drive_m, fc)) / mech[M_JM]
    tcl, tdyn = _loads(t, wl, mech)
    tdyn += _generator(t, wl, x[b + 4], mech, dx, b + 4)
    drive_l = tsh - tdyn
    dx[b + 1] = (drive_l - _resist(wl, drive_l, tcl)) / mech[M_JL]
    dx[b + 2] = _twist_rate(x[b + 2], wm - wl, mech)
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
    """Coast with no electromagnetic torque: RK4 on ``x4`` = (w_m, w_l, twist, theta, i_a)
    with step ``h``; ``out[k] = (w_l, theta)`` every ``every`` steps (``out[0]`` the start)."""
    ns = x4.shape[0]
    k1 = np.zeros(ns)
    k2 = np.zeros(ns)
    k3 = np.zeros(ns)
    k4 = np.zeros(ns)
    xs = np.zeros(ns)
    xo = np.zeros(ns)
    m = 0
    for j in range(nsteps + 1):
        if j % every == 0:
            out[m, 0] = x4[1]
            out[m, 1] = x4[3]
            m += 1
        if j == nsteps:
            break
        t = t0 + j * h
        if x4[0] == 0.0 and x4[1] == 0.0 and x4[2] == 0.0 and x4[4] == 0.0 and mech[M_LOAD] != 3.0:
            continue  # at rest with nothing driving it: stays at rest
        xo[:] = x4
        mech_derivatives(t, x4, 0, 0.0, mech, k1)
        for i in range(ns):
            xs[i] = x4[i] + 0.5 * h * k1[i]
        mech_derivatives(t + 0.5 * h, xs, 0, 0.0, mech, k2)
        for i in range(ns):
            xs[i] = x4[i] + 0.5 * h * k2[i]
        mech_derivatives(t + 0.5 * h, xs, 0, 0.0, mech, k3)
        for i in range(ns):
            xs[i] = x4[i] + h * k3[i]
        mech_derivatives(t + h, xs, 0, 0.0, mech, k4)
        for i in range(ns):
            x4[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        stick(xo, x4, 0, t + h, mech)
    return m
