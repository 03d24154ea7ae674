"""The effect catalogue: realistic random sizes and forms, and how each changes the plant.

Every effect has ``draw(rng, motor) -> spec`` (a dict ``{name, form, size, unit, ...}`` with
everything needed to rebuild it) and ``apply(build, spec) -> dict`` (changes the plant or
sensor settings being assembled; returns what was actually realised, for ``truth.yaml``).
Effects are applied in the order of :data:`EFFECTS`. Draw ranges (``I_n`` rated current
amplitude, ``T_n`` rated torque, ``f`` rated frequency, ``M`` internal steps per sample):

* ``coulomb_friction`` (form ``coulomb``): size = the plant's ``fc``, 0.3-1.5 % of ``T_n``, N m.
* ``double_cage`` (``double_cage`` two cages, ``deep_bar`` 3-6 bar slices): size = rotor
  resistance at ``f`` over its low-slip value, 1.3-2.2 (double cage), 1.2-1.6 (deep bar). When
  the motor's own rotor leakage cannot give the ratio it grows (at most 2x) and the truth
  holds the realised low-slip values; ``achieved_size`` is the realised ratio.
* ``main_saturation`` (``frohlich``, ``arctan``, ``table``): size = drop of the secant
  magnetising inductance at rated flux, 0.08-0.30 (fraction).
* ``iron_loss`` (``eddy_winding`` with an eddy time constant 0.2-1 ms, ``shunt`` = a
  resistance across the magnetising branch): size = core loss at rated voltage, 2-6 % of
  rated power (fraction).
* ``leakage_saturation`` (``lorentzian``, ``frohlich``): size = ``L(6 I_n)/L(0.9 I_n)`` of the
  stator leakage (the rotor's saturable part follows the same curve), 0.45-0.75; linear
  (non-saturating) share 0.25-0.4.
* ``temperature_drift`` (``one_body``, ``two_body``): size = stator winding temperature
  rise over the start-up record, 5-25 K (rotor 1-2x that for two bodies); cooling time
  constant 20-50 min.
* ``inverter_drop`` (``igbt``: threshold 0.8-2 V plus slope 0.2-1 V at ``I_n``; ``mosfet``:
  on-resistance 1-3 V at ``I_n``, body diode 0.7-1.2 V): size = device drop at ``I_n``, V;
  dead time 1-4 us. Inverter scenarios only.
* ``load_torque`` (``constant``, ``quadratic``, ``step`` at 30-70 % of the record): size =
  ``T_L/T_n``, 0.1-1.0.
* ``two_mass`` (``spring``, ``backlash`` of 0.1-0.5 deg): size = torsional resonance,
  30-200 Hz (log-uniform); load inertia 0.3-2 x the motor's; damping ratio 0.02-0.1.
* ``current_sensor_saturation`` (``tanh``, ``knee``, ``clip``): size = level / ``I_n``, 1.5-3.
* ``speed_sensor_gain`` (``gain``, ``gain_ripple``): size = gain error, +-(1-5) %
  (fraction); offset up to +-0.5 % of synchronous speed; ripple at the rotation frequency
  0.2-1 % of the speed (``gain_ripple``).
* ``sensor_offset`` (``both``, ``current``, ``voltage``): current offsets 0.05-0.3 A, voltage
  offsets 0.5-5 V, random signs; size = the largest current offset, A (the largest voltage
  offset, V, for ``voltage``).
* ``channel_delay`` (``current_lag``, ``voltage_lag``): size = skew 0.1-2 samples, realised
  to a multiple of ``1/M`` (``achieved_size``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from synthetic.independent.curves import LeakageCurve, MagnetisingCurve
from synthetic.independent.inverter import Inverter
from synthetic.independent.motors import Motor
from synthetic.independent.plant import IronLoss
from synthetic.independent.rotor import RotorCage, design
from synthetic.independent.thermal import Thermal


@dataclass
class Build:
    """What the effects edit: the plant's parts, the sensor settings, the channel skews
    (samples) and requests for the data-set maker (sizing that needs a simulation);
    ``scenario`` and ``duration`` (s) are read-only context."""

    motor: Motor
    scenario: object
    duration: float
    plant: dict = field(default_factory=dict)
    sensors: dict = field(default_factory=dict)
    skew: dict = field(default_factory=lambda: {"current": 0.0, "voltage": 0.0})
    requests: dict = field(default_factory=dict)

    @property
    def machine(self):
        return self.plant["machine"]


def _signed(rng, lo, hi):
    return float(rng.choice([-1.0, 1.0]) * rng.uniform(lo, hi))


class Effect:
    name = ""
    forms: tuple = ()
    unit = ""
    inverter_only = False

    def draw(self, rng: np.random.Generator, motor: Motor, form: str | None = None) -> dict:
        form = form if form is not None else str(rng.choice(self.forms))
        if form not in self.forms:
            raise ValueError(f"{self.name}: form must be one of {self.forms}, got {form!r}")
        spec = {"name": self.name, "form": form, "unit": self.unit}
        spec.update(self._draw(rng, motor, form))
        return spec

    def _draw(self, rng, motor, form) -> dict:
        raise NotImplementedError

    def apply(self, build: Build, spec: dict) -> dict:
        if self.inverter_only and build.scenario.kind == "dol":
            raise ValueError(f"{self.name} needs an inverter-fed scenario (six_step or pwm)")
        return self._apply(build, spec) or {}

    def _apply(self, build, spec):
        raise NotImplementedError


class CoulombFriction(Effect):
    name, forms, unit = "coulomb_friction", ("coulomb",), "N m"

    def _draw(self, rng, motor, form):
        return {"size": float(rng.uniform(0.003, 0.015) * motor.rated_torque)}

    def _apply(self, build, spec):
        build.plant["machine"] = replace(build.machine, fc=float(spec["size"]))


class DoubleCage(Effect):
    name, forms, unit = "double_cage", ("double_cage", "deep_bar"), "ratio R(f)/R(0)"

    def _draw(self, rng, motor, form):
        if form == "double_cage":
            return {"size": float(rng.uniform(1.3, 2.2)), "loops": 2}
        return {"size": float(rng.uniform(1.2, 1.6)), "loops": int(rng.integers(3, 7))}

    def _apply(self, build, spec):
        m = build.machine
        cage, ratio = design(spec["form"], m.Rr, m.Llr, 2 * math.pi * build.motor.frequency, spec["size"],
                             n=int(spec.get("loops", 4)), max_growth=2.0)
        build.plant["rotor"] = cage
        return {"achieved_size": ratio, "loop_resistances": [float(r) for r in cage.R],
                "common_leakage": cage.common.L0}


class MainSaturation(Effect):
    name, forms, unit = "main_saturation", ("frohlich", "arctan", "table"), "fraction"

    def _draw(self, rng, motor, form):
        return {"size": float(rng.uniform(0.08, 0.30))}

    def _apply(self, build, spec):
        curve = MagnetisingCurve.with_drop(spec["form"], build.machine.Lm, build.motor.psi_rated, spec["size"])
        build.plant["magnetising"] = curve
        return {"Lm0": curve.Lm0, "knee": curve.knee, "Linf": curve.Linf, "psi_ref": build.motor.psi_rated}


class IronLossEffect(Effect):
    name, forms, unit = "iron_loss", ("eddy_winding", "shunt"), "fraction of rated power"

    def _draw(self, rng, motor, form):
        tau = float(rng.uniform(2e-4, 1e-3)) if form == "eddy_winding" else 0.0
        return {"size": float(rng.uniform(0.02, 0.06)), "time_constant": tau}

    def _apply(self, build, spec):
        mo = build.motor
        w = 2 * math.pi * mo.frequency
        E = mo.psi_rated * w
        Rc = 1.5 * E**2 / (spec["size"] * mo.rated_power)
        tau = float(spec.get("time_constant", 0.0))
        if tau > 0:
            R = Rc / (1 + (w * tau) ** 2)
            L = tau * R
        else:
            R, L = Rc, 0.01 * build.machine.Lls  # a resistance across the magnetising branch
        build.plant["iron"] = IronLoss(R, L)
        return {"R_fe": R, "L_fe": L, "Rc_equivalent": Rc}


class LeakageSaturation(Effect):
    name, forms, unit = "leakage_saturation", ("lorentzian", "frohlich"), "ratio L(6 In)/L(0.9 In)"

    def _draw(self, rng, motor, form):
        return {"size": float(rng.uniform(0.45, 0.75)), "linear_share": float(rng.uniform(0.25, 0.4))}

    def _apply(self, build, spec):
        m, mo = build.machine, build.motor
        lo, hi = 0.9 * mo.rated_current_peak, 6.0 * mo.rated_current_peak
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


class TemperatureDrift(Effect):
    name, forms, unit = "temperature_drift", ("one_body", "two_body"), "K"

    def _draw(self, rng, motor, form):
        return {"size": float(rng.uniform(5.0, 25.0)), "rotor_factor": float(rng.uniform(1.0, 2.0)),
                "time_constant": float(rng.uniform(1200.0, 3000.0))}

    def _apply(self, build, spec):
        # sized from the copper energies of a run without heating (see make_dataset); a
        # first estimate from the kinetic energy law keeps the plant usable on its own:
        # a start dissipates the final kinetic energy in the rotor, Rs/Rr of it in the stator
        m, mo = build.machine, build.motor
        kinetic = 0.5 * (m.J + build.plant["mechanics"].J_load) * mo.w_sync**2
        ref = m.referred()
        build.plant["thermal"] = Thermal.sized(spec["form"] == "two_body", kinetic * ref["Rs"] / ref["Rr"], kinetic,
                                               spec["size"], spec["rotor_factor"], spec["time_constant"], m.theta_ref)
        build.requests["temperature_drift"] = spec


class InverterDrop(Effect):
    name, forms, unit, inverter_only = "inverter_drop", ("igbt", "mosfet"), "V at rated current", True

    def _draw(self, rng, motor, form):
        In = motor.rated_current_peak
        if form == "igbt":
            VT = float(rng.uniform(0.8, 2.0))
            r = float(rng.uniform(0.2, 1.0)) / In
            VD = float(VT * rng.uniform(0.7, 1.0))
        else:
            VT, VD = 0.0, float(rng.uniform(0.7, 1.2))
            r = float(rng.uniform(1.0, 3.0)) / In
        return {"size": VT + r * In, "V_T": VT, "V_D": VD, "r": r, "dead_time": float(rng.uniform(1e-6, 4e-6))}

    def _apply(self, build, spec):
        build.plant["inverter"] = Inverter(V_T=spec["V_T"], V_D=spec["V_D"], r=spec["r"], dead_time=spec["dead_time"],
                                           i_knee=0.01 * build.motor.rated_current_peak)


class LoadTorque(Effect):
    name, forms, unit = "load_torque", ("constant", "quadratic", "step"), "fraction of rated torque"

    def _draw(self, rng, motor, form):
        spec = {"size": float(rng.uniform(0.1, 1.0))}
        if form == "step":
            spec["step_fraction"] = float(rng.uniform(0.3, 0.7))
        return spec

    def _apply(self, build, spec):
        mo = build.motor
        t_step = float(spec.get("step_fraction", 0.0)) * build.duration + getattr(build.scenario, "pre_trigger", 0.0)
        build.plant["mechanics"] = replace(build.plant["mechanics"], load=spec["form"],
                                           load_torque=spec["size"] * mo.rated_torque, w_ref=mo.w_sync, t_step=t_step)
        return {"load_torque": spec["size"] * mo.rated_torque, "t_step": t_step if spec["form"] == "step" else None}


class TwoMass(Effect):
    name, forms, unit = "two_mass", ("spring", "backlash"), "Hz"

    def _draw(self, rng, motor, form):
        bl = float(np.radians(rng.uniform(0.1, 0.5))) if form == "backlash" else 0.0
        return {"size": float(np.exp(rng.uniform(np.log(30.0), np.log(200.0)))),
                "inertia_ratio": float(rng.uniform(0.3, 2.0)), "damping_ratio": float(rng.uniform(0.02, 0.1)),
                "backlash": bl}

    def _apply(self, build, spec):
        Jm = build.machine.J
        Jl = spec["inertia_ratio"] * Jm
        Jr = Jm * Jl / (Jm + Jl)
        k = (2 * math.pi * spec["size"]) ** 2 * Jr
        c = 2 * spec["damping_ratio"] * math.sqrt(k * Jr)
        build.plant["mechanics"] = replace(build.plant["mechanics"], J_load=Jl, stiffness=k, damping=c,
                                           backlash=spec["backlash"])
        return {"J_load": Jl, "stiffness": k, "damping": c}


class CurrentSensorSaturation(Effect):
    name, forms, unit = "current_sensor_saturation", ("tanh", "knee", "clip"), "x rated current amplitude"

    def _draw(self, rng, motor, form):
        return {"size": float(rng.uniform(1.5, 3.0))}

    def _apply(self, build, spec):
        level = spec["size"] * build.motor.rated_current_peak
        build.sensors.update(compress=spec["form"], compress_level=level)
        return {"level": level}


class SpeedSensorGain(Effect):
    name, forms, unit = "speed_sensor_gain", ("gain", "gain_ripple"), "fraction"

    def _draw(self, rng, motor, form):
        ripple = float(rng.uniform(0.002, 0.01)) if form == "gain_ripple" else 0.0
        return {"size": _signed(rng, 0.01, 0.05), "offset": float(rng.uniform(-0.005, 0.005) * motor.w_sync),
                "ripple": ripple, "ripple_phase": float(rng.uniform(0, 2 * np.pi))}

    def _apply(self, build, spec):
        build.sensors.update(speed_gain=1.0 + spec["size"], speed_offset=spec["offset"],
                             speed_ripple_rel=spec["ripple"], speed_ripple_phase=spec["ripple_phase"])


class SensorOffset(Effect):
    name, forms, unit = "sensor_offset", ("both", "current", "voltage"), "A"

    def _draw(self, rng, motor, form):
        cur = [_signed(rng, 0.05, 0.3) for _ in range(2)] if form != "voltage" else [0.0, 0.0]
        vol = [_signed(rng, 0.5, 5.0) for _ in range(3)] if form != "current" else [0.0, 0.0, 0.0]
        size = max(abs(c) for c in cur) if form != "voltage" else max(abs(v) for v in vol)
        return {"size": size, "unit": "V" if form == "voltage" else "A", "current_offsets": cur,
                "voltage_offsets": vol}

    def _apply(self, build, spec):
        build.sensors.update(current_offset=tuple(spec["current_offsets"]),
                             voltage_offset=tuple(spec["voltage_offsets"]))


class ChannelDelay(Effect):
    name, forms, unit = "channel_delay", ("current_lag", "voltage_lag"), "samples"

    def _draw(self, rng, motor, form):
        return {"size": float(rng.uniform(0.1, 2.0))}

    def _apply(self, build, spec):
        build.skew["current" if spec["form"] == "current_lag" else "voltage"] = float(spec["size"])


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
