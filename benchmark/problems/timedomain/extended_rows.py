"""Parameter rows of the extended model (:mod:`benchmark.problems.timedomain.extended`).

A row holds every field of :data:`EXTENDED_FIELDS` in order (SI units). Neutral values (zero
for every effect term, the base model's reference values elsewhere) make the base model of
:mod:`benchmark.problems.timedomain.motor`; new fields are appended so that indices stay stable.
"""

from __future__ import annotations

import numpy as np

from benchmark.core.constants import COPPER_INFERRED_ZERO_C
from benchmark.problems.timedomain.motor import InductionMotor

#: Fields of an extended parameter row, in order. Neutral values make the base model.
EXTENDED_FIELDS = (
    "Rs",  # ohm, stator resistance
    "L_sigma",  # H, leakage inductance (= Le)
    "L_M",  # H, magnetising inductance of the inverse-Gamma model (= Ls - Le)
    "R_r1",  # ohm, rotor cage 1 (inverse-Gamma referred)
    "R_r2",  # ohm, rotor cage 2; 0 = absent
    "L_sigma2",  # H, leakage of cage 2
    "g_fe",  # S, iron-loss conductance on the magnetising node; 0 = none
    "ms_k",  # -, main saturation: extra magnetising current at ms_psi (fraction)
    "ms_psi",  # Wb, main saturation reference flux
    "ms_exp",  # -, main saturation exponent
    "ls_k",  # -, leakage saturation: extra stator current at ls_psi (fraction)
    "ls_psi",  # Wb, leakage saturation reference flux linkage
    "ls_exp",  # -, leakage saturation exponent
    "U_d",  # V, inverter voltage drop per phase
    "i_0",  # A, current scale of the drop's sign change (0: hard sign)
    "h_th",  # K/J, temperature rise per joule of copper loss; 0 = constant temperature
    "alpha_th",  # 1/K, copper temperature coefficient 1/(234.5 + theta_ref)
    "J",  # kg m^2
    "fv",  # N m s
    "fc",  # N m
    "p",  # pole pairs
    # --- bench effects (appended: the indices above are stable) ---
    "v_off_a",  # V, DC offset of the recorded alpha voltage (the motor sees v - v_off)
    "v_off_b",  # V, DC offset of the recorded beta voltage
    "ms_k2",  # -, main saturation: weight of the second power term
    "ms_exp2",  # -, main saturation: exponent of the second power term
    "T_L",  # N m, constant passive load torque
    "T_q",  # N m, quadratic load torque at w_ref
    "w_ref",  # rad/s (mechanical), speed at which the quadratic load reaches T_q
    "T_s",  # N m, passive load torque stepping on at t_step
    "t_step",  # s, instant of the step load
    "t_rise",  # s, width of the smooth step (0: hard)
    "J_l",  # kg m^2, load inertia of a two-mass shaft; 0 = rigid (single mass J)
    "k_sh",  # N m/rad, torsional stiffness of the coupling
    "c_sh",  # N m s/rad, coupling damping
    "g_fe_s",  # S, iron-loss conductance across the stator EMF (terminals after Rs); 0 = none
    "ls_floor",  # -, leakage saturation: share of the leakage that never saturates (0: none)
    "t_split",  # -, Llr/Lls of the T circuit whose magnetising node saturates (0: the inverse-Gamma node)
    "backlash",  # rad, half-width of a two-mass coupling's free play (0: none)
    "th_rotor",  # -, rotor temperature rise per stator rise, less 1 (0: both windings rise alike)
    "R_r3",  # ohm, rotor loop 3 (a deep bar's third current path); 0 = absent
    "L_sigma3",  # H, leakage of rotor loop 3
    "T_s_speed",  # -, share of the switched load T_s proportional to speed (w/w_ref: a DC generator on a resistor)
    "tau_s",  # s, first-order rise (and fall) of the switched load and lag of its speed share (an armature); 0: t_rise
    "t_step_off",  # s, instant the switched load is switched off again (at or before t_step: never)
    "k_cubic",  # 1/rad^2, a hardening coupling's cubic term: torque k z (1 + k_cubic z^2) (0: linear spring)
    "r_crit",  # -, w_ref over the critical speed of the switched load's speed share (an eddy-current brake); 0: linear
)
N_EXT = len(EXTENDED_FIELDS)
IDX = {name: k for k, name in enumerate(EXTENDED_FIELDS)}

