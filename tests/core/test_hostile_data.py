"""Hostile data sets (issue 7, item 1): each one either loads (possibly with a warning) or is
refused with one clear message naming the file, and the column and row where they apply.

The loader is exercised directly on every data set (fast); a handful go through the command
line, run in parallel: exit status 2, the message on one line, no traceback unless
``IMBENCH_DEBUG=1``.

Speed plausibility (the decision documented in ``benchmark/problems/timedomain/data.py``):

* above 1600 rad/s (about 15 000 rpm) no motor of this benchmark turns: error;
* with ``supply_frequency`` in ``meta.yaml``, a speed above 1.5 times the synchronous speed
  ``2 pi f / p`` is impossible for a motor starting on that supply: error;
* without it, the synchronous speed is estimated from the supply's rotation, and the
  same excess is only a warning ("looks like rpm"): the run goes on.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from benchmark.core.errors import DataError, DataWarning
from benchmark.core.tables import read_table, table_size_limit
from benchmark.problems.timedomain.data import (
    StartupDataset,
    StartupRecord,
    StopRecord,
    load_startup_dataset,
    write_startup_dataset,
)
from benchmark.problems.timedomain.protocol import StartupStopTest, run_startup_stop
from tests.conftest import PAPER_MOTOR
from tests.core.csv_edits import RPM, lines, scale_column, write_lines
from tests.core.hostile_cases import CASES, m_meta_misspelt_key, m_nan, m_stop_too_short

REPO = Path(__file__).resolve().parents[2]


def _dataset(
    records,
    p: int,
    n_start: int | None = None,
    n_stop: int | None = None,
    supply_frequency: float | None = 50.0,
) -> StartupDataset:
    s, st = records["startup"], records["stop"]
    sl = slice(0, n_start)
    rec = StartupRecord(
        t=s["t"][sl],
        v_alpha=s["v_alpha"][sl],
        v_beta=s["v_beta"][sl],
        i_alpha=s["i_alpha"][sl],
        i_beta=s["i_beta"][sl],
        speed=s["speed"][sl],
    )
    stop = StopRecord(t=st["t"][:n_stop], speed=st["speed"][:n_stop])
    return StartupDataset(
        pole_pairs=p,
        sample_time=1 / 12000,
        startups=[rec],
        stops=[stop],
        input_hold="zoh",
        dc_link_voltage=300.0,
        supply_frequency=supply_frequency,
    )


@pytest.fixture(scope="module")
def small_set(tmp_path_factory, paper_records) -> Path:
    """A valid data set: the paper motor's first 0.2 s of start-up and 0.5 s of stop."""
    folder = tmp_path_factory.mktemp("small")
    write_startup_dataset(folder, _dataset(paper_records, 1, n_start=2400, n_stop=500))
    return folder


@pytest.fixture(scope="module")
def four_pole_records():
    """A 4-pole variant of the paper motor (synchronous speed 157 rad/s = 1500 rpm), 0.4 s."""
    return run_startup_stop(dataclasses.replace(PAPER_MOTOR, p=2), StartupStopTest(cycles=20))


@pytest.fixture(scope="module")
def four_pole_set(tmp_path_factory, four_pole_records) -> Path:
    folder = tmp_path_factory.mktemp("four_pole")
    write_startup_dataset(folder, _dataset(four_pole_records, 2))
    return folder


