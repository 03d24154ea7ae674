"""Make a data set from a spec, and write it as a folder the project's loader reads.

A *spec* (a plain dict, YAML-able) says everything: ``motor`` (preset name), optional
``machine`` (T-circuit overrides), ``scenario`` (``kind`` and its parameters), ``sample_rate``
(Hz), ``oversampling``, ``effects`` (drawn effect specs), ``noise``, ``sensors``
(``has_speed``, ``has_torque``, ``anti_alias``), ``stop`` (``duration``, ``sample_time``; or
null), ``meta`` (``nameplate``, ``dc_resistance``: whether to write them) and ``seed``.
:func:`make_spec` draws one from a few choices; :func:`make_dataset` simulates it;
:func:`write_dataset` writes ``meta.yaml``, ``startup.csv``, optionally ``stop.csv``, and
``truth.yaml`` (the truth: referred parameters, T-circuit parameters, effects with their
sizes, noise, scenario).

Randomness: effect sizes, forms and scenario details come from ``default_rng([seed, 1])``
(in :func:`make_spec`), the noise from ``default_rng(seed)``; the same spec gives
bit-identical files.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import yaml

from synthetic.independent.effects import Build, core_of, get_effect, ordered
from synthetic.independent.integrate import COL, coast, oversampling, simulate
from synthetic.independent.machine import TMachine
from synthetic.independent.mechanics import Mechanics
from synthetic.independent.motors import Motor, get_motor
from synthetic.independent.plant import Plant
from synthetic.independent.sensors import Noise, Sensors, sensed_speed, startup_record
from synthetic.independent.supply import Grid, Pwm, SixStep, stop_drive
from synthetic.independent.thermal import Thermal

#: An open contactor pole is this many times the locked-rotor impedance (0.03 % current).
OPEN_POLE_FACTOR = 3000.0


@dataclass
class Dataset:
    """A made data set: ``meta`` (dict), ``startup`` and ``stop`` (column name -> array; stop
    may be None), ``truth`` (dict), and the internal trajectory for inspection."""

    meta: dict
    startup: dict
    stop: dict | None
    truth: dict
    trajectory: object = None
    plant: Plant | None = None


def default_noise(motor: Motor) -> dict:
    """A moderate bench: 0.4 % and 0.3 % of rated current amplitude white and coloured
    current noise, 12-bit current ADC over 8x rated, speed quantum 0.05 rad/s."""
    In = motor.rated_current_peak
    return {"current_white": 0.004 * In, "current_colored": 0.003 * In, "current_pole": 0.97,
            "current_quantum": 16 * In / 4096, "voltage_white": 0.3, "voltage_quantum": 0.0,
            "speed_white": 0.02, "speed_quantum": 0.05}


def draw_scenario(kind: str, motor: Motor, duration: float, sample_rate: float,
                  rng: np.random.Generator | None) -> dict:
    """Scenario parameters for ``kind``; with ``rng`` the imperfections of a real supply are
    drawn (grid harmonics, unbalance, pole scatter and bounce, dip; PWM ramp), else ideal."""
    f = motor.frequency
    if kind == "six_step":
        sc = {"kind": kind, "Ed": motor.Ed, "Nc": max(1, int(round(sample_rate / (6 * f))))}
        return scenario_with_duration(sc, duration, sample_rate)
    if kind == "pwm":
        sc = {"kind": kind, "Ed": round(1.35 * motor.voltage, 1), "f": f, "V_rated": motor.voltage, "f_rated": f,
              "ramp": 0.3 * duration, "boost": 0.03, "duration": duration}
        if rng is not None:
            sc.update(ramp=float(rng.uniform(0.2, 0.6) * duration), boost=float(rng.uniform(0.02, 0.05)))
        return sc
    if kind != "dol":
        raise ValueError(f"scenario must be dol, six_step or pwm, got {kind!r}")
    sc = {"kind": kind, "V": motor.voltage, "f": f, "duration": duration}
    if rng is not None:
        stagger = [0.0] + list(rng.uniform(0.0, 1.5e-3, 2))
        sc.update(h5=float(rng.uniform(0, 0.04)), h7=float(rng.uniform(0, 0.03)),
                  phase5=float(rng.uniform(0, 2 * np.pi)), phase7=float(rng.uniform(0, 2 * np.pi)),
                  unbalance=[float(x) for x in rng.normal(0, 0.005, 3)], phase0=float(rng.uniform(0, 2 * np.pi)),
                  pre_trigger=float(rng.uniform(0, 0.05)), stagger=[float(x) for x in rng.permutation(stagger)],
                  bounce=[float(x) for x in rng.uniform(0.2e-3, 1.0e-3, 3)], arc_voltage=float(rng.uniform(20, 40)),
                  dip=float(rng.uniform(0.01, 0.05)), x_over_r=float(rng.uniform(2, 6)))
    return sc


def scenario_with_duration(sc: dict, duration: float, sample_rate: float) -> dict:
    """Scenario ``sc`` recording ``duration`` s at ``sample_rate`` Hz: a six-step start states
    it as whole cycles of its ``Nc`` samples per state, the others as ``duration``."""
    if sc["kind"] == "six_step":
        return sc | {"cycles": max(1, int(round(duration * sample_rate / (6 * sc["Nc"]))))}
    return sc | {"duration": float(duration)}


def make_spec(motor: str, scenario: str = "six_step", effects=(), seed: int = 0, duration: float = 1.0,
              sample_rate: float | None = None, stop: float | None = None, forms: dict | None = None,
              ideal_supply: bool = False, noise: dict | None = None, oversampling: int = 10,
              has_speed: bool = True, has_torque: bool = False, form_set: str = "development") -> dict:
    """A spec with the named effects at random realistic sizes and forms (``forms`` fixes
    some forms, the others are drawn from the form set ``form_set``: ``development``,
    ``heldout`` or ``all``, see :mod:`~synthetic.independent.forms`), noise ``noise`` (default
    :func:`default_noise`), stop record of ``stop`` s."""
    mo = get_motor(motor)
    fs = float(sample_rate or mo.sample_rate)
    rng = np.random.default_rng([seed, 1])
    forms = forms or {}
    return {
        "motor": motor, "scenario": draw_scenario(scenario, mo, duration, fs, None if ideal_supply else rng),
        "sample_rate": fs, "oversampling": int(oversampling),
        "effects": [get_effect(n).draw(rng, mo, forms.get(n), form_set, scenario) for n in effects],
        "noise": default_noise(mo) if noise is None else dict(noise),
        "sensors": {"has_speed": bool(has_speed), "has_torque": bool(has_torque)},
        "stop": None if not stop else {"duration": float(stop), "sample_time": 1e-3},
        "meta": {"nameplate": True, "dc_resistance": False}, "seed": int(seed)}


def build_scenario(sc: dict):
    kind = sc["kind"]
    args = {k: (tuple(v) if isinstance(v, list) else v) for k, v in sc.items() if k != "kind"}
    return {"six_step": SixStep, "pwm": Pwm, "dol": Grid}[kind](**args)


def _plain(x):
    """numpy scalars/arrays and tuples -> plain YAML-safe Python values."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_plain(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x)
    if isinstance(x, (np.integer, int)) and not isinstance(x, bool):
        return int(x)
    return x


