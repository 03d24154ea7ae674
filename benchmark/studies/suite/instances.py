"""Instance data sets, written once into the suite's cache folder (``CACHE/data/NAME/``) and reused.

**Time domain** (:func:`synthetic.zoo.make_zoo_dataset`): a zoo motor's start-up from the
independent plant or motulator, no motor preset: the harness derives the bounds from the data
as it does for a user's folder. Record: the zoo's recommended sample rate and length
(:func:`synthetic.zoo.recommended_settings`; a PWM V/f start 1.6 times longer for its ramp),
the sample rate lowered to fit the suite's ``records.max_samples`` but not below
``records.min_sample_rate``. Noise: ``none``; ``white`` (the zoo's: 0.3 % of the rated peak
current, speed noise and a speed quantum of 0.1 % of synchronous speed); ``coloured`` (the
zoo's coloured current noise, on the independent plant with a 12-bit current ADC, and the
speed quantised at 0.32 % of synchronous speed: 0.5 rad/s on a 4-pole 50 Hz motor).
``effect``: one unmodelled effect of the independent plant at a size drawn from its realistic
range (model error). An explicit instance's ``settings`` (``friction: {fv, fc}``, ``noise``,
``duration``, ``sample_rate``) replace these rules.

**Admittance** (:func:`synthetic.admittance.make_dataset`): a zoo motor's T circuit at its rated
frequency (``X = 2 pi f L``), with a series core-loss resistance ``R0 = X0 / 15`` (the ratio of
Lindsay and Barton's machine) and, for an 8-parameter machine, their machine's ratios
``R1sigma = 0.03 R1``, ``R2sigma = 0.116 R2``, ``X3 = 0.0167 X2``. The sweep at 24 % of the rated
phase voltage (their 30.2 V of 127 V) in steps of 1/18 of synchronous speed; windings warming
by their thermal model scaled with the rated power. Bounds: the problem's own derivation from
the data (model A's reading of the synchronous and standstill admittances, a factor 4 either
side), widened by a further factor 2.5, recorded in ``instance.yaml`` (a box that wide around
the answer, so the global optimisers have something to search).

``instance.yaml`` beside the data records the instance: its spec, data seed, group labels and
(admittance) bounds.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import yaml

from benchmark.core.io import write_yaml_atomic
from benchmark.studies.suite.spec import InstanceSpec

SPEED_QUANTUM_COLOURED = 0.0032  # of synchronous speed
LB_RATIOS = {"R1sigma": 0.03, "R2sigma": 0.116, "X3": 0.0167, "X0_over_R0": 15.0}
LB_POWER = 5595.0  # W, Lindsay and Barton's 7.5 hp machine (its thermal model's scale)
ADMITTANCE_WIDEN = 2.5


def data_folder(cache: Path, name: str) -> Path:
    return Path(cache) / "data" / name


def size_class(power_w: float) -> str:
    kw = power_w / 1e3
    return "<= 5 kW" if kw <= 5 else "5-50 kW" if kw <= 50 else "> 50 kW"


def groups(inst: InstanceSpec, motor) -> dict[str, str]:
    """The instance's label in each group the measures are broken down by."""
    if inst.problem == "timedomain":
        exp = inst.experiment + (" + stop" if inst.stop else "")
        noise = str(inst.noise)
        error = inst.effect if inst.effect != "none" else "stop held by the inverter" if inst.held_stop else "none"
    else:
        exp = f"{inst.experiment} sweep"
        noise = f"{100 * float(inst.noise):g} %"
        error = "8-parameter machine, 6 fitted" if inst.model_error else "none"
    return {"problem": inst.problem, "size": size_class(motor.rated_power), "pole pairs": f"p = {motor.pole_pairs}",
            "experiment": exp, "noise": noise, "model error": error, "source": inst.source}


def _timedomain_noise(motor, kind: str, source: str) -> dict:
    from synthetic.zoo import independent_noise, motulator_noise, synchronous_speed

    if kind == "none":
        return {}
    noise = (independent_noise if source == "independent" else motulator_noise)(motor, kind)
    if kind == "coloured":
        noise["speed_quantum"] = SPEED_QUANTUM_COLOURED * synchronous_speed(motor)
    return noise


def record_settings(motor, inst: InstanceSpec, records: dict) -> tuple[float, float]:
    """(sample rate Hz, start-up length s) of a time-domain instance (module docstring)."""
    from synthetic.zoo import recommended_settings

    rec = recommended_settings(motor)
    duration = float(inst.settings.get("duration") or rec["duration"] * (1.6 if inst.experiment == "pwm" else 1.0))
    fs = float(inst.settings.get("sample_rate") or rec["sample_rate"])
    cap = records.get("max_samples")
    if cap and "sample_rate" not in inst.settings and fs * duration > cap:
        fs = max(float(records.get("min_sample_rate", 4000)), 500.0 * math.floor(cap / duration / 500.0))
    return fs, duration


def _make_timedomain(inst: InstanceSpec, folder: Path, records: dict) -> dict:
    from synthetic.zoo import get_motor, make_zoo_dataset

    motor = get_motor(inst.motor)
    friction = inst.settings.get("friction")
    if friction:
        motor = replace(motor, fv=float(friction["fv"]), fc=float(friction["fc"]))
    fs, duration = record_settings(motor, inst, records)
    noise = inst.settings.get("noise")
    noise = dict(noise) if noise is not None else _timedomain_noise(motor, str(inst.noise), inst.source)
    effects = {} if inst.effect == "none" else {inst.effect: {}}
    make_zoo_dataset(motor, scenario=inst.experiment, noise=noise, seed=inst.seed, out=folder, source=inst.source,
                     effects=effects, stop=inst.stop, duration=duration, sample_rate=fs)
    return {"sample_rate": fs, "duration": duration, "noise_settings": noise}


