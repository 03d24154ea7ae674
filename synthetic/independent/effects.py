"""The effect catalogue: realistic random sizes and forms, and how each changes the plant.

Effects (:class:`~synthetic.independent.effect_base.Effect`) are applied in the order of
:data:`EFFECTS`; the sensor effects live in :mod:`~synthetic.independent.sensor_effects`. Each
has development forms (the ones the diagnosis was developed on) and held-out forms (second
physical forms, for scoring only), split in :mod:`~synthetic.independent.forms`; the
equations and ranges of every form are in ``docs/effect_forms.md``. Draw ranges (``I_n``
rated current amplitude, ``T_n`` rated torque, ``f`` rated frequency, ``M`` internal steps
per sample); held-out forms marked (h):

* ``coulomb_friction`` (``coulomb``; (h) ``bearing``: Palmgren's hydrodynamic term, 0.5-2 x
  the Coulomb level at synchronous speed, and a Stribeck breakaway 1.2-2 x the Coulomb level
  below 0.5-5 rad/s): size = the plant's ``fc``, 0.3-1.5 % of ``T_n``, N m.
* ``double_cage`` (``double_cage`` two cages, ``deep_bar`` 3-6 bar slices; (h) ``tapered_bar``
  5-8 slices of a trapezoidal bar, bottom over top width 0.4-2.5): size = rotor resistance at
  ``f`` over its low-slip value, 1.3-2.2 (double cage), 1.2-1.6 (bars). When the motor's own
  rotor leakage cannot give the ratio it grows (at most 2x) and the truth holds the realised
  low-slip values; ``achieved_size`` is the realised ratio.
* ``main_saturation`` (``frohlich``, ``arctan``, ``table``; (h) ``steel_gap``: an air gap plus
  an M400-50A iron path 80-400 x the gap (log-uniform), ``langevin``): size = drop of the
  secant magnetising inductance at rated flux, 0.08-0.30 (fraction).
* ``iron_loss`` (``eddy_winding`` with an eddy time constant 0.2-1 ms, ``shunt`` = a
  resistance across the magnetising branch; (h) ``steinmetz``: hysteresis 40-70 % of the
  loss at ``f``, exponent 1.6-2.2, eddy time constant 0.2-1 ms): size = core loss at rated
  voltage, 2-6 % of rated power (fraction).
* ``leakage_saturation`` (``lorentzian``, ``frohlich``: size = ``L(6 I_n)/L(0.9 I_n)`` of the
  stator leakage (the rotor's saturable part follows the same curve), 0.45-0.75; linear
  (non-saturating) share 0.25-0.4. (h) ``closed_slot_bridge``: the rotor's leakage only,
  an iron bridge saturating at 0.15-0.5 ``I_n``, the leakage at ``0.9 I_n`` kept; size the
  same ratio of the rotor leakage.
* ``temperature_drift`` (``one_body``, ``two_body``; (h) ``three_body``: winding-to-core time
  constant 3-30 s, core 5-15 x the winding's capacity): size = stator winding temperature
  rise over the start-up record, 5-25 K (rotor 1-2x that for two or three bodies); cooling
  time constant 20-50 min.
* ``inverter_drop`` (``igbt``: threshold 0.8-2 V plus slope 0.2-1 V at ``I_n``; ``mosfet``:
  on-resistance 1-3 V at ``I_n``, body diode 0.7-1.2 V; (h) ``mosfet_capacitive``: on-resistance
  1-3 V at ``I_n`` and a capacitive dead-time transition, transition current 3-15 % of
  ``I_n``): size = device drop at ``I_n``, V; dead time 1-4 us. Inverter scenarios only.
* ``load_torque`` (``constant``, ``quadratic``, ``step`` at 30-70 % of the record;
  ``dc_generator`` (retired from the held-out forms): armature time constant 2-20 ms, EMF
  100-250 V at synchronous speed, brush drop 1-2 V, armature closed at the start or at 30-70 %
  of the record; ``eddy_brake`` (retired from the held-out forms): an eddy-current brake,
  critical speed 0.2-2 x synchronous (log-uniform), field time constant 20-200 ms
  (log-uniform), excited at the start or at 30-70 % of the record; (h) ``battery_charger``: a
  permanent-magnet generator charging a battery through a diode bridge, cut-in speed 0.3-0.8 x
  synchronous, connected at the start or at 30-70 % of the record): size = ``T_L/T_n`` (the
  generator's, the brake's and the charger's: their steady torque at synchronous speed), 0.1-1.0.
* ``two_mass`` (``spring``, ``backlash`` of 0.1-0.5 deg; ``elastomer`` (retired from the
  held-out forms): stiffness 1.5-3 x harder at rated torque; (h) ``slip_clutch``: a
  friction torque limiter in series with the spring, slipping at 0.7-1.8 x the rated torque (set to
  spare the load machine the starting torque)):
  size = (small-twist) torsional resonance, 30-200 Hz (log-uniform);
  load inertia 0.3-2 x the motor's; damping ratio 0.02-0.1.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from synthetic.independent.curves import M400_50A, LeakageCurve, MagnetisingCurve
from synthetic.independent.effect_base import Build, Effect, log_uniform
from synthetic.independent.forms import SWITCHED_LOADS
from synthetic.independent.inverter import Inverter
from synthetic.independent.plant import IronLoss
from synthetic.independent.rotor import RotorCage, design
from synthetic.independent.sensor_effects import (
    ChannelDelay,
    CurrentSensorSaturation,
    SensorOffset,
    SpeedSensorGain,
)
from synthetic.independent.thermal import Thermal

__all__ = ["EFFECTS", "Build", "Effect", "get_effect", "ordered"]


class CoulombFriction(Effect):
    name, unit = "coulomb_friction", "N m"

    def _draw(self, rng, motor, form):
        spec = {"size": float(rng.uniform(0.003, 0.015) * motor.rated_torque)}
        if form == "bearing":
            spec.update(breakaway_ratio=float(rng.uniform(1.2, 2.0)), stribeck_speed=float(rng.uniform(0.5, 5.0)),
                        palmgren_share=float(rng.uniform(0.5, 2.0)))
        return spec

    def _apply(self, build, spec):
        build.plant["machine"] = replace(build.machine, fc=float(spec["size"]))
        if spec["form"] == "bearing":
            fs = spec["breakaway_ratio"] * spec["size"]
            c_p = spec["palmgren_share"] * spec["size"] / build.motor.w_sync ** (2 / 3)
            build.plant["mechanics"] = replace(build.plant["mechanics"], breakaway=fs,
                                               stribeck_speed=spec["stribeck_speed"], palmgren=c_p)
            return {"breakaway": fs, "palmgren": c_p}


class DoubleCage(Effect):
    name, unit = "double_cage", "ratio R(f)/R(0)"

    def _draw(self, rng, motor, form):
        if form == "double_cage":
            return {"size": float(rng.uniform(1.3, 2.2)), "loops": 2}
        if form == "tapered_bar":
            return {"size": float(rng.uniform(1.2, 1.6)), "loops": int(rng.integers(5, 9)),
                    "taper": log_uniform(rng, 0.4, 2.5)}
        return {"size": float(rng.uniform(1.2, 1.6)), "loops": int(rng.integers(3, 7))}

    def _apply(self, build, spec):
        m = build.machine
        cage, ratio = design(spec["form"], m.Rr, m.Llr, 2 * math.pi * build.motor.frequency, spec["size"],
                             n=int(spec.get("loops", 4)), max_growth=2.0, taper=float(spec.get("taper", 1.0)))
        build.plant["rotor"] = cage
        return {"achieved_size": ratio, "loop_resistances": [float(r) for r in cage.R],
                "common_leakage": cage.common.L0}


class MainSaturation(Effect):
    name, unit = "main_saturation", "fraction"

    def _draw(self, rng, motor, form):
        spec = {"size": float(rng.uniform(0.08, 0.30))}
        if form == "steel_gap":
            spec["iron_ratio"] = log_uniform(rng, 80.0, 400.0)
        return spec

    def _apply(self, build, spec):
        m, psi = build.machine, build.motor.psi_rated
        if spec["form"] == "steel_gap":
            curve = MagnetisingCurve.steel_gap(m.Lm, psi, spec["size"], spec["iron_ratio"])
            extra = {"flux_density": psi * M400_50A[-1, 0] / curve.table[1][-1]}  # T at the rated flux
        else:
            curve, extra = MagnetisingCurve.with_drop(spec["form"], m.Lm, psi, spec["size"]), {}
        build.plant["magnetising"] = curve
        return {"Lm0": curve.Lm0, "knee": curve.knee, "Linf": curve.Linf, "psi_ref": psi, **extra}


class IronLossEffect(Effect):
    name, unit = "iron_loss", "fraction of rated power"

    def _draw(self, rng, motor, form):
        tau = float(rng.uniform(2e-4, 1e-3)) if form in ("eddy_winding", "steinmetz") else 0.0
        spec = {"size": float(rng.uniform(0.02, 0.06)), "time_constant": tau}
        if form == "steinmetz":
            spec.update(hysteresis_share=float(rng.uniform(0.4, 0.7)), exponent=float(rng.uniform(1.6, 2.2)))
        return spec

    def _apply(self, build, spec):
        mo = build.motor
        w = 2 * math.pi * mo.frequency
        E = mo.psi_rated * w
        P = spec["size"] * mo.rated_power
        tau = float(spec.get("time_constant", 0.0))
        if spec["form"] == "steinmetz":
            iron = IronLoss.steinmetz(E, w, P, spec["hysteresis_share"], tau, spec["exponent"], mo.psi_rated)
            build.plant["iron"] = iron
            return {"R_fe": iron.R, "L_fe": iron.L, "coercive_current": iron.coercive}
        Rc = 1.5 * E**2 / P
        if tau > 0:
            R = Rc / (1 + (w * tau) ** 2)
            L = tau * R
        else:
            R, L = Rc, 0.01 * build.machine.Lls  # a resistance across the magnetising branch
        build.plant["iron"] = IronLoss(R, L)
        return {"R_fe": R, "L_fe": L, "Rc_equivalent": Rc}


class LeakageSaturation(Effect):
    name, unit = "leakage_saturation", "ratio L(6 In)/L(0.9 In)"

    def _draw(self, rng, motor, form):
        if form == "closed_slot_bridge":
            return {"size": float(rng.uniform(0.45, 0.75)), "knee_fraction": float(rng.uniform(0.15, 0.5))}
        return {"size": float(rng.uniform(0.45, 0.75)), "linear_share": float(rng.uniform(0.25, 0.4))}

    def _apply(self, build, spec):
        m, mo = build.machine, build.motor
        lo, hi = 0.9 * mo.rated_current_peak, 6.0 * mo.rated_current_peak
        if spec["form"] == "closed_slot_bridge":
            return _bridge(build, spec, lo, hi)
        a = float(spec["linear_share"])
        stat = LeakageCurve.with_ratio(spec["form"], m.Lls, lo, hi, spec["size"], a)
        build.plant["stator_leakage"] = stat
        cage = build.plant.get("rotor") or RotorCage.single(m.Rr, m.Llr)
        if cage.n == 1:
            tot = LeakageCurve.with_ratio(spec["form"], m.Llr, lo, hi, spec["size"], a)
            cage = RotorCage(cage.R, ((tot.L_lin,),), LeakageCurve(spec["form"], 0.0, tot.L_sat, tot.knee))
        else:  # the common path (slot opening, end ring) of a multi-loop rotor saturates
            ladder = 1.0 / float(np.sum(np.linalg.inv(cage.L_array)))
            sat = min(cage.common.L0, 7.0 * ladder)  # keeps the rotor's flux rising with current
            cage = replace(cage, common=LeakageCurve(spec["form"], cage.common.L0 - sat, sat, stat.knee))
        build.plant["rotor"] = cage
        Lr_lo, Lr_hi = (_rotor_leakage(cage, i) for i in (lo, hi))
        s_lo, s_hi = stat.inductance([lo, hi])
        return {"achieved_size": float(s_hi / s_lo), "stator_knee": stat.knee, "rotor_knee": cage.common.knee,
                "rotor_ratio": Lr_hi / Lr_lo}


def _rotor_leakage(cage: RotorCage, i: float) -> float:
    """Low-slip rotor leakage (H) with the common path at current ``i``."""
    return cage.low_slip()[1] - cage.common.L0 + float(cage.common.inductance(i)[0])


def _bridge(build: Build, spec: dict, lo: float, hi: float) -> dict:
    """A closed rotor slot's bridge (leakage form ``bridge``, knee ``knee_fraction I_n``) in
    series with the rotor current, the stator's leakage linear: its saturable leakage ``L_b``
    and the linear rotor leakage are set so that the rotor leakage at ``lo`` is the motor's
    (a locked-rotor test at rated current measured it) and falls to ``size`` times that at
    ``hi``: with ``phi(i) = i_k tanh(i/i_k)/i``, ``L_b = L (1 - size)/(phi(lo) - phi(hi))``. A
    multi-loop rotor whose common path is shorter than ``L_b phi(lo)`` gets the bridge on top of
    its ladder (``L_ladder``), ``L_b = L_ladder (1 - size)/(size phi(lo) - phi(hi))``: the ratio
    is kept, the leakage at ``lo`` grows."""
    m = build.machine
    knee = spec["knee_fraction"] * build.motor.rated_current_peak
    phi_lo, phi_hi = (knee * math.tanh(i / knee) / i for i in (lo, hi))
    cage = build.plant.get("rotor") or RotorCage.single(m.Rr, m.Llr)
    total = cage.low_slip()[1]
    L_b = total * (1 - spec["size"]) / (phi_lo - phi_hi)
    if cage.n == 1:  # the linear leakage lives in the loop, the bridge in the common path
        lin = max(total - L_b * phi_lo, 0.02 * total)
        cage = RotorCage(cage.R, ((lin,),), LeakageCurve("bridge", 0.0, L_b, knee))
    elif cage.common.L0 >= L_b * phi_lo:  # the bridge replaces part of the common path
        cage = replace(cage, common=LeakageCurve("bridge", cage.common.L0 - L_b * phi_lo, L_b, knee))
    else:  # a deep rotor ladder leaves no room: the bridge comes on top, sized for the ratio
        ladder = total - cage.common.L0
        L_b = ladder * (1 - spec["size"]) / (spec["size"] * phi_lo - phi_hi)
        cage = replace(cage, common=LeakageCurve("bridge", 0.0, L_b, knee))
    build.plant["rotor"] = cage
    Lr_lo, Lr_hi = (_rotor_leakage(cage, i) for i in (lo, hi))
    return {"achieved_size": Lr_hi / Lr_lo, "rotor_knee": knee, "bridge_leakage": L_b,
            "rotor_leakage_unsaturated": cage.low_slip()[1]}


class TemperatureDrift(Effect):
    name, unit = "temperature_drift", "K"

    def _draw(self, rng, motor, form):
        spec = {"size": float(rng.uniform(5.0, 25.0)), "rotor_factor": float(rng.uniform(1.0, 2.0)),
                "time_constant": float(rng.uniform(1200.0, 3000.0))}
        if form == "three_body":
            spec.update(core_time_constant=log_uniform(rng, 3.0, 30.0), core_ratio=float(rng.uniform(5.0, 15.0)))
        return spec

    def _apply(self, build, spec):
        # sized from the copper energies of a run without heating (see make_dataset); a
        # first estimate from the kinetic energy law keeps the plant usable on its own:
        # a start dissipates the final kinetic energy in the rotor, Rs/Rr of it in the stator
        m, mo = build.machine, build.motor
        kinetic = 0.5 * (m.J + build.plant["mechanics"].J_load) * mo.w_sync**2
        ref = m.referred()
        build.plant["thermal"] = Thermal.sized(spec["form"] == "two_body", kinetic * ref["Rs"] / ref["Rr"], kinetic,
                                               spec["size"], spec["rotor_factor"], spec["time_constant"], m.theta_ref,
                                               core=core_of(spec))
        build.requests["temperature_drift"] = spec


def core_of(spec: dict) -> tuple | None:
    """``(winding-to-core time constant s, core over winding capacity)`` of a ``three_body``
    temperature drift, else None."""
    return (spec["core_time_constant"], spec["core_ratio"]) if spec["form"] == "three_body" else None


class InverterDrop(Effect):
    name, unit, inverter_only = "inverter_drop", "V at rated current", True

    def _draw(self, rng, motor, form):
        In = motor.rated_current_peak
        if form == "igbt":
            VT = float(rng.uniform(0.8, 2.0))
            r = float(rng.uniform(0.2, 1.0)) / In
            VD = float(VT * rng.uniform(0.7, 1.0))
        elif form == "mosfet":
            VT, VD = 0.0, float(rng.uniform(0.7, 1.2))
            r = float(rng.uniform(1.0, 3.0)) / In
        else:  # mosfet_capacitive: the channel conducts both ways, no diode outside the dead time
            VT, VD = 0.0, 0.0
            r = float(rng.uniform(1.0, 3.0)) / In
        spec = {"size": VT + r * In, "V_T": VT, "V_D": VD, "r": r, "dead_time": float(rng.uniform(1e-6, 4e-6))}
        if form == "mosfet_capacitive":
            spec["transition_fraction"] = float(rng.uniform(0.03, 0.15))
        return spec

    def _apply(self, build, spec):
        In = build.motor.rated_current_peak
        i_c = float(spec.get("transition_fraction", 0.0)) * In
        build.plant["inverter"] = Inverter(V_T=spec["V_T"], V_D=spec["V_D"], r=spec["r"], dead_time=spec["dead_time"],
                                           i_knee=0.01 * In, i_transition=i_c)


class LoadTorque(Effect):
    name, unit = "load_torque", "fraction of rated torque"

    def _draw(self, rng, motor, form):
        spec = {"size": float(rng.uniform(0.1, 1.0))}
        if form == "step":
            spec["step_fraction"] = float(rng.uniform(0.3, 0.7))
        if form in SWITCHED_LOADS:  # switched on at the start or later, with equal odds
            spec["step_fraction"] = 0.0 if rng.random() < 0.5 else float(rng.uniform(0.3, 0.7))
        if form == "dc_generator":
            spec.update(armature_time_constant=log_uniform(rng, 2e-3, 2e-2), emf=float(rng.uniform(100.0, 250.0)),
                        brush_drop=float(rng.uniform(1.0, 2.0)))
        if form == "eddy_brake":
            spec.update(critical_speed_ratio=log_uniform(rng, 0.2, 2.0),
                        field_time_constant=log_uniform(rng, 0.02, 0.2))
        if form == "battery_charger":
            spec["cut_in_ratio"] = float(rng.uniform(0.3, 0.8))
        return spec

    def _apply(self, build, spec):
        mo = build.motor
        t_step = float(spec.get("step_fraction", 0.0)) * build.duration + getattr(build.scenario, "pre_trigger", 0.0)
        TL = spec["size"] * mo.rated_torque
        mech = replace(build.plant["mechanics"], load=spec["form"], load_torque=TL, w_ref=mo.w_sync, t_step=t_step)
        out = {"load_torque": TL, "t_step": t_step if spec["form"] in ("step", *SWITCHED_LOADS) else None}
        if spec["form"] == "dc_generator":
            # EMF ``emf`` at synchronous speed; the circuit resistance gives TL there (brush drop aside)
            ke = spec["emf"] / mo.w_sync
            R = ke**2 * mo.w_sync / TL
            mech = replace(mech, generator=(ke, R, spec["armature_time_constant"] * R, spec["brush_drop"],
                                            0.01 * TL / ke))
            out.update(emf_constant=ke, armature_resistance=R, armature_inductance=spec["armature_time_constant"] * R)
        if spec["form"] == "eddy_brake":
            # the critical speed w_k a ratio of synchronous speed; T_k so that the steady torque at w_sync is TL
            w_k = spec["critical_speed_ratio"] * mo.w_sync
            q = mo.w_sync / w_k
            T_k = TL * (1.0 + q * q) / (2.0 * q)
            mech = replace(mech, brake=(T_k, w_k, spec["field_time_constant"]))
            out.update(peak_torque=T_k, critical_speed=w_k)
        if spec["form"] == "battery_charger":
            w_c = spec["cut_in_ratio"] * mo.w_sync
            mech = replace(mech, cut_in_speed=w_c)
            out.update(cut_in_speed=w_c)
        build.plant["mechanics"] = mech
        return out


class TwoMass(Effect):
    name, unit = "two_mass", "Hz"

    def _draw(self, rng, motor, form):
        bl = float(np.radians(rng.uniform(0.1, 0.5))) if form == "backlash" else 0.0
        spec = {"size": float(np.exp(rng.uniform(np.log(30.0), np.log(200.0)))),
                "inertia_ratio": float(rng.uniform(0.3, 2.0)), "damping_ratio": float(rng.uniform(0.02, 0.1)),
                "backlash": bl}
        if form == "elastomer":
            spec["hardening"] = float(rng.uniform(1.5, 3.0))
        if form == "slip_clutch":
            spec["slip_share"] = float(rng.uniform(0.7, 1.8))
        return spec

    def _apply(self, build, spec):
        Jm = build.machine.J
        Jl = spec["inertia_ratio"] * Jm
        Jr = Jm * Jl / (Jm + Jl)
        k = (2 * math.pi * spec["size"]) ** 2 * Jr
        c = 2 * spec["damping_ratio"] * math.sqrt(k * Jr)
        z_r = 0.0
        if spec["form"] == "elastomer":
            # incremental stiffness k (1 + (z/z_r)^2) is ``hardening`` k at the rated torque's twist z_n:
            # T_n = k z_n (1 + (H - 1)/3), z_r = z_n / sqrt(H - 1)
            H = spec["hardening"]
            z_r = build.motor.rated_torque / (k * (1 + (H - 1) / 3)) / math.sqrt(H - 1)
        T_lim = spec["slip_share"] * build.motor.rated_torque if spec["form"] == "slip_clutch" else 0.0
        build.plant["mechanics"] = replace(build.plant["mechanics"], J_load=Jl, stiffness=k, damping=c,
                                           backlash=spec["backlash"], twist_ref=z_r, slip_torque=T_lim)
        return {"J_load": Jl, "stiffness": k, "damping": c, **({"twist_ref": z_r} if z_r else {}),
                **({"slip_torque": T_lim} if T_lim else {})}


EFFECTS = {e.name: e for e in (CoulombFriction(), DoubleCage(), MainSaturation(), IronLossEffect(),
                               LeakageSaturation(), LoadTorque(), TwoMass(), TemperatureDrift(), InverterDrop(),
                               CurrentSensorSaturation(), SpeedSensorGain(), SensorOffset(), ChannelDelay())}


def get_effect(name: str) -> Effect:
    try:
        return EFFECTS[name]
    except KeyError:
        raise ValueError(f"unknown effect {name!r}; known: {list(EFFECTS)}") from None


def ordered(specs: list[dict]) -> list[dict]:
    """Effect specs in application order (rotor before leakage saturation, mechanics before
    the thermal sizing, and so on)."""
    order = list(EFFECTS)
    return sorted(specs, key=lambda s: order.index(s["name"]))
