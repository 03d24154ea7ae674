"""Sim-to-real diagnosis of the slip sweep: effect catalogue, verdicts, blindness.

Data: the bare 6-parameter Lindsay-Barton machine, two voltage levels (20 and 50 V) each swept up
and down, 0.03 % of full-scale noise; each effect at the geometric middle of its realistic range.
"""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from benchmark.core.effects import load_effects
from benchmark.problems.admittance.circuit import input_admittance
from benchmark.problems.admittance.diagnosis.pipeline import AdmittanceDiagnosisSettings, diagnose_sweep
from benchmark.problems.admittance.sweep_circuit import SweepCircuit
from synthetic.admittance import make_dataset
from tests.conftest import compose_config

ROOT = Path(__file__).resolve().parents[3]
EFFECTS = load_effects("admittance")
TEST = [
    "problem=admittance",
    "motor.test.voltages=[20.0,50.0]",
    "motor.test.down_sweep=true",
    "motor.test.full_scale_admittance=1.0",
    "noise.admittance_fraction=0.0003",
    "noise.seed=5",
]


def sweep(effect: str, *extra):
    cfg = compose_config([*TEST, f"effects=[{effect}]", *extra], name="synthetic")
    return make_dataset(cfg)


def test_catalogue_has_the_six_sweep_effects_with_sizes_and_ranges():
    assert set(EFFECTS) == {
        "double_cage",
        "main_saturation",
        "iron_loss",
        "temperature_drift",
        "leakage_saturation",
        "leakage_core_loss",
    }
    for eff in EFFECTS.values():
        lo, hi = eff.realistic
        assert 0 < lo < hi and eff.size_name and eff.extra_names and eff.problem == "admittance"


def test_generalised_circuit_without_hooks_is_the_8_parameter_circuit():
    p = {
        "R1": 0.2,
        "R1sigma": 0.006,
        "X1": 0.56,
        "R2": 0.29,
        "R2sigma": 0.034,
        "X2": 0.55,
        "X3": 0.009,
        "R0": 1.06,
        "X0": 16.1,
    }
    s = np.linspace(-0.4, 2.0, 37)
    Y = SweepCircuit.from_parameters(p).admittance(s, 30.0)
    ref = input_admittance(
        s, p["R1"] + p["R1sigma"], p["X1"], p["R2"], p["X2"], p["R0"], p["X0"], p["R2sigma"], p["X3"]
    )
    assert np.max(np.abs(Y - ref)) < 1e-14


def test_effects_list_gives_exactly_the_named_effects():
    data, truth = sweep("none")
    assert truth["effects"] == [] and truth["parameters"]["R2sigma"] == 0.0
    assert truth["temperature"]["before"] == truth["temperature"]["after"]  # no warming
    data2, truth2 = sweep("temperature_drift", "+effect_size={temperature_drift: 8.0}")
    rise = truth2["temperature"]["last_reading"] - truth2["temperature"]["first_reading"]
    assert 7.9 < rise < 8.1  # the rise from the first reading to the hottest
    assert truth2["effects"][0]["name"] == "temperature_drift"


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_each_effect_at_a_mid_realistic_size_is_named(name):
    data, _truth = sweep(name)
    doc = diagnose_sweep(data, EFFECTS, AdmittanceDiagnosisSettings())
    assert doc["verdict"] == name, [(r["effect"], round(r["heldout_reduction"], 3)) for r in doc["ranking"]]
    # the contract shared with the time-domain diagnosis
    assert doc["status"] in ("explained", "partly_explained") and doc["effects"] == [name]
    assert 0.3 <= doc["explained_share"] <= 1.0
    top = doc["ranking"][0]
    assert top["effect"] == name and top["criterion"] < 0
    assert doc["gap_after"]["heldout_rms_over_noise"] < doc["gap_before"]["heldout_rms_over_noise"]


def test_effect_free_sweep_gives_none():
    data, _truth = sweep("none")
    doc = diagnose_sweep(data, EFFECTS, AdmittanceDiagnosisSettings())
    assert doc["verdict"] == "none"
    assert doc["status"] == "no_gap" and doc["effects"] == [] and doc["explained_share"] == 0.0
    assert doc["gap_before"]["heldout_chi2_per_residual"] < 1.5
    assert all(r["heldout_reduction"] < 0.05 for r in doc["ranking"])
    assert 0.7 < doc["noise_level"]["percent_of_full_scale"] / 0.03 < 1.3  # noise estimated from the data


def test_cli_writes_the_diagnosis_and_never_opens_truth(tmp_path):
    ds = tmp_path / "ds"
    proc = subprocess.run(
        [sys.executable, "-m", "synthetic", *TEST, "effects=[leakage_core_loss]", f"out={ds}"],
        capture_output=True,
        text=True,
        cwd=str(ROOT),
    )
    assert proc.returncode == 0, proc.stderr
    assert (ds / "truth.yaml").is_file()
    out = tmp_path / "out"
    script = textwrap.dedent(f"""
        import runpy, sys
        opened = []
        def hook(event, args):
            if event == "open":
                opened.append(str(args[0]))
        sys.addaudithook(hook)
        sys.argv = ["diagnose", "problem=admittance", "data.path={ds}", "hydra.run.dir={out}"]
        try:
            runpy.run_module("benchmark.diagnose", run_name="__main__")
        except SystemExit as exc:
            assert not exc.code, exc.code
        from pathlib import Path
        print("OPENED_TRUTH", [p for p in opened if "truth" in Path(p).name])
        print("OPENED_DATA", any(p.endswith("sweep01.csv") for p in opened))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=str(ROOT))
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "OPENED_TRUTH []" in proc.stdout
    assert "OPENED_DATA True" in proc.stdout  # the hook does see the files the diagnosis reads
    doc = json.loads((out / "diagnosis.json").read_text())
    assert doc["verdict"] == "leakage_core_loss"
    assert {"verdict", "ranking", "localisation", "gap_before", "gap_after"} <= set(doc)
    assert {"effect", "heldout_reduction", "in_sample_reduction", "criterion"} <= set(doc["ranking"][0])
    assert set(doc["localisation"]["by_slip_region"]) == {"braking", "motoring", "near_synchronism", "generating"}
    assert set(doc["localisation"]["by_channel"]) == {"G", "B"}
    assert (out / "diagnosis.md").is_file() and (out / "residual_map.png").is_file()
    # each candidate's extra parameters carry their units, in the JSON and in the candidates table
    lcl = next(r for r in doc["ranking"] if r["effect"] == "leakage_core_loss")
    assert lcl["extra_parameter_units"] == {"R2sigma_pu": "p.u. of R2"}
    row = next(line for line in (out / "diagnosis.md").read_text().splitlines()
               if line.startswith("| leakage_core_loss |"))
    assert f"R2sigma_pu = {lcl['extra_parameters']['R2sigma_pu']:.4g} p.u. of R2 |" in row