def copy_set(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


@pytest.mark.parametrize("name, mutate, outcome, expected", CASES, ids=[c[0] for c in CASES])
def test_hostile_data_set(tmp_path, small_set, name, mutate, outcome, expected):
    folder = copy_set(small_set, tmp_path / "ds")
    mutate(folder)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if outcome == "error":
            with pytest.raises(DataError) as err:
                load_startup_dataset(folder)
            msg = str(err.value)
            assert "\n" not in msg.strip(), msg
        else:
            ds = load_startup_dataset(folder)
            msg = " | ".join(str(w.message) for w in caught if issubclass(w.category, DataWarning))
    for s in expected:
        assert s in msg, f"{s!r} not in {msg!r}"
    assert str(folder) in msg or not expected
    if outcome == "ok":
        assert msg == "", msg
        ref = load_startup_dataset(small_set)
        n = 999 if name == "records of different lengths" else len(ref.startups[0].t)
        for r in ds.startups:
            assert np.isfinite(r.speed).all()
            tol = 0.0 if name != "rounded time stamps" else 1e-6
            np.testing.assert_allclose(r.t[:n], ref.startups[0].t[:n], rtol=0, atol=tol)
            for col in ("v_alpha", "v_beta", "i_alpha", "i_beta", "speed"):
                np.testing.assert_array_equal(getattr(r, col)[:n], getattr(ref.startups[0], col)[:n])
        if name == "records of different lengths":
            assert [len(r.t) for r in ds.startups] == [2400, 999]


def test_speed_in_rpm_with_declared_supply_is_an_error(tmp_path, four_pole_set):
    """4-pole motor, 1500 rpm < 1600 rad/s: only the synchronous speed can tell."""
    folder = copy_set(four_pole_set, tmp_path / "ds")
    scale_column(folder, "speed", RPM, "startup.csv")
    with pytest.raises(DataError) as err:
        load_startup_dataset(folder)
    msg = str(err.value)
    for s in (
        "startup.csv, column 'speed', row",
        "impossible",
        "synchronous speed 157.1 rad/s",
        "supply_frequency 50 Hz and pole_pairs 2",
        "rad/s = rpm * pi / 30",
    ):
        assert s in msg, msg


def test_speed_in_rpm_without_supply_is_a_warning(tmp_path, four_pole_set):
    folder = copy_set(four_pole_set, tmp_path / "ds")
    scale_column(folder, "speed", RPM, "startup.csv")
    scale_column(folder, "speed", RPM, "stop.csv")
    meta = (folder / "meta.yaml").read_text()
    (folder / "meta.yaml").write_text(
        "\n".join(line for line in meta.split("\n") if "supply_frequency" not in line)
    )
    with pytest.warns(DataWarning) as rec:
        ds = load_startup_dataset(folder)
    msgs = [str(w.message) for w in rec]
    assert any(
        "startup.csv, column 'speed', row" in m
        and "looks like rpm" in m
        and "estimated from the supply's rotation (about 49.9 Hz)" in m  # the record's supply: 50 Hz
        for m in msgs
    ), msgs
    assert any("stop.csv" in m for m in msgs), msgs
    assert not any("pole_pairs too" in m for m in msgs), msgs  # 10 times is no pole pairs' multiple (was "then 0.2")
    assert ds.startups[0].speed.max() > 1000


def test_real_rad_per_s_speed_gives_no_warning(four_pole_set):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_startup_dataset(four_pole_set)


def test_size_limit_is_configurable(small_set):
    path = small_set / "startup.csv"
    size = path.stat().st_size
    with pytest.raises(DataError, match=r"startup.csv: table is .* larger than the 100 KiB limit"):
        read_table(path, [("t",)], max_bytes=100 * 1024)
    with table_size_limit(size - 1), pytest.raises(DataError, match="larger than"):
        load_startup_dataset(small_set)
    with table_size_limit(size):
        load_startup_dataset(small_set)


# -- through the command line ---------------------------------------------------------------------
def _cli(folder: Path, rundir: Path, *extra: str, debug: bool = False) -> subprocess.Popen:
    env = dict(os.environ)
    env.pop("IMBENCH_DEBUG", None)
    env.pop("HYDRA_FULL_ERROR", None)
    if debug:
        env["IMBENCH_DEBUG"] = "1"
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "benchmark",
            f"data.path={folder}",
            "optimizer=scipy_de",
            "budget=50",
            f"hydra.run.dir={rundir}",
            *extra,
        ],
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_cli_hostile_data(tmp_path, small_set, four_pole_set):
    """A few data sets through the command line at once (in parallel; ~2 s of CPU each): the
    loader's messages reach the user as one line, exit status 2; IMBENCH_DEBUG=1 adds the
    traceback; a set that loads with a warning runs, and says so in one line."""
    cases = {}

    def make(name, base, mutate):
        folder = copy_set(base, tmp_path / name)
        mutate(folder)
        return folder

    errors = {
        "nan": (m_nan, ["error: ", "startup.csv, column 'v_beta', row 7 (line 8 of the file): not a finite number"],
                ()),
        "meta": (m_meta_misspelt_key, ["error: ", "meta.yaml: missing key 'sample_time'"], ()),
        "huge": (
            lambda f: None,
            ["error: ", "startup.csv: table is", "larger than the 50 KiB limit", "data.max_file_mib"],
            ("data.max_file_mib=0.048828125",),
        ),
        "stop_short": (m_stop_too_short, ["error: ", "stop.csv: stop record too short"], ()),
    }
    for name, (mutate, expected, extra) in errors.items():
        cases[name] = (_cli(make(name, small_set, mutate), tmp_path / f"run_{name}", *extra), expected)
    debug_folder = make("debug", small_set, m_nan)
    debug = _cli(debug_folder, tmp_path / "run_debug", debug=True)

    # a set that runs: speed in rpm without supply_frequency (a warning), two records of
    # different lengths
    def rpm_two_records(f):
        scale_column(f, "speed", RPM, "startup.csv")
        scale_column(f, "speed", RPM, "stop.csv")
        meta = (f / "meta.yaml").read_text()
        (f / "meta.yaml").write_text("\n".join(x for x in meta.split("\n") if "supply_frequency" not in x))
        ls = lines(f / "startup.csv")
        write_lines(f / "startup_2.csv", ls[:3001])

    ok_folder = make("ok", four_pole_set, rpm_two_records)
    ok = _cli(ok_folder, tmp_path / "run_ok")
    try:
        _check_cli_outcomes(tmp_path, cases, debug, ok)
    finally:
        for proc in [p for p, _ in cases.values()] + [debug, ok]:
            if proc.poll() is None:
                proc.kill()
            proc.communicate()


def _check_cli_outcomes(tmp_path, cases, debug, ok):
    for name, (proc, expected) in cases.items():
        out, err = proc.communicate(timeout=120)
        assert proc.returncode == 2, (name, out, err)
        assert "Traceback" not in out + err, (name, err)
        lines_ = [x for x in err.strip().split("\n") if x]
        assert len(lines_) == 1, (name, err)
        for s in expected:
            assert s in err, (name, s, err)
        assert str(tmp_path / name) in err, (name, err)
        assert not (tmp_path / f"run_{name}" / "result.json").exists()

    out, err = debug.communicate(timeout=120)
    assert debug.returncode == 2, err
    assert "Traceback" in err and "DataError" in err and "column 'v_beta', row 7" in err

    out, err = ok.communicate(timeout=120)
    assert ok.returncode == 0, err
    assert "Traceback" not in err
    warn = [x for x in err.split("\n") if x.startswith("warning: ")]
    assert any("startup.csv, column 'speed', row" in x and "looks like rpm" in x for x in warn), err
    import json

    rec = json.loads((tmp_path / "run_ok" / "result.json").read_text())
    assert rec["status"] == "budget_spent" and rec["problem_info"]["records"] == 2
    assert rec["problem_info"]["samples"] == 4800 + 3000
    assert any("looks like rpm" in w for w in rec["warnings"])
