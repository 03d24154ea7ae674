"""The motor zoo study: the independent-plant adapter of synthetic.zoo and the study's scoring."""

from __future__ import annotations

import json
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


def _run(pipeline, noise, err, se, scenario="six_step", source=None, motor="m"):
    names = study.SUCCESS_PARAMETERS
    truth = dict.fromkeys(names, 1.0)
    extra = {} if source is None else {"source": source}
    return {**extra, "pipeline": pipeline, "noise": noise, "scenario": scenario, "motor": motor, "rated_power": 1e3,
            "pole_pairs": 1, "status": "converged", "truth": truth,
            "estimate": {k: 1.0 + err for k in names}, "rel_error": dict.fromkeys(names, err),
            "standard_error": dict.fromkeys(names, se), "wall_time_s": 2.0, "warnings": []}


def test_success_coverage_and_report():
    runs = [_run("multistart", "white", 0.001, 0.001), _run("multistart", "white", 0.03, 0.001),
            _run("multistart", "coloured", 0.001, 0.0001), _run("scipy_de+polish", "white", 0.001, None)]
    assert [study.success(r) for r in runs] == [True, False, True, True]
    assert study.coverage(runs[:2]) == (5, 10)
    assert study.coverage(runs[3:]) == (0, 0)
    runs[1]["motor"] = "m2"  # two records of one motor would be one record (the latest)
    text = study.report(runs)
    assert "| independent | multistart | six_step | white | 1/2 |" in text
    assert "| independent | white | six_step | 5/10 | 50.0 % |" in text
    assert "scipy_de+polish" in text


def test_report_rows_per_source_and_latest_run_wins():
    runs = [_run("multistart", "white", 0.03, 0.001, source="motulator"),  # replaced by the rerun below
            _run("multistart", "white", 0.001, 0.001, source="motulator"),
            _run("multistart", "white", 0.001, 0.001, source="independent", motor="m2"),
            _run("multistart", "coloured", 0.001, 0.001, scenario="dol", source="motulator", motor="m3")]
    assert len(study.latest(runs)) == 3
    text = study.report(runs)
    assert "| motulator | multistart | six_step | white | 1/1 |" in text
    assert "| independent | multistart | six_step | white | 1/1 |" in text
    assert "| motulator | 2 | 2/2 | 2 |" in text  # motors identified, per source
    assert "| motulator | coloured | dol | 5/5 | 100.0 % |" in text
    assert text.index("| independent | m2 |") < text.index("| motulator | m |")


def test_sources_option_and_data_folders(tmp_path, monkeypatch):
    assert study.dataset_folder(tmp_path, "m", "dol", "white") == tmp_path / "m__dol__white"
    assert study.dataset_folder(tmp_path, "m", "dol", "white", "motulator") == tmp_path / "m__dol__white__motulator"
    with pytest.raises(SystemExit):
        study.main(["--sources", "matlab", "--report-only"])
    seen = []
    monkeypatch.setattr(study, "run_study", lambda args: seen.append(args.sources))
    runs = tmp_path / "runs.jsonl"
    runs.write_text(json.dumps(_run("multistart", "white", 0.001, 0.001)) + "\n")
    assert study.main(["--source", "motulator", "--runs", str(runs), "--out", str(tmp_path / "z.md")]) == 0
    assert seen == ["motulator"] and "| independent |" in (tmp_path / "z.md").read_text()


def test_subset_spans_the_zoo():
    motors = {m.name: m for m in load_zoo()}
    subset = [motors[n] for n in study.SUBSET]  # every name is a zoo motor
    kw = [m.rated_power / 1e3 for m in subset]
    assert min(kw) <= 1.0 and max(kw) >= 200.0
    assert {m.pole_pairs for m in subset} == {1, 2, 3, 4}
