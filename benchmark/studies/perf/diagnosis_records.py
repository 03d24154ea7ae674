"""The records of the perf study's diagnosis section: fourteen data sets from the three sources.

Each record is written by its own source's generator in a subprocess (the project's plant
``python -m synthetic``, the independent plant ``python -m synthetic.independent``, motulator
:func:`synthetic.motulator_source.make_motulator_dataset`), from a fixed seed, so the set is
the same on every machine. Together they cover direct-on-line, six-step and PWM starts, with
and without a stop record, 1 to 7.5 kW, 2 to 6 poles, no effect to two effects at once; the
first is the issue's slow case (0.8 s at 12 kHz of the independent plant's 1 kW motor on a
six-step start, probes that saturate softly and a flexible coupling, a 10 s stop at 1 kHz); the
last two are the kind the blind draws found slowest, a load in a form the catalogue lacks (a
battery charger), on the independent plant's 6-pole motor and on motulator's 2.2 kW motor (its
stop 24 s long: the charger brakes it only above its cut-in speed).

    python -m benchmark.studies.perf.diagnosis_records DIR      # writes DIR/<name>/ for each record
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from benchmark.core.config_files import CONFIG_DIR

#: (name, source, options). ``plant``: options of ``python -m synthetic.independent``;
#: ``own``: Hydra overrides of ``python -m synthetic``; ``motulator``: keyword arguments of
#: :func:`synthetic.motulator_source.make_motulator_dataset` (``motor``: ``preset`` is the
#: paper's 1 kW motor, else a zoo name).
RECORDS = (
    ("plant_1kw_sixstep_probe_coupling", "plant",
     "--motor paper_1kw --scenario six_step --effects current_sensor_saturation,two_mass --seed 1 "
     "--duration 0.8 --sample-rate 12000 --stop 10"),
    ("plant_1kw_sixstep_cage_mainsat", "plant",
     "--motor paper_1kw --scenario six_step --effects double_cage,main_saturation --seed 2 "
     "--duration 0.8 --sample-rate 12000 --stop 10"),
    ("plant_1kw_sixstep_heating_drop", "plant",
     "--motor paper_1kw --scenario six_step --effects temperature_drift,inverter_drop --seed 3 "
     "--duration 0.8 --sample-rate 12000 --stop 10"),
    ("plant_2k2_dol_offsets", "plant",
     "--motor motulator_2k2 --scenario dol --effects sensor_offset --seed 4 --duration 1.0 --stop 10"),
    ("plant_7k5_pwm_none", "plant", "--motor simulink_7k5 --scenario pwm --seed 5 --duration 1.0"),
    ("plant_6pole_dol_leakage", "plant",
     "--motor fitzgerald_6pole --scenario dol --effects leakage_saturation --seed 6 --duration 1.0 --stop 10"),
    ("plant_3k7_sixstep_load", "plant",
     "--motor simulink_5hp --scenario six_step --effects load_torque --seed 7 --duration 1.0 --stop 10"),
    ("own_1kw_sixstep_cage", "own", "effects=[double_cage] noise=noisy seed=0"),
    ("own_1kw_dol_load_nostop", "own",
     "effects=[load_torque] noise=noisy seed=1 motor.test.waveform=sinusoidal motor.record_stop=false"),
    ("motulator_1kw_sixstep_mainsat", "motulator",
     {"motor": "preset", "scenario": "six_step", "effects": {"main_saturation": {"size": 0.3, "exponent": 4.0}},
      "seed": 8, "stop": True}),
    ("motulator_2k2_dol_coupling_load", "motulator",
     {"motor": "motulator_2p2kw", "scenario": "dol",
      "effects": {"two_mass": {"size": 0.4, "resonance_hz": 25.0, "damping_ratio": 0.1},
                  "load_torque": {"form": "quadratic", "size": 0.4}}, "seed": 9, "stop": True}),
    ("motulator_1kw_pwm_none_nostop", "motulator",
     {"motor": "preset", "scenario": "pwm", "effects": None, "seed": 10, "stop": False}),
    # the slow kind the blind draws show: a load in a form the catalogue lacks (a battery charger
    # cutting in above a speed), whose fits carry the load's eight parameters into every round
    ("plant_6pole_sixstep_charger", "plant",
     "--motor fitzgerald_6pole --scenario six_step --effects load_torque --forms load_torque=battery_charger "
     "--seed 11 --duration 1.0 --stop 10"),
    ("motulator_2k2_sixstep_charger", "motulator",
     {"motor": "motulator_2p2kw", "scenario": "six_step",
      "effects": {"load_torque": {"form": "battery_charger", "time": 0.2, "cut_in_ratio": 0.4, "size": 0.5}},
      "seed": 12, "stop": True}),
)

#: motulator's noise (the blind source's middle values) and record: 0.6 s at 12 kHz.
MOTULATOR_NOISE = {"current_std": 0.05, "current_colored_std": 0.02, "speed_std": 0.1, "speed_quantum": 0.1}
MOTULATOR_DURATION, MOTULATOR_RATE = 0.6, 12000.0


def motulator_motor(name: str) -> dict:
    """The motor description ``make_motulator_dataset`` takes: the paper's 1 kW motor (``preset``,
    ``conf/motor/timedomain.yaml``) or a zoo motor."""
    if name == "preset":
        import yaml


        m = yaml.safe_load((CONFIG_DIR / "motor" / "alonge_1kw.yaml").read_text())
        return {"parameters": dict(m["parameters"]), "pole_pairs": int(m["pole_pairs"]), "frequency": 50.0,
                "dc_link_voltage": float(m["test"]["dc_link_voltage"]), "rated_power": 1000.0}
    from synthetic.zoo import get_motor, motor_description

    return motor_description(get_motor(name))


def make_motulator(options: dict, folder: Path) -> None:
    from synthetic.motulator_source import make_motulator_dataset

    make_motulator_dataset(motulator_motor(options["motor"]), options["scenario"], options["effects"],
                           MOTULATOR_NOISE, int(options["seed"]), folder, MOTULATOR_DURATION, MOTULATOR_RATE,
                           bool(options["stop"]))


def command(source: str, options, folder: Path) -> list[str]:
    """The command that writes one record into ``folder``."""
    if source == "plant":
        return [sys.executable, "-m", "synthetic.independent", *options.split(), "--out", str(folder)]
    if source == "own":
        return [sys.executable, "-m", "synthetic", f"out={folder}", *options.split()]
    return [sys.executable, "-m", "benchmark.studies.perf.diagnosis_records", "--motulator", json.dumps(options),
            str(folder)]


def make_records(root: Path, names: list[str] | None = None) -> list[tuple[str, Path]]:
    """Write each record (those named, or all) into ``root/<name>`` unless it is there already."""
    out = []
    for name, source, options in RECORDS:
        if names and name not in names:
            continue
        folder = Path(root) / name
        if not (folder / "meta.yaml").exists():
            subprocess.run(command(source, options, folder), check=True, capture_output=True, text=True)
        out.append((name, folder))
    return out


if __name__ == "__main__":
    if sys.argv[1] == "--motulator":
        make_motulator(json.loads(sys.argv[2]), Path(sys.argv[3]))
    else:
        for name, folder in make_records(Path(sys.argv[1]), sys.argv[2:] or None):
            print(name, folder)