def make_dataset(spec: dict) -> Dataset:
    """Simulate the spec (see module docstring) and return the recorded data set."""
    motor = get_motor(spec["motor"])
    if spec.get("machine"):
        motor = motor.with_machine(replace(motor.machine, **spec["machine"]))
    Ts = 1.0 / float(spec["sample_rate"])
    scenario = build_scenario(spec["scenario"])
    K = scenario.samples() if scenario.kind == "six_step" else scenario.samples(Ts)
    duration = K * Ts - getattr(scenario, "pre_trigger", 0.0)
    build = Build(motor, scenario, duration, plant={"machine": motor.machine, "mechanics": Mechanics(),
                                                     "thermal": Thermal()},
                  sensors={k: v for k, v in (spec.get("sensors") or {}).items()})
    realised = []
    for eff in ordered(list(spec.get("effects") or [])):
        realised.append({**eff, **_plain(get_effect(eff["name"]).apply(build, eff))})
    plant, drive, M, inv, grid = _plant_and_drive(build, Ts, K, int(spec.get("oversampling", 10)))
    h = Ts / M
    pk = plant.pack()
    req = build.requests.get("temperature_drift")
    if req is not None:  # size the heat capacities from this test's own copper energies
        cold = simulate(replace(plant, thermal=Thermal()), drive)
        E_s, E_r = (float(np.sum(cold.col(c)[:-1]) * h) for c in ("P_s", "P_r"))
        core = core_of(req)
        if core is not None:  # three bodies: the winding's heat leaves into the core meanwhile
            P_s = cold.col("P_s")[:-1]
            E_s = float(np.sum(P_s * np.exp(-(len(P_s) - 1 - np.arange(len(P_s))) * h / core[0])) * h)
        sized = Thermal.sized(req["form"] == "two_body", E_s, E_r, req["size"], req["rotor_factor"],
                              req["time_constant"], motor.machine.theta_ref, core=core)
        plant = replace(plant, thermal=sized)
        pk = plant.pack()
    traj = simulate(plant, drive, packed=pk)
    out = traj.out
    if scenario.kind == "dol":
        v_step = terminal_voltage(out, drive, plant.source_L, h)
    else:
        v_step = drive.v_ideal
    timing = _channel_timing(build.skew, M, Ts)
    achieved = timing.pop("achieved")
    for eff in realised:
        if eff["name"] == "channel_delay":
            eff["achieved_size"] = achieved
    sensors = Sensors(**build.sensors, **timing)
    noise = Noise(**(spec.get("noise") or {}))
    rng = np.random.default_rng(int(spec["seed"]))
    rec = startup_record(out, COL, v_step, scenario.kind != "dol", K, M, h, sensors, noise, rng,
                         measured_voltage=scenario.kind == "dol")
    stop = None
    if spec.get("stop") and sensors.has_speed:  # a stop record is a speed record
        last = scenario.gates(K)[-1] if scenario.kind == "six_step" else np.zeros(3)
        stop = _free_stop(plant, pk, scenario, traj, K * Ts, Ts, M, spec["stop"], last, inv, grid, sensors, noise,
                          rng, motor)
    temps = out[:, [COL["theta_s"], COL["theta_r"]]]
    for eff in realised:
        if eff["name"] == "temperature_drift":
            eff["achieved_size"] = float(temps[K * M, 0] - temps[0, 0])
            eff["achieved_rotor_rise"] = float(temps[K * M, 1] - temps[0, 1])
    meta = {"kind": "startup", "pole_pairs": int(motor.machine.p), "sample_time": Ts,
            **_plain(scenario.meta(Ts))}
    flags = spec.get("meta") or {}
    if flags.get("dc_resistance"):
        meta["stator_dc_resistance"] = float(plant.machine.Rs)
        meta["winding_temperature"] = float(plant.machine.theta_ref)
    if flags.get("nameplate", True):
        meta["nameplate"] = _plain(motor.nameplate())
    truth = _truth(spec, motor, plant, realised, noise, scenario, M, traj)
    return Dataset(meta, rec, stop, truth, traj, plant)


