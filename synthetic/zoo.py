"""A zoo of published induction motors (``zoo_motors.yaml``) and data sets made from them.

Each motor carries its published T-equivalent circuit (``Rs, Rr, Lls, Llr, Lm``; rotor
quantities referred to the stator), its rating and its source. :func:`project_parameters`
refers the circuit to the project's parametrisation, which fixes ``Lr = Ls``:
``Ls = Lls + Lm``, ``Lr = Llr + Lm``, ``Le = Ls - Lm**2/Lr`` and ``Rr = Rr_T*Ls/Lr`` (the
rotor time constant ``Lr/Rr_T`` is kept). The stator-side behaviour is unchanged.

Where a source gives no inertia or friction, a documented rule fills it in (and the motor's
``derived`` field names what was filled in):

* inertia: ``J = INERTIA_COEFFICIENT * (T_N / 1 N m) ** INERTIA_EXPONENT`` kg m^2, a
  least-squares fit of log J on log rated torque over the 14 MATLAB/Simscape preset motors
  in the zoo (4-pole, 3.7-149 kW; rated torque from the rated power at 97 % of synchronous
  speed when the rated speed is not given);
* friction: friction and windage loss at rated speed = 1 % of rated power (the Modelica
  Standard Library's 18.5 kW example motor has 180 W), half viscous, half Coulomb.

:func:`recommended_settings` picks a per-motor sample rate, record length and noise level;
:func:`independent_noise` and :func:`motulator_noise` give the study's ``white`` and ``coloured``
noise in each source's own names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import yaml

ZOO_FILE = Path(__file__).with_name("zoo_motors.yaml")
INERTIA_COEFFICIENT = 1.88e-4  # kg m^2 (fit, see module docstring)
INERTIA_EXPONENT = 1.42
FRICTION_LOSS_FRACTION = 0.01
DEFAULT_SLIP = 0.03
SOURCES = ("motulator", "independent")


@dataclass(frozen=True)
class ZooMotor:
    """A published induction motor.

    Attributes
    ----------
    name : str
        Identifier (lower case, no spaces).
    rated_power : float
        Rated output power (W).
    voltage : float
        Rated voltage (V, line-line rms).
    frequency : float
        Rated frequency (Hz).
    pole_pairs : int
        Number of pole pairs.
    Rs, Rr : float
        Stator resistance and rotor resistance referred to the stator (ohm, per phase, star).
    Lls, Llr, Lm : float
        Stator and rotor leakage and magnetising inductances (H).
    J : float
        Moment of inertia (kg m^2).
    fv : float
        Viscous friction coefficient (N m s/rad).
    fc : float
        Coulomb friction torque (N m).
    source : str
        Citation (book/paper/manual and table/page).
    rated_current : float or None
        Rated current (A rms), if published.
    rated_speed : float or None
        Rated speed (rpm), if published.
    dc_link_voltage : float or None
        DC-link voltage (V) of the source's inverter, if it has one.
    notes : str
        Remarks on the data (conversions, assumptions).
    derived : tuple of str
        Fields filled in by the rules of this module (J, fv, fc).
    """

    name: str
    rated_power: float
    voltage: float
    frequency: float
    pole_pairs: int
    Rs: float
    Rr: float
    Lls: float
    Llr: float
    Lm: float
    J: float
    fv: float
    fc: float
    source: str
    rated_current: float | None = None
    rated_speed: float | None = None
    dc_link_voltage: float | None = None
    notes: str = ""
    derived: tuple = field(default_factory=tuple)


def synchronous_speed(m: ZooMotor) -> float:
    """Synchronous mechanical speed (rad/s)."""
    return 2 * math.pi * m.frequency / m.pole_pairs


def rated_speed(m: ZooMotor) -> float:
    """Rated mechanical speed (rad/s): published, else synchronous speed at 3 % slip."""
    return m.rated_speed * math.pi / 30 if m.rated_speed else (1 - DEFAULT_SLIP) * synchronous_speed(m)


def rated_torque(m: ZooMotor) -> float:
    """Rated torque (N m) from rated power and rated speed."""
    return m.rated_power / rated_speed(m)


def rated_current(m: ZooMotor) -> float:
    """Rated current (A rms): published, else ``P/(sqrt(3) U * 0.75)`` (efficiency x power factor)."""
    return m.rated_current or m.rated_power / (math.sqrt(3) * m.voltage * 0.75)


def inertia_rule(torque: float) -> float:
    """Inertia (kg m^2) of a motor of that rated torque (N m) by the zoo's catalogue fit."""
    return INERTIA_COEFFICIENT * torque**INERTIA_EXPONENT