def admittance_run(inst: InstanceSpec) -> dict:
    """The synthetic generator's run configuration for an admittance instance (module docstring)."""
    from synthetic.zoo import get_motor

    m = get_motor(inst.motor)
    w = 2 * math.pi * m.frequency
    X0 = w * m.Lm
    p = {"R1": m.Rs, "X1": w * m.Lls, "R2": m.Rr, "X2": w * m.Llr, "R0": X0 / LB_RATIOS["X0_over_R0"], "X0": X0}
    if inst.data_model == 8:
        p.update(R1sigma=LB_RATIOS["R1sigma"] * m.Rs, R2sigma=LB_RATIOS["R2sigma"] * m.Rr,
                 X3=LB_RATIOS["X3"] * p["X2"])
    n_sync = 60 * m.frequency / m.pole_pairs
    full = inst.experiment == "full"
    k = m.rated_power / LB_POWER
    test = {"voltages": [0.24 * m.voltage / math.sqrt(3)], "speed_start_rpm": -n_sync if full else 0.0,
            "speed_stop_rpm": 4 * n_sync / 3 if full else n_sync, "speed_step_rpm": n_sync / 18,
            "ramp_rpm_per_s": n_sync / 72, "down_sweep": False, "settle_s": 20.0, "dc_after_delay_s": 5.0,
            "warming": True, "record_torque": True}
    thermal = {"initial_temperature": 50.0, "ambient_temperature": 25.0, "capacitance": 11300.0 * k,
               "conductance_standstill": 8.0 * k, "conductance_at_speed": 20.0 * k,
               "conductance_speed_rpm": n_sync}
    motor = {"name": m.name, "frequency": m.frequency, "pole_pairs": m.pole_pairs, "reference_temperature": 50.0,
             "parameters": p, "test": test, "thermal": thermal}
    return {"motor": motor, "noise": {"admittance_fraction": float(inst.noise), "seed": inst.seed}}


def admittance_bounds(folder: Path, model: int) -> dict[str, list[float]]:
    """The problem's bounds from the data, widened by :data:`ADMITTANCE_WIDEN` (module docstring)."""
    from benchmark.problems.admittance.data import load_admittance
    from benchmark.problems.admittance.problem import parameter_names_for
    from benchmark.problems.admittance.setup import derive_bounds

    b = derive_bounds(load_admittance(folder), parameter_names_for(int(model), False))
    return {n: [lo / ADMITTANCE_WIDEN if lo > 0 else 0.0, hi * ADMITTANCE_WIDEN] for n, (lo, hi) in b.items()}


def _make_admittance(inst: InstanceSpec, folder: Path) -> dict:
    from benchmark.problems.admittance.data import write_admittance
    from synthetic.admittance import make_dataset

    data, truth = make_dataset(admittance_run(inst))
    write_admittance(folder, data, truth=truth)
    return {"bounds": admittance_bounds(folder, int(inst.model))}


def build_instance(inst: InstanceSpec, cache: Path, records: dict, fresh: bool = False) -> Path:
    """The instance's data folder, written unless ``instance.yaml`` is there already."""
    from synthetic.zoo import get_motor

    folder = data_folder(cache, inst.name)
    done = folder / "instance.yaml"
    if done.is_file() and not fresh:
        return folder
    folder.mkdir(parents=True, exist_ok=True)
    made = _make_timedomain(inst, folder, records) if inst.problem == "timedomain" else _make_admittance(inst, folder)
    m = get_motor(inst.motor)
    doc = {"name": inst.name, "problem": inst.problem, "motor": inst.motor, "rated_power": m.rated_power,
           "pole_pairs": m.pole_pairs, "source": inst.source, "experiment": inst.experiment, "stop": inst.stop,
           "noise": inst.noise, "effect": inst.effect, "model": inst.model, "data_model": inst.data_model,
           "model_error": inst.model_error, "seed": inst.seed, "settings": inst.settings,
           "groups": groups(inst, m), **made}
    write_yaml_atomic(done, doc)
    return folder


def read_instance(folder: Path) -> dict:
    return yaml.safe_load((Path(folder) / "instance.yaml").read_text(encoding="utf-8"))


def harness_config(doc: dict, folder: Path) -> dict:
    """What an instance sets in a run's configuration: problem, data folder, bounds, model; on the
    time domain ``stator_resistance=free`` (the default ``auto`` puts a prior on Rs where meta.yaml
    gives its DC value, weighed at each run's own fit: the suite compares optimisers on one cost)."""
    cfg: dict = {"problem": doc["problem"], "data": {"path": str(Path(folder).resolve())}}
    if doc["problem"] == "admittance":
        cfg["bounds"] = doc["bounds"]
        cfg["problem_options"] = {"model": int(doc["model"])}
    else:  # one fixed cost per instance: no prior on Rs, whose weight a run would calibrate at its own fit
        cfg["problem_options"] = {"stator_resistance": "free"}
    return cfg
