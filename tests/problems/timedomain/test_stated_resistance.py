"""A DC stator resistance stated in meta.yaml is reported beside the diagnosis's final Rs: the
deviation, the copper winding temperature it would take, and whether the diagnosis used it (its
base fits Rs from the record unless ``problem.stator_resistance`` asks for the prior)."""

from __future__ import annotations

import subprocess
import sys
from types import SimpleNamespace

import pytest
import yaml

from benchmark.problems.timedomain.diagnosis.run import (
    render_markdown,
    stated_resistance_check,
    stated_resistance_lines,
)
from benchmark.problems.timedomain.stator_prior import copper_temperature
from tests.conftest import compose_config


def test_copper_temperature_inverts_the_copper_law():
    assert copper_temperature(1.0, 1.0) == pytest.approx(20.0)
    assert copper_temperature(1.0 + 20.0 / 254.5, 1.0) == pytest.approx(40.0)  # +7.9 % at 20 C is 20 K warmer
    assert copper_temperature(2.0, 1.0, winding_temperature=40.0) == pytest.approx(2 * 274.5 - 234.5)


def test_a_resistance_no_winding_reaches_is_said_so():
    ds = SimpleNamespace(stator_dc_resistance=2.0, winding_temperature=None)
    check = stated_resistance_check(ds, {"Rs": 6.0}, "free")
    assert check["relative_deviation"] == pytest.approx(2.0) and not check["used"]
    assert check["copper_temperature_C"] == pytest.approx(3 * 254.5 - 234.5) and not check["copper_can_reach"]
    (line,) = stated_resistance_lines(check)
    assert "+200 % off it" in line and "which no winding reaches" in line and "not used" in line
    near = stated_resistance_check(SimpleNamespace(stator_dc_resistance=2.0, winding_temperature=25.0),
                                   {"Rs": 2.1}, "prior")
    assert near["copper_can_reach"] and near["used"]
    (line,) = stated_resistance_lines(near)
    assert "at 25 deg C, used as the run asks" in line and "no winding" not in line
    assert stated_resistance_check(SimpleNamespace(stator_dc_resistance=None), {"Rs": 2.1}, "free") is None


def test_a_diagnosed_record_with_a_stated_resistance_reports_it(tmp_path):
    """End to end on a written record: meta.yaml states the true Rs at 20 deg C; the document and
    diagnosis.md compare the final model's Rs with it."""
    from benchmark.core.harness import run_diagnosis

    ds = tmp_path / "ds"
    proc = subprocess.run([sys.executable, "-m", "synthetic", "effects=[]", "noise=noisy", f"out={ds}",
                           "motor.test.cycles=10", "motor.test.stop_duration=2.0"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    rs_true = float(yaml.safe_load((ds / "truth.yaml").read_text())["parameters"]["Rs"])
    (ds / "truth.yaml").unlink()
    meta = yaml.safe_load((ds / "meta.yaml").read_text())
    (ds / "meta.yaml").write_text(yaml.safe_dump({**meta, "stator_dc_resistance": rs_true}))
    cfg = compose_config([f"data.path={ds}", "budget=300", "polish_budget=100", "candidates=[double_cage]",
                          "diagnosis.max_iterations=4", "figures=false"], name="diagnose")
    doc = run_diagnosis(cfg, tmp_path / "out")
    check = doc["stator_dc_resistance"]
    assert check["ohm"] == rs_true and check["used"] is False and check["winding_temperature_C"] is None
    assert check["final_Rs_ohm"] == doc["base"]["estimate"]["Rs"]
    assert abs(check["relative_deviation"]) < 0.05 and check["copper_can_reach"]
    assert "Stated DC stator resistance (meta.yaml)" in (tmp_path / "out" / "diagnosis.md").read_text()
    assert "Stated DC" not in render_markdown({**doc, "stator_dc_resistance": None})
