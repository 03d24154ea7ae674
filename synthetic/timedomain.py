"""Synthetic start-up / free-stop data sets from known parameters.

The plant is the time-domain model (:mod:`benchmark.problems.timedomain.motor`; with effects,
the extended model) integrated with RK4 at ``plant_substeps`` steps per sample (finer than the
identification model's one step), so that the data are not the identification model's own
discretisation. Noise (``run.noise``): white noise on the two
current channels (A) and on speed (rad/s), and speed quantisation (rad/s), from the
generator ``numpy.random.default_rng(noise.seed)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from benchmark.core.errors import ConfigError
from benchmark.problems.timedomain.data import StartupDataset, StartupRecord, StopRecord, write_startup_dataset
from benchmark.problems.timedomain.motor import PARAMETER_NAMES, InductionMotor
from benchmark.problems.timedomain.protocol import StartupStopTest, run_startup_stop


def motor_from_config(run) -> InductionMotor:
    try:
        return InductionMotor(**{n: float(run["motor"]["parameters"][n]) for n in PARAMETER_NAMES},
                              p=int(run["motor"]["pole_pairs"]))
    except (KeyError, TypeError) as exc:
        raise ConfigError(f"motor.parameters: the preset must give {list(PARAMETER_NAMES)} and pole_pairs "
                          f"({exc})") from None
    except ValueError as exc:
        raise ConfigError(f"motor.parameters: {exc}") from None


def test_from_config(run) -> StartupStopTest:
    try:
        return StartupStopTest(**dict(run["motor"]["test"]))
    except TypeError as exc:
        raise ConfigError(f"motor.test: {exc}") from None


def add_noise(x: np.ndarray, std: float, quantum: float, rng: np.random.Generator) -> np.ndarray:
    y = x + rng.normal(0.0, std, size=x.shape) if std > 0 else x.copy()
    if quantum > 0:
        y = np.round(y / quantum) * quantum
    return y


def _run_extended(row: np.ndarray, test: StartupStopTest, substeps: int) -> dict:
    """Start-up and stop on an extended-model row, with the time running on through the stop
    (so that a load step keeps its instant)."""
    from benchmark.problems.timedomain.extended import N_STATES, simulate_extended
    from benchmark.problems.timedomain.protocol import _stop_record
    from benchmark.problems.timedomain.simulation import hold_is_linear

    t, v_a, v_b = test.startup_voltages()
    h = test.sample_time
    x = np.zeros(N_STATES)
    y = simulate_extended(row, v_a, v_b, hold_is_linear(test.input_hold), h, substeps, x, 0.0)
    startup = {"t": t, "v_alpha": v_a, "v_beta": v_b, "i_alpha": y[0], "i_beta": y[1], "speed": y[2]}
    # one more step with the last start-up voltage, then the stator is shorted (v = 0)
    simulate_extended(row, v_a[-1:].repeat(2), v_b[-1:].repeat(2), False, h, substeps, x, float(t[-1]))
    zeros = np.zeros(int(round(test.stop_duration / h)) + 1)
    w_m = simulate_extended(row, zeros, zeros, False, h, substeps, x, float(t[-1]) + h)[2]
    return {"startup": startup, "stop": _stop_record(w_m, test)}


def plant_with_effects(motor: InductionMotor, test: StartupStopTest, effects: list[str], sizes: dict,
                       forms: dict, substeps: int) -> tuple[dict, list[dict]]:
    """Simulate the experiment on the extended plant with the named effects injected.

    Row effects edit the extended-model row (``Effect.plant``); sensor effects then act on the
    simulated record, in the order of the sensor chain (``Effect.measure_stage``): the
    recorded voltages (``Effect.plant_voltages``) and currents and speed
    (``Effect.plant_measure`` with the extras of ``Effect.plant_extras``), the stop record's
    speed too. Sizes default to the geometric middle of each effect's realistic range.
    Returns the records and the list of injected effects (name, size, unit, form) for
    truth.yaml."""
    from benchmark.core.effects import effect_context, load_effects
    from benchmark.problems.timedomain.extended import base_row

    catalogue = load_effects("timedomain", names=list(effects))
    row = base_row(motor)
    base = _run_extended(row, test, substeps)["startup"]
    ctx = effect_context(base["t"], base["v_alpha"], base["v_beta"], base["i_alpha"], base["i_beta"],
                         base["speed"], motor.p, motor.J, motor.Ls - motor.Le, motor.Le,
                         test.dc_link_voltage)
    injected, sensors = [], []
    for name in effects:
        eff = catalogue[name]
        lo, hi = eff.realistic
        size = float(sizes.get(name, np.sqrt(lo * hi)))
        form = {**eff.form, **dict(forms.get(name, {}) or {})}
        row = eff.plant(row, size, ctx, form)
        entry = {"name": name, "size": size, "size_name": eff.size_name, "unit": eff.size_unit, "form": form}
        extras = eff.plant_extras(size, ctx, form)
        if extras is not None:
            entry["measure_extras"] = {n: float(v) for n, v in zip(eff.extra_names, np.ravel(extras), strict=False)}
        sensors.append((eff, size, form, extras))
        injected.append(entry)
    rec = _run_extended(row, test, substeps)
    s = rec["startup"]
    sensors.sort(key=lambda e: e[0].measure_stage)
    for eff, size, form, extras in sensors:
        s["v_alpha"], s["v_beta"] = eff.plant_voltages(s["v_alpha"], s["v_beta"], size, ctx, form)
        if extras is None:
            continue
        sim = eff.plant_measure(np.stack([s["i_alpha"], s["i_beta"], s["speed"]])[None], extras, ctx, form)[0]
        s["i_alpha"], s["i_beta"], s["speed"] = sim[0], sim[1], sim[2]
        st = rec["stop"]["speed"]
        stop = np.stack([np.zeros_like(st), np.zeros_like(st), st])[None]
        rec["stop"]["speed"] = eff.plant_measure(stop, extras, ctx, form)[0][2]
    return rec, injected


def make_dataset(run) -> tuple[StartupDataset, dict]:
    """The data set and its truth document for the composed config (motor preset, optional
    ``effects`` with ``effect_size``/``effect_form``, noise)."""
    motor = motor_from_config(run)
    test = test_from_config(run)
    substeps = int(run["motor"].get("plant_substeps", 4))
    effects = list(run.get("effects") or [])
    if effects:
        rec, injected = plant_with_effects(motor, test, effects, dict(run.get("effect_size") or {}),
                                           dict(run.get("effect_form") or {}), substeps)
    else:
        rec, injected = run_startup_stop(motor, test, substeps=substeps), []
    noise = run["noise"]
    rng = np.random.default_rng(int(noise["seed"]))
    s, st = rec["startup"], rec["stop"]
    startup = StartupRecord(
        t=s["t"],
        v_alpha=s["v_alpha"],
        v_beta=s["v_beta"],
        i_alpha=add_noise(s["i_alpha"], float(noise["current_std"]), 0.0, rng),
        i_beta=add_noise(s["i_beta"], float(noise["current_std"]), 0.0, rng),
        speed=add_noise(s["speed"], float(noise["speed_std"]), float(noise["speed_quantum"]), rng),
    )
    stops = []
    if run["motor"].get("record_stop", True):
        stops.append(StopRecord(t=st["t"], speed=add_noise(st["speed"], float(noise["speed_std"]),
                                                           float(noise["speed_quantum"]), rng)))
    ds = StartupDataset(
        pole_pairs=motor.p,
        sample_time=test.sample_time,
        startups=[startup],
        stops=stops,
        input_hold=test.input_hold,
        chord_voltage=test.input_hold == "linear",  # the plant interpolates its samples linearly
        dc_link_voltage=test.dc_link_voltage,
        supply_frequency=test.supply_frequency,
        inertia=float(motor.J) if run["motor"].get("inertia_known", False) else None,
    )
    truth = {
        "parameters": motor.as_dict(),
        "effects": injected,
        "noise": {k: float(noise[k]) for k in ("current_std", "speed_std", "speed_quantum")}
        | {"seed": int(noise["seed"])},
        "test": {k: (v if isinstance(v, str) else float(v)) for k, v in dict(run["motor"]["test"]).items()},
        "plant_substeps": int(run["motor"].get("plant_substeps", 4)),
    }
    return ds, truth


def generate(run, outdir: Path) -> Path:
    """Write the data set of :func:`make_dataset` (section 7 format + truth.yaml) to ``outdir``."""
    ds, truth = make_dataset(run)
    return write_startup_dataset(outdir, ds, truth=truth)