def friction_rule(power: float, speed: float) -> tuple[float, float]:
    """(fv N m s/rad, fc N m) dissipating 1 % of ``power`` (W) at ``speed`` (rad/s), half each."""
    loss = 0.5 * FRICTION_LOSS_FRACTION * power
    return loss / speed**2, loss / speed


def _motor_from_entry(e: dict) -> ZooMotor:
    derived = []
    kw = {k: e.get(k) for k in ("name", "rated_power", "voltage", "frequency", "pole_pairs", "Rs", "Rr", "Lls",
                                "Llr", "Lm", "source", "rated_current", "rated_speed", "dc_link_voltage")}
    kw["notes"] = str(e.get("notes", "")).strip()
    base = ZooMotor(**kw, J=1.0, fv=0.0, fc=0.0)
    J, fv, fc = e.get("J"), e.get("fv"), e.get("fc")
    if J is None:
        J = inertia_rule(rated_torque(base))
        derived.append("J")
    if fv is None or fc is None:
        rv, rc = friction_rule(base.rated_power, rated_speed(base))
        if fv is None:
            fv = rv
            derived.append("fv")
        if fc is None:
            fc = rc
            derived.append("fc")
    return ZooMotor(**kw, J=float(J), fv=float(fv), fc=float(fc), derived=tuple(derived))


def load_zoo(path: str | Path | None = None) -> list[ZooMotor]:
    """The motors of ``zoo_motors.yaml`` (or ``path``), rules applied where data are missing."""
    doc = yaml.safe_load(Path(path or ZOO_FILE).read_text())
    return [_motor_from_entry(e) for e in doc["motors"]]


def get_motor(name: str, path: str | Path | None = None) -> ZooMotor:
    """One zoo motor by name."""
    motors = {m.name: m for m in load_zoo(path)}
    if name not in motors:
        raise KeyError(f"no zoo motor {name!r}; known: {', '.join(motors)}")
    return motors[name]


def project_parameters(m: ZooMotor) -> dict:
    """Project parameters ``Rs, Ls, Le, Rr`` (ohm, H; ``Lr = Ls``), ``J`` (kg m^2), ``fv``, ``fc``."""
    Ls, Lr = m.Lls + m.Lm, m.Llr + m.Lm
    return {"Rs": m.Rs, "Ls": Ls, "Le": Ls - m.Lm**2 / Lr, "Rr": m.Rr * Ls / Lr, "J": m.J, "fv": m.fv, "fc": m.fc}


def recommended_settings(m: ZooMotor) -> dict:
    """Sample rate (Hz), start-up length (s) and noise for a no-load start of ``m``.

    * sample rate: at least 25 samples per transient time constant ``Le/Re`` and 100 per
      supply period, rounded up to 1 kHz, within 5-20 kHz;
    * duration: ``2 J w_sync / T_N + 0.3`` s (the rated torque is a lower bound of the mean
      accelerating torque of a direct-on-line start; the margin lets the electromechanical
      oscillation settle), rounded up to 0.1 s, within 0.6-5 s;
    * noise: white current noise 0.3 % and coloured (50 Hz first-order) 0.1 % of the rated
      peak current; speed noise 0.05 % and quantum 0.1 % of synchronous speed.
    """
    p = project_parameters(m)
    Lr = p["Ls"]
    Lm = math.sqrt(p["Ls"] * (p["Ls"] - p["Le"]))
    tau = p["Le"] / (p["Rs"] + (Lm / Lr) ** 2 * p["Rr"])
    fs = min(20000.0, max(5000.0, 1000.0 * math.ceil(max(25 / tau, 100 * m.frequency) / 1000.0)))
    t_start = m.J * synchronous_speed(m) / rated_torque(m)
    duration = min(5.0, max(0.6, math.ceil(10 * (2.0 * t_start + 0.3)) / 10))
    i_peak = math.sqrt(2) * rated_current(m)
    w_sync = synchronous_speed(m)
    noise = {"current_std": 0.003 * i_peak, "current_colored_std": 0.001 * i_peak,
             "current_colored_bandwidth": 50.0, "speed_std": 5e-4 * w_sync, "speed_quantum": 1e-3 * w_sync}
    return {"sample_rate": fs, "duration": duration, "noise": noise}