def terminal_voltage(out: np.ndarray, drive, source_L: float, h: float) -> np.ndarray:
    """The motor-terminal alpha-beta voltage of a grid start at every internal step (n, 2):
    the voltage behind the source impedance's inductance (``out``'s ``v_a, v_b``: EMF minus the
    resistive and arc drops, the open pole's drop included) minus ``L_g di/dt``.

    At a step where the contactor changes (a pole closes, an arc starts or ends) the value is
    the one just after the change, extrapolated from the next two steps, which is what a
    voltmeter on the motor's terminals reads: the plant's first row of a new configuration is
    computed before the currents have moved, so an open pole's terminal would show the grid's
    EMF (its large resistance carries no current yet) instead of the motor's own back-EMF that a
    floating terminal sits at, and ``di/dt`` would be a central difference across the kink."""
    i_ab = out[:, [COL["i_a"], COL["i_b"]]]
    di = np.gradient(i_ab, h, axis=0)
    v = out[:-1, [COL["v_a"], COL["v_b"]]] - source_L * di[:-1]
    n = len(v)
    change = np.zeros(n, bool)
    change[1:] = (np.any(drive.closed[1:] != drive.closed[:-1], axis=1)
                  | np.any(drive.arc[1:] != drive.arc[:-1], axis=1) | (drive.mode[1:] != drive.mode[:-1]))
    for j in np.flatnonzero(change):
        if j + 2 < n and not change[j + 1] and not change[j + 2]:
            v[j] = 2.0 * v[j + 1] - v[j + 2]
        elif j + 1 < n:
            v[j] = v[j + 1]
    return v


