"""Synthetic start-up / free-stop data sets from known parameters.

The plant is the model of MODEL.md section 1 integrated with RK4 at ``plant_substeps`` steps
per sample (finer than the identification model's one step), so that the data are not the
identification model's own discretisation. Noise (``run.noise``): white noise on the two
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
        raise ConfigError(f"motor.parameters: the preset must give {list(PARAMETER_NAMES)} and pole_pairs ({exc})") from None
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


def plant_with_effects(motor: InductionMotor, test: StartupStopTest, effects: list[str], sizes: dict,
                       forms: dict, substeps: int) -> tuple[dict, list[dict]]:
    """Simulate the experiment on the extended plant with the named effects injected.

    Sizes default to the geometric middle of each effect's realistic range. Returns the
    records and the list of injected effects (name, size, unit, form) for truth.yaml."""
    from benchmark.core.effects import effect_context, load_effects
    from benchmark.problems.timedomain.extended import base_row
    from benchmark.problems.timedomain.protocol import run_startup_stop_extended

    catalogue = load_effects("timedomain", names=list(effects))
    row = base_row(motor)
    base = run_startup_stop_extended(row, test, substeps)["startup"]
    ctx = effect_context(base["t"], base["v_alpha"], base["v_beta"], base["i_alpha"], base["i_beta"],
                         base["speed"], motor.p, motor.J, motor.Ls - motor.Le, motor.Le,
                         test.dc_link_voltage)
    injected = []
    for name in effects:
        eff = catalogue[name]
        lo, hi = eff.realistic
        size = float(sizes.get(name, np.sqrt(lo * hi)))
        form = {**eff.form, **dict(forms.get(name, {}) or {})}
        row = eff.plant(row, size, ctx, form)
        injected.append({"name": name, "size": size, "size_name": eff.size_name, "unit": eff.size_unit,
                         "form": form})
    return run_startup_stop_extended(row, test, substeps), injected


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