def motor_description(m: ZooMotor) -> dict:
    """The motor as a data-set generator takes it (project parameters, pole pairs, rating)."""
    d = {"name": m.name, "pole_pairs": m.pole_pairs, "voltage": m.voltage, "frequency": m.frequency,
         "rated_power": m.rated_power, "rated_torque": rated_torque(m), "parameters": project_parameters(m)}
    if m.dc_link_voltage:
        d["dc_link_voltage"] = m.dc_link_voltage
    return d


#: This module's noise names -> the independent plant's (``synthetic.independent.dataset``).
_INDEPENDENT_NOISE = {"current_std": "current_white", "current_colored_std": "current_colored",
                      "voltage_std": "voltage_white", "speed_std": "speed_white", "speed_quantum": "speed_quantum"}


def independent_noise(m: ZooMotor, kind: str = "white") -> dict:
    """Noise settings of the independent plant for a zoo motor (its own noise names).

    ``white``: white current noise 0.3 % of the rated peak current, speed noise 0.05 % and
    quantum 0.1 % of synchronous speed (as :func:`recommended_settings`).
    ``coloured``: the same plus AR(1) current noise of 0.3 % (pole 0.95 per sample: the
    noise of an anti-aliased, oversampled bench channel) and a 12-bit current ADC over 8x the
    rated peak current.
    """
    rec = recommended_settings(m)["noise"]
    noise = {"current_white": rec["current_std"], "speed_white": rec["speed_std"],
             "speed_quantum": rec["speed_quantum"]}
    if kind in ("coloured", "colored"):
        i_peak = math.sqrt(2) * rated_current(m)
        noise.update(current_colored=0.003 * i_peak, current_pole=0.95, current_quantum=8 * i_peak / 4096)
    elif kind not in ("white", "none"):
        raise ValueError(f"noise kind must be white, coloured or none, got {kind!r}")
    if kind == "none":
        return {}
    return noise


def motulator_noise(m: ZooMotor, kind: str = "white") -> dict:
    """Noise settings of the motulator source for a zoo motor (``make_motulator_dataset``'s names).

    ``white``: as :func:`independent_noise` ``white`` (0.3 % of the rated peak current, speed
    noise 0.05 % and quantum 0.1 % of synchronous speed). ``coloured``: the same plus
    first-order coloured current noise of 0.3 % whose bandwidth gives the AR(1) pole 0.95 per
    sample of :func:`independent_noise` at the recommended sample rate (motulator's noise has
    no current ADC quantisation). ``none``: no noise.
    """
    if kind == "none":
        return {}
    if kind not in ("white", "coloured", "colored"):
        raise ValueError(f"noise kind must be white, coloured or none, got {kind!r}")
    rec = recommended_settings(m)
    noise = {k: rec["noise"][k] for k in ("current_std", "speed_std", "speed_quantum")}
    if kind != "white":
        i_peak = math.sqrt(2) * rated_current(m)
        noise.update(current_colored_std=0.003 * i_peak,
                     current_colored_bandwidth=-math.log(0.95) * rec["sample_rate"] / (2 * math.pi))
    return noise


def independent_motor(m: ZooMotor):
    """The zoo motor as a motor of the independent plant (``synthetic.independent.motors.Motor``):
    its referred parameters through ``TMachine.from_referred`` (equal leakages, so the plant's
    T circuit refers back exactly to the zoo's ``Rs, Ls, Le, Rr``), DC link ``dc_link_voltage``
    or the six-step value ``V pi / sqrt(6)`` (six-step fundamental = rated voltage)."""
    from functools import cached_property

    from synthetic.independent.machine import TMachine
    from synthetic.independent.motors import Motor

    class ZooPlantMotor(Motor):
        """The plant's motor with the zoo's rating as a fallback where the plant's rated-point
        solver finds no slip delivering the published power (a published circuit that is
        slightly weak at rated voltage): only the nameplate and default noise use it."""

        @cached_property
        def rated(self) -> dict:
            try:
                return self.machine.rated_point(self.voltage, self.frequency, self.rated_power)
            except ValueError:
                w = rated_speed(m)
                return {"slip": 1 - w / synchronous_speed(m), "current": rated_current(m),
                        "speed": w * 30 / math.pi, "torque": rated_torque(m)}

    p = project_parameters(m)
    machine = TMachine.from_referred(p["Rs"], p["Ls"], p["Le"], p["Rr"], p["J"], p["fv"], p["fc"], m.pole_pairs)
    fs = recommended_settings(m)["sample_rate"]
    Ed = m.dc_link_voltage or round(m.voltage * math.pi / math.sqrt(6), 1)
    Nc = max(1, int(round(fs / (6 * m.frequency))))
    return ZooPlantMotor(m.name, machine, m.rated_power, m.voltage, m.frequency, fs, Ed, Nc, m.source)