def _channel_timing(skew: dict, M: int, Ts: float) -> dict:
    """The sensors' timing settings of the effects' channel skews (samples): common lags in
    internal steps, or a multiplexed card's per-phase lags (its slot realised to a multiple
    of ``1/M``), or a Bessel filter's group delay (s); ``achieved`` the realised size."""
    out = {"current_delay": int(round(skew["current"] * M)), "voltage_delay": int(round(skew["voltage"] * M))}
    out["achieved"] = (out["current_delay"] or out["voltage_delay"]) / M
    if skew.get("filter"):
        out.update(current_filter_delay=skew["filter"] * Ts, achieved=skew["filter"])
    if skew.get("mux"):
        slot = max(1, int(round(skew["mux"]["slot"] * M)))
        lag = {c: k * slot for k, c in enumerate(skew["mux"]["order"])}
        out.update(current_delays=(lag["i_r"], lag["i_s"]), voltage_delays=(lag["v_r"], lag["v_s"], lag["v_t"]),
                   achieved=slot / M)
    return out


def _plant_and_drive(build: Build, Ts: float, K: int, oversample: int):
    """The plant (with the grid's source impedance), its start-up drive, the steps per sample
    and the inverter and grid parameter arrays."""
    motor, scenario = build.motor, build.scenario
    plant = Plant(**build.plant)
    Z_lr = plant.locked_rotor_impedance(motor.frequency)
    if scenario.kind == "dol":
        Rg, Lg = scenario.source_impedance(Z_lr)
        plant = replace(plant, source_R=Rg, source_L=Lg)
    M = oversampling(plant, Ts, oversample)
    inv = plant.inverter.pack(getattr(scenario, "Ed", 0.0))
    if scenario.kind == "dol":
        R_open = OPEN_POLE_FACTOR * Z_lr
        sub = max(1, math.ceil(Ts / M * plant.fastest_rate(R_open) / 2.0))
        grid = scenario.pack(plant.source_R, R_open, 0.01 * motor.rated_current_peak)
        return plant, scenario.startup(Ts, M, K, grid, sub), M, inv, grid
    grid = np.zeros(11)
    return plant, scenario.startup(Ts, M, K, inv), M, inv, grid


