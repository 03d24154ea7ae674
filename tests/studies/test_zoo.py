"""The motor zoo study: the independent-plant adapter of synthetic.zoo and the study's scoring."""

from __future__ import annotations

import math

import pytest
import yaml

from benchmark.studies import zoo as study
from synthetic.zoo import (
    get_motor,
    independent_motor,
    independent_noise,
    load_zoo,
    make_zoo_dataset,
    project_parameters,
)


def test_the_zoo_has_at_least_24_cited_motors():
    motors = load_zoo()
    assert len(motors) >= 24
    assert all(m.source and len(m.source) > 20 for m in motors)
    assert {m.pole_pairs for m in motors} >= {1, 2, 3, 4}


def test_independent_adapter_writes_the_zoo_motor(tmp_path):
    m = get_motor("alonge_1kw")
    truth = make_zoo_dataset(m, "six_step", noise=independent_noise(m, "coloured"), seed=3, out=tmp_path / "d",
                             source="independent", duration=0.3)
    want = project_parameters(m)
    for k in ("Rs", "Ls", "Le", "Rr", "J"):
        assert truth["parameters"][k] == pytest.approx(want[k], rel=1e-9)
    meta = yaml.safe_load((tmp_path / "d" / "meta.yaml").read_text())
    assert meta["kind"] == "startup" and meta["stator_dc_resistance"] == pytest.approx(m.Rs)
    assert truth["noise"]["current_colored"] > 0
    from synthetic.independent.motors import PRESETS

    assert m.name not in PRESETS  # registered only for the call


def test_independent_motor_falls_back_to_the_zoo_rating():
    m = get_motor("msl_18p5kw")  # its circuit cannot deliver the published power at rated voltage
    rated = independent_motor(m).rated
    assert rated["current"] > 0 and math.isfinite(rated["torque"])


def _run(pipeline, noise, err, se, scenario="six_step"):
    names = study.SUCCESS_PARAMETERS
    truth = dict.fromkeys(names, 1.0)
    return {"pipeline": pipeline, "noise": noise, "scenario": scenario, "motor": "m", "rated_power": 1e3,
            "pole_pairs": 1, "status": "converged", "truth": truth,
            "estimate": {k: 1.0 + err for k in names}, "rel_error": dict.fromkeys(names, err),
            "standard_error": dict.fromkeys(names, se), "wall_time_s": 2.0, "warnings": []}


def test_success_coverage_and_report():
    runs = [_run("multistart", "white", 0.001, 0.001), _run("multistart", "white", 0.03, 0.001),
            _run("multistart", "coloured", 0.001, 0.0001), _run("scipy_de+polish", "white", 0.001, None)]
    assert [study.success(r) for r in runs] == [True, False, True, True]
    assert study.coverage(runs[:2]) == (5, 10)
    assert study.coverage(runs[3:]) == (0, 0)
    text = study.report(runs)
    assert "| multistart | six_step | white | 1/2 |" in text
    assert "| white | six_step | 5/10 | 50.0 % |" in text
    assert "scipy_de+polish" in text
