"""Sim-to-real diagnosis (time domain): extended model, effect catalogue, verdicts, blindness."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from benchmark.core.effects import load_effects
from benchmark.problems.timedomain.extended import IDX, base_row, simulate_extended_batch
from benchmark.problems.timedomain.motor import coefficients
from benchmark.problems.timedomain.protocol import StartupStopTest
from benchmark.problems.timedomain.simulation import startup_outputs_batch
from tests.conftest import PAPER_MOTOR, compose_config

EFFECTS = load_effects("timedomain")


def test_catalogue_has_the_interface_names():
    assert set(EFFECTS) == {"coulomb_friction", "double_cage", "main_saturation", "iron_loss",
                            "temperature_drift", "leakage_saturation", "inverter_drop"}
    for eff in EFFECTS.values():
        lo, hi = eff.realistic
        assert 0 < lo < hi
        elo, ehi = eff.extra_bounds(_ctx())
        assert len(elo) == len(eff.extra_names) and np.all(elo < ehi)


def _ctx():
    from benchmark.core.effects import EffectContext

    return EffectContext(w_e=2 * np.pi * 50, V1=191.0, I_peak=28.0, w_sync=2 * np.pi * 50, dc_link_voltage=300.0,
                         E_cu=600.0, L_M=PAPER_MOTOR.Ls - PAPER_MOTOR.Le, L_sigma=PAPER_MOTOR.Le)


def test_extended_model_with_neutral_effects_is_the_base_model():
    t, va, vb = StartupStopTest(cycles=20).startup_voltages()
    ref = startup_outputs_batch(coefficients(PAPER_MOTOR.vector()[None], 1), va, vb, False, 1 / 12000, 1.0)[0]
    ext = simulate_extended_batch(base_row(PAPER_MOTOR)[None], va, vb, False, 1 / 12000, 1)[0]
    np.testing.assert_allclose(ext, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_each_effect_changes_the_plant_and_its_augmentation_can_reproduce_it(name):
    """Injected at a mid-realistic size, every effect moves the outputs well above a sensor's
    noise; the augmentation with the plant's own values gives the same model row."""
    eff = EFFECTS[name]
    ctx = _ctx()
    base = base_row({**PAPER_MOTOR.as_dict(), "fc": 0.0} if name == "coulomb_friction" else PAPER_MOTOR)
    lo, hi = eff.realistic
    size = float(np.sqrt(lo * hi))
    row = eff.plant(base, size, ctx)
    t, va, vb = StartupStopTest(cycles=15).startup_voltages()
    out = simulate_extended_batch(np.stack([base, row]), va, vb, False, 1 / 12000, 1)
    diff_i = np.max(np.abs(out[1, :2] - out[0, :2]))
    diff_w = np.max(np.abs(out[1, 2] - out[0, 2]))
    assert diff_i > 0.05 or diff_w > 0.2, (name, diff_i, diff_w)
    # the augmentation's parameter space contains the plant (default form)
    changed = np.flatnonzero(~np.isclose(row, base))
    assert len(changed) > 0
    for k in changed:
        assert list(IDX)[k] in {"fc", "R_r1", "R_r2", "L_sigma2", "ms_k", "ms_psi", "ms_exp", "g_fe", "h_th",
                                "ls_k", "ls_psi", "ls_exp", "U_d", "i_0"}


def _diagnose(tmp_path, effects, candidates, name):
    from benchmark.core.harness import run_diagnosis

    cfg = compose_config([f"effects={effects}", "noise=noisy", "motor.parameters.fc=0", "budget=3000",
                          "motor.test.cycles=25", "motor.test.stop_duration=25",
                          "polish_budget=600", f"candidates={candidates}", "diagnosis.fit_evaluations=250",
                          "figures=false"], name="diagnose")
    return run_diagnosis(cfg, tmp_path / name)


CANDIDATES = "[double_cage,leakage_saturation,coulomb_friction]"


def test_double_cage_is_named_and_the_gap_shrinks(tmp_path):
    doc = _diagnose(tmp_path, "[double_cage]", CANDIDATES, "dc")
    assert doc["verdict"] == "double_cage"
    top = doc["ranking"][0]
    assert top["effect"] == "double_cage" and top["heldout_reduction"] > 0.5
    assert doc["gap_after"]["heldout_rms_over_noise"] < 0.7 * doc["gap_before"]["heldout_rms_over_noise"]
    segments = doc["localisation"]["by_segment"]
    assert segments["electrical_start"] + segments["acceleration"] > 0.5
    saved = json.loads((tmp_path / "dc" / "diagnosis.json").read_text())
    assert {"verdict", "ranking", "localisation", "gap_before", "gap_after"} <= set(saved)
    assert {"effect", "heldout_reduction", "in_sample_reduction", "criterion"} <= set(saved["ranking"][0])


def test_effect_free_data_gives_none(tmp_path):
    doc = _diagnose(tmp_path, "[]", CANDIDATES, "none")
    assert doc["verdict"] == "none"
    assert all(r["heldout_reduction"] < 0.02 for r in doc["ranking"])


def test_diagnosis_never_opens_truth_files(tmp_path):
    ds = tmp_path / "ds"
    proc = subprocess.run([sys.executable, "-m", "synthetic", "effects=[double_cage]", f"out={ds}",
                           "motor.test.cycles=10", "motor.test.stop_duration=2.0"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert (ds / "truth.yaml").is_file()
    script = textwrap.dedent(f"""
        import sys
        opened = []
        def hook(event, args):
            if event == "open":
                opened.append(str(args[0]))
        sys.addaudithook(hook)
        from pathlib import Path
        from tests.conftest import compose_config
        from benchmark.core.harness import run_diagnosis
        cfg = compose_config(["data.path={ds}", "budget=300", "polish_budget=100", "candidates=[double_cage]",
                              "diagnosis.fit_evaluations=60", "figures=false"], name="diagnose")
        doc = run_diagnosis(cfg, Path("{tmp_path / 'out'}"))
        print("VERDICT", doc["verdict"])
        print("OPENED_TRUTH", [p for p in opened if "truth" in Path(p).name])
        print("OPENED_DATA", any(p.endswith("startup.csv") for p in opened))
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, cwd=str(
        __import__("pathlib").Path(__file__).resolve().parents[3]))
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "OPENED_TRUTH []" in proc.stdout
    assert "OPENED_DATA True" in proc.stdout  # the hook does see the files the diagnosis reads