def _free_stop(plant, pk, scenario, traj, t_start, Ts, M, stop_spec, last_gates, inv, grid, sensors, noise, rng, motor):
    """Free stop after supply removal: fine integration while the currents brake the rotor,
    then mechanics only (cheap). Returns ``{t, speed}`` at ``stop.sample_time``.

    The electrical part is over when the stator current is below 1e-3 of its start-up peak
    and the air-gap torque, acting for another rotor time constant, would change the speed
    by less than 1e-3 rad/s."""
    every = max(1, int(round(float(stop_spec.get("sample_time", 1e-3)) / Ts)))
    dt = every * Ts
    n_out = int(round(float(stop_spec["duration"]) / dt)) + 1
    x, im = traj.x, traj.im
    i_peak = float(np.max(np.hypot(traj.out[:, 0], traj.out[:, 1]))) or 1.0
    R_eq, L_eq = plant.cage().low_slip()
    tau_r = (L_eq + plant.mag_curve().Lm0) / R_eq
    J = plant.machine.J + plant.mechanics.J_load
    rows = []
    first = True
    while len(rows) < n_out:
        k = min(10, n_out - len(rows))
        drv = stop_drive(scenario, Ts, M, k * every, last_gates if first else np.ones(3), inv, grid)
        tr = simulate(plant, drv, x0=x, t0=t_start + len(rows) * dt, im=im, packed=pk)
        rows.extend(tr.out[:-1:every * M][:, [COL["w_l"], COL["theta"]]])
        x, im, first = tr.x, tr.im, False
        quiet = (np.max(np.abs(tr.out[:, COL["T_e"]])) * tau_r / J < 1e-3
                 and np.max(np.hypot(tr.out[:, 0], tr.out[:, 1])) < 1e-3 * i_peak)
        if quiet:
            break
    rows = np.array(rows)
    if len(rows) < n_out:
        rest = coast(plant, x, t_start + len(rows) * dt, (n_out - len(rows)) * dt, dt)
        rows = np.vstack([rows, rest[:n_out - len(rows)]])
    speed = sensed_speed(rows[:, 0], rows[:, 1], sensors, noise, rng, dt)
    return {"t": np.arange(n_out) * dt, "speed": speed}


def _truth(spec, motor, plant, realised, noise, scenario, M, traj) -> dict:
    m = plant.machine
    par = m.referred()
    par["J"] = m.J + plant.mechanics.J_load  # the rigid-body inertia a single-mass model sees
    cage = plant.cage()
    R_eq, L_eq = cage.low_slip()
    low = TMachine(m.Rs, m.Lls, L_eq, plant.mag_curve().Lm0, R_eq, m.p, m.J, m.fv, m.fc, m.theta_ref)
    par.update({k: v for k, v in low.referred().items() if k in ("Ls", "Le", "Rr")})
    plant_par = m.as_dict()
    plant_par.update({"Llr_low_slip": L_eq, "Rr_low_slip": R_eq, "rotor_loops": cage.n,
                      "source_R": plant.source_R, "source_L": plant.source_L})
    return _plain({
        "source": "independent", "seed": int(spec["seed"]), "motor": motor.name, "motor_source": motor.source,
        "parameters": par, "plant_parameters": plant_par,
        "effects": [{k: v for k, v in e.items()} for e in realised],
        "noise": noise.describe(), "scenario": scenario.describe(),
        "simulation": {"sample_rate": float(spec["sample_rate"]), "internal_steps_per_sample": int(M),
                       "unconverged_solves": int(traj.unconverged)},
        "spec": spec,
    })


def _write_csv(path: Path, cols: dict) -> None:
    names = list(cols)
    data = np.column_stack([np.asarray(cols[n], float) for n in names])
    np.savetxt(path, data, fmt="%.17g", delimiter=",", header=",".join(names), comments="")


def write_dataset(ds: Dataset, folder) -> Path:
    """Write ``meta.yaml``, ``startup.csv``, ``stop.csv`` (if any) and ``truth.yaml``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "meta.yaml", "w") as fh:
        yaml.safe_dump(_plain(ds.meta), fh, sort_keys=False)
    _write_csv(folder / "startup.csv", ds.startup)
    if ds.stop is not None:
        _write_csv(folder / "stop.csv", ds.stop)
    with open(folder / "truth.yaml", "w") as fh:
        yaml.safe_dump(_plain(ds.truth), fh, sort_keys=False)
    return folder