def _make_independent(motor: ZooMotor, kw: dict) -> dict:
    """Run the project's independent plant (``make_spec`` -> ``make_dataset`` -> ``write_dataset``)
    on the zoo motor: it is registered as a plant preset for the duration of the call (see
    :func:`independent_motor`). Noise: ``kw["noise"]`` in the plant's names (or this module's,
    translated), else :func:`independent_noise` ``white``."""
    from synthetic.independent import dataset as ind
    from synthetic.independent import motors as ind_motors

    noise = dict(kw["noise"]) if kw["user_noise"] else independent_noise(motor, "white")
    noise = {_INDEPENDENT_NOISE.get(k, k): v for k, v in noise.items()
             if k not in ("current_colored_bandwidth",)}
    key = motor.name
    previous = ind_motors.PRESETS.get(key)
    ind_motors.PRESETS[key] = independent_motor(motor)
    try:
        spec = ind.make_spec(key, scenario=kw["scenario"], effects=list(kw["effects"]), seed=kw["seed"],
                             duration=kw["duration"], sample_rate=kw["sample_rate"],
                             stop=3.0 if kw["stop"] else None, noise=noise,
                             ideal_supply=bool(kw.get("ideal_supply", False)))
        spec["meta"]["dc_resistance"] = True
        ds = ind.make_dataset(spec)
        ind.write_dataset(ds, kw["out"])
    finally:
        if previous is None:
            ind_motors.PRESETS.pop(key, None)
        else:
            ind_motors.PRESETS[key] = previous
    return ds.truth


def make_zoo_dataset(motor: ZooMotor | str, scenario: str = "dol", noise: dict | None = None, seed: int = 0,
                     out: str | Path = "data/zoo", source: str = "motulator", effects: dict | None = None,
                     stop: bool = False, duration: float | None = None,
                     sample_rate: float | None = None) -> dict:
    """Write a start-up data set of a zoo motor; returns its truth document.

    Parameters
    ----------
    motor : ZooMotor or str
        The motor, or its name in the zoo.
    scenario : {"dol", "six_step", "pwm"}
        Direct-on-line sine start, six-step or sine-PWM inverter start.
    noise : dict or None
        Noise settings (see :func:`synthetic.motulator_source.make_motulator_dataset`);
        None: :func:`recommended_settings` (0.3 % of rated current and so on).
    seed : int
        Noise seed.
    out : str or Path
        Output folder.
    source : {"motulator", "independent"}
        Simulator: motulator (optional dependency, about 8 s per record), or the project's
        independent plant (``synthetic.independent``, about 0.5 s per record; the zoo motor is
        handed to it through :func:`independent_motor`; noise in its names or this module's,
        default :func:`independent_noise` ``white``; a realistic grid for ``dol``: harmonics,
        source impedance, contactor stagger and bounce).
    effects : dict or None
        Effects to inject (``{name: options}``).
    stop : bool
        Also record the free stop.
    duration, sample_rate : float or None
        Start-up length (s) and sample rate (Hz); None: :func:`recommended_settings`.
    """
    if isinstance(motor, str):
        motor = get_motor(motor)
    if source not in SOURCES:
        raise ValueError(f"source must be one of {SOURCES}, got {source!r}")
    rec = recommended_settings(motor)
    kwargs = {"motor": motor_description(motor), "scenario": scenario, "effects": dict(effects or {}),
              "noise": rec["noise"] if noise is None else dict(noise), "seed": int(seed), "out": Path(out),
              "duration": float(duration or rec["duration"]), "sample_rate": float(sample_rate or rec["sample_rate"]),
              "stop": bool(stop)}
    if source == "motulator":
        from synthetic.motulator_source import make_motulator_dataset

        return make_motulator_dataset(**kwargs)
    return _make_independent(motor, {**kwargs, "user_noise": noise is not None})


def zoo_table(motors: list[ZooMotor] | None = None) -> str:
    """A plain-text table: name, kW, pole pairs, source."""
    rows = [f"{'name':28s} {'kW':>7s} {'p':>2s}  source"]
    for m in motors or load_zoo():
        rows.append(f"{m.name:28s} {m.rated_power / 1e3:7.2f} {m.pole_pairs:2d}  {m.source}")
    return "\n".join(rows)


if __name__ == "__main__":
    print(zoo_table())
