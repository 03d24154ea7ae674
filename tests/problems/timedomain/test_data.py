"""Data sets: round trip through files, both column conventions, and clear errors."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from benchmark.core.errors import DataError
from benchmark.problems.timedomain.data import (
    StartupDataset,
    StartupRecord,
    StopRecord,
    load_startup_dataset,
    write_startup_dataset,
)
from benchmark.problems.timedomain.frames import inverse_clarke


@pytest.fixture()
def dataset(paper_records):
    s, st = paper_records["startup"], paper_records["stop"]
    rec = StartupRecord(t=s["t"], v_alpha=s["v_alpha"], v_beta=s["v_beta"], i_alpha=s["i_alpha"],
                        i_beta=s["i_beta"], speed=s["speed"])
    return StartupDataset(pole_pairs=1, sample_time=1 / 12000, startups=[rec],
                          stops=[StopRecord(t=st["t"], speed=st["speed"])], input_hold="zoh")


def test_round_trip_is_exact(tmp_path, dataset):
    write_startup_dataset(tmp_path, dataset, truth={"parameters": {"Rs": 1.0}})
    back = load_startup_dataset(tmp_path)
    a, b = dataset.startups[0], back.startups[0]
    for name in ("t", "v_alpha", "v_beta", "i_alpha", "i_beta", "speed"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    np.testing.assert_array_equal(dataset.stops[0].speed, back.stops[0].speed)
    assert back.input_hold == "zoh" and back.pole_pairs == 1


def test_phase_columns_give_the_same_alpha_beta(tmp_path, dataset):
    r = dataset.startups[0]
    v_r, v_s, v_t = inverse_clarke(r.v_alpha, r.v_beta)
    i_r, i_s, _ = inverse_clarke(r.i_alpha, r.i_beta)
    pd.DataFrame({"t": r.t, "v_r": v_r, "v_s": v_s, "v_t": v_t, "i_r": i_r, "i_s": i_s, "speed": r.speed}).to_csv(
        tmp_path / "startup.csv", index=False, float_format="%.17g")
    # the generator's voltages are exactly linear between samples (chord_voltage: not restored)
    (tmp_path / "meta.yaml").write_text("kind: startup\npole_pairs: 1\nsample_time: 8.333333333333333e-05\n"
                                        "chord_voltage: true\n")
    back = load_startup_dataset(tmp_path).startups[0]
    np.testing.assert_allclose(back.v_alpha, r.v_alpha, atol=1e-9)
    np.testing.assert_allclose(back.v_beta, r.v_beta, atol=1e-9)
    np.testing.assert_allclose(back.i_alpha, r.i_alpha, atol=1e-9)
    np.testing.assert_allclose(back.i_beta, r.i_beta, atol=1e-9)


def _small_set(tmp_path, table: str, meta: str = "kind: startup\npole_pairs: 1\nsample_time: 0.001\n") -> Path:
    (tmp_path / "meta.yaml").write_text(meta)
    (tmp_path / "startup.csv").write_text(table)
    return tmp_path


GOOD_HEADER = "t,v_alpha,v_beta,i_alpha,i_beta,speed\n"
GOOD_ROWS = "".join(f"{k * 0.001},1,2,0.1,0.2,{k}\n" for k in range(5))


@pytest.mark.parametrize(
    "table, meta, expected",
    [
        ("t,v_alpha,v_beta,i_alpha,speed\n0,1,2,3,4\n0.001,1,2,3,4\n", None, "column 'i_beta'"),
        (GOOD_HEADER + "0,1,2,3,4,5\n0.002,1,2,3,4,5\n0.001,1,2,3,4,5\n", None, "column 't', row 3"),
        (GOOD_HEADER + "0,1,2,3,4,5\n0.001,1,nan,3,4,5\n", None, "column 'v_beta', row 2"),
        (GOOD_HEADER + "0,1,2,3,4,5\n0.001,1,2,3,4,3000\n", None, "rpm"),
        ("", None, "empty"),
        (GOOD_HEADER + GOOD_ROWS, "kind: startup\nsample_time: 0.001\n", "missing key 'pole_pairs'"),
        (GOOD_HEADER + GOOD_ROWS, "kind: startup\npole_pairs: two\nsample_time: 0.001\n", "pole_pairs"),
    ],
)
def test_bad_data_names_file_column_row(tmp_path, table, meta, expected):
    folder = _small_set(tmp_path, table, meta or "kind: startup\npole_pairs: 1\nsample_time: 0.001\n")
    with pytest.raises(DataError) as err:
        load_startup_dataset(folder)
    msg = str(err.value)
    assert expected in msg
    assert str(folder) in msg


def test_cli_reports_data_errors_without_traceback(tmp_path):
    folder = _small_set(tmp_path, GOOD_HEADER + "0,1,2,3,4,5\n0.001,1,2,,4,5\n")
    proc = subprocess.run([sys.executable, "-m", "benchmark", f"data.path={folder}", "optimizer=genesis",
                           f"hydra.run.dir={tmp_path / 'run'}"], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "startup.csv, column 'i_alpha', row 2 (line 3 of the file): empty" in proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout


@pytest.mark.parametrize("override, expected", [
    ("optimizer=no_such_plugin", "error: optimizer=no_such_plugin: no such option; options: ["),
    ("budget=0", "budget: must be a positive"),
])
def test_cli_reports_config_errors(tmp_path, override, expected):
    proc = subprocess.run([sys.executable, "-m", "benchmark", override, f"hydra.run.dir={tmp_path / 'run'}"],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert expected in proc.stderr
    assert "Traceback" not in proc.stderr


def test_truth_yaml_written_by_generator(tmp_path):
    out = tmp_path / "ds"
    proc = subprocess.run([sys.executable, "-m", "synthetic", f"out={out}"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    truth = yaml.safe_load((out / "truth.yaml").read_text())
    assert truth["parameters"]["Rs"] == 4.96434
    ds = load_startup_dataset(out)
    assert ds.input_hold == "zoh" and len(ds.startups[0].t) == 12000 and ds.stops


@pytest.mark.parametrize("text, expected", [
    ("parameters: [1, 2\n", "not valid YAML"),
    ("- 1\n- 2\n", "needs a mapping 'parameters'"),
    ("parameters:\n  Rs: abc\n", "parameters.Rs must be a number"),
])
def test_malformed_truth_yaml_is_a_clear_data_error(tmp_path, text, expected):
    from benchmark.problems.timedomain.true_parameters import read_truth_for_scoring

    (tmp_path / "truth.yaml").write_bytes(text.encode())
    with pytest.raises(DataError) as err:
        read_truth_for_scoring(tmp_path)
    assert expected in str(err.value) and "truth.yaml" in str(err.value)