def base_row(motor: InductionMotor | dict) -> np.ndarray:
    """Extended parameter row of a base-model parameter set (every effect neutral)."""
    m = motor if isinstance(motor, dict) else motor.as_dict()
    row = np.zeros(N_EXT)
    Ls, Le = m["Ls"], m["Le"]
    row[IDX["Rs"]] = m["Rs"]
    row[IDX["L_sigma"]] = Le
    row[IDX["L_M"]] = Ls - Le
    row[IDX["R_r1"]] = m["Rr"] * (Ls - Le) / Ls
    row[IDX["ms_psi"]] = 1.0
    row[IDX["ms_exp"]] = 2.0
    row[IDX["ls_psi"]] = 1.0
    row[IDX["ls_exp"]] = 2.0
    row[IDX["alpha_th"]] = 1.0 / (COPPER_INFERRED_ZERO_C + 20.0)
    row[IDX["J"]] = m["J"]
    row[IDX["fv"]] = m["fv"]
    row[IDX["fc"]] = m["fc"]
    row[IDX["p"]] = m.get("p", 1)
    row[IDX["ms_exp2"]] = 2.0
    row[IDX["w_ref"]] = 1.0
    return row


def base_rows(theta: np.ndarray, p: int) -> np.ndarray:
    """Vectorised :func:`base_row` for physical parameter rows (n, 7) in PARAMETER_NAMES order."""
    theta = np.atleast_2d(theta)
    Rs, Ls, Le, Rr, J, fv, fc = theta.T
    rows = np.zeros((len(theta), N_EXT))
    rows[:, IDX["Rs"]] = Rs
    rows[:, IDX["L_sigma"]] = Le
    rows[:, IDX["L_M"]] = Ls - Le
    with np.errstate(all="ignore"):
        rows[:, IDX["R_r1"]] = Rr * (Ls - Le) / Ls
    rows[:, IDX["ms_psi"]] = 1.0
    rows[:, IDX["ms_exp"]] = 2.0
    rows[:, IDX["ls_psi"]] = 1.0
    rows[:, IDX["ls_exp"]] = 2.0
    rows[:, IDX["alpha_th"]] = 1.0 / (COPPER_INFERRED_ZERO_C + 20.0)
    rows[:, IDX["J"]] = J
    rows[:, IDX["fv"]] = fv
    rows[:, IDX["fc"]] = fc
    rows[:, IDX["p"]] = p
    rows[:, IDX["ms_exp2"]] = 2.0
    rows[:, IDX["w_ref"]] = 1.0
    bad = ~((Le > 0) & (Ls > Le) & (Rs > 0) & (Rr > 0) & (J > 0) & (fv >= 0) & (fc >= 0))
    rows[bad] = np.nan
    return rows


def valid_rows(rows: np.ndarray) -> np.ndarray:
    """Mask of physically valid extended rows."""
    r = rows
    ok = np.all(np.isfinite(r), axis=1)
    for name in ("Rs", "L_sigma", "L_M", "R_r1", "J", "ms_psi", "ls_psi"):
        ok &= r[:, IDX[name]] > 0
    for name in ("R_r2", "R_r3", "g_fe", "ms_k", "ls_k", "U_d", "i_0", "h_th", "fv", "fc", "ms_k2", "T_L", "T_q", "T_s",
                 "t_rise", "J_l", "k_sh", "c_sh", "g_fe_s", "ls_floor", "backlash", "T_s_speed", "tau_s",
                 "k_cubic", "r_crit"):
        ok &= r[:, IDX[name]] >= 0
    ok &= r[:, IDX["ls_floor"]] < 1
    ok &= r[:, IDX["t_split"]] >= 0
    ok &= r[:, IDX["th_rotor"]] >= -1
    ok &= (r[:, IDX["R_r2"]] == 0) | (r[:, IDX["L_sigma2"]] > 0)
    ok &= (r[:, IDX["R_r3"]] == 0) | (r[:, IDX["L_sigma3"]] > 0)
    ok &= r[:, IDX["w_ref"]] > 0
    ok &= (r[:, IDX["J_l"]] == 0) | (r[:, IDX["k_sh"]] > 0)
    return ok
