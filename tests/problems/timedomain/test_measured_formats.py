"""Measured data as engineers keep it: MATLAB .mat records, phase or alpha-beta quantities,
speed in rpm or rad/s declared in meta.yaml.

A .mat data set written with scipy.io.savemat from the same numbers as a CSV data set loads
to the same arrays bit for bit; rpm converts exactly (rad/s = rpm * pi / 30); errors name the
file, the variable (as the column) and the row.
"""

from __future__ import annotations

import shutil

import numpy as np
import pandas as pd
import pytest
import scipy.io
import yaml

from benchmark.core.errors import DataError, DataWarning
from benchmark.problems.timedomain.data import load_startup_dataset, write_startup_dataset
from benchmark.problems.timedomain.frames import inverse_clarke
from tests.conftest import compose_config

N_STARTUP, N_STOP = 3000, 4000
RECORD_FIELDS = ("t", "v_alpha", "v_beta", "i_alpha", "i_beta", "speed")


@pytest.fixture(scope="module")
def base_set(tmp_path_factory):
    """The paper's synthetic start-up (first 0.25 s) and stop (first 4 s), alpha-beta, rad/s."""
    from dataclasses import replace

    from synthetic.timedomain import make_dataset

    ds, truth = make_dataset(compose_config([]))
    r, s = ds.startups[0], ds.stops[0]
    cut = replace(ds, startups=[replace(r, **{f: getattr(r, f)[:N_STARTUP] for f in RECORD_FIELDS})],
                  stops=[replace(s, t=s.t[:N_STOP], speed=s.speed[:N_STOP])])
    folder = tmp_path_factory.mktemp("base") / "ds"
    write_startup_dataset(folder, cut, truth)
    return folder


def _tables(folder):
    return {name: pd.read_csv(folder / f"{name}.csv", dtype=float) for name in ("startup", "stop")}


def _as_phase_rpm(tables: dict) -> dict:
    """The same records as phase quantities (v_r, v_s, v_t, i_r, i_s) with the speed in rpm."""
    st = tables["startup"]
    v_r, v_s, v_t = inverse_clarke(st["v_alpha"], st["v_beta"])
    i_r, i_s, _ = inverse_clarke(st["i_alpha"], st["i_beta"])
    startup = pd.DataFrame({"t": st["t"], "v_r": v_r, "v_s": v_s, "v_t": v_t, "i_r": i_r, "i_s": i_s,
                            "speed": st["speed"] * 30 / np.pi})
    stop = pd.DataFrame({"t": tables["stop"]["t"], "speed": tables["stop"]["speed"] * 30 / np.pi})
    return {"startup": startup, "stop": stop}


def _write_set(folder, base, tables: dict, fmt: str, speed_unit: str | None, oned_as: str = "column"):
    folder.mkdir(parents=True)
    meta = yaml.safe_load((base / "meta.yaml").read_text())
    if speed_unit is not None:
        meta["speed_unit"] = speed_unit
    (folder / "meta.yaml").write_text(yaml.safe_dump(meta))
    for name, df in tables.items():
        if fmt == "csv":
            df.to_csv(folder / f"{name}.csv", index=False, float_format="%.17g")
        else:
            scipy.io.savemat(folder / f"{name}.mat", {c: df[c].to_numpy() for c in df.columns}, oned_as=oned_as)
    return folder


def _same_arrays(a, b):
    assert len(a.startups) == len(b.startups) == 1 and len(a.stops) == len(b.stops) == 1
    for f in RECORD_FIELDS:
        np.testing.assert_array_equal(getattr(a.startups[0], f), getattr(b.startups[0], f), err_msg=f)
    np.testing.assert_array_equal(a.stops[0].t, b.stops[0].t)
    np.testing.assert_array_equal(a.stops[0].speed, b.stops[0].speed)
    assert (a.pole_pairs, a.sample_time, a.input_hold) == (b.pole_pairs, b.sample_time, b.input_hold)


@pytest.mark.parametrize("quantities", ["alpha-beta, rad/s", "phase, rpm"])
@pytest.mark.parametrize("oned_as", ["column", "row"])
def test_mat_set_loads_to_the_same_arrays_as_its_csv_twin(tmp_path, base_set, quantities, oned_as):
    tables = _tables(base_set)
    unit = None
    if quantities == "phase, rpm":
        tables, unit = _as_phase_rpm(tables), "rpm"
    csv_set = load_startup_dataset(_write_set(tmp_path / "csv", base_set, tables, "csv", unit))
    mat_set = load_startup_dataset(_write_set(tmp_path / "mat", base_set, tables, "mat", unit, oned_as))
    _same_arrays(csv_set, mat_set)
    # and both are the original record (phase quantities and rpm round to the last bits only)
    ref = load_startup_dataset(base_set)
    for f in RECORD_FIELDS:
        np.testing.assert_allclose(getattr(mat_set.startups[0], f), getattr(ref.startups[0], f),
                                   rtol=1e-12, atol=1e-12, err_msg=f)


def test_mat_in_single_precision_and_integers_loads(tmp_path, base_set):
    """Acquisition systems save float32 or integer counts: any real numeric type is read."""
    tables = _tables(base_set)
    folder = tmp_path / "f32"
    _write_set(folder, base_set, tables, "csv", None)
    (folder / "startup.csv").unlink()
    st = tables["startup"]
    scipy.io.savemat(folder / "startup.mat", {"t": st["t"].to_numpy(),
                                              **{c: st[c].to_numpy(np.float32) for c in RECORD_FIELDS[1:]}})
    ds = load_startup_dataset(folder)
    np.testing.assert_array_equal(ds.startups[0].i_alpha, st["i_alpha"].to_numpy(np.float32).astype(float))


def test_rpm_declared_converts_exactly(tmp_path, base_set):
    tables = _tables(base_set)
    rpm = {name: df["speed"].to_numpy() * 30 / np.pi for name, df in tables.items()}
    for name, df in tables.items():
        df["speed"] = rpm[name]
    ds = load_startup_dataset(_write_set(tmp_path / "rpm", base_set, tables, "csv", "rpm"))
    np.testing.assert_array_equal(ds.startups[0].speed, rpm["startup"] * np.pi / 30)
    np.testing.assert_array_equal(ds.stops[0].speed, rpm["stop"] * np.pi / 30)
    # the default and an explicit rad/s leave the column as it is
    ds = load_startup_dataset(_write_set(tmp_path / "rad", base_set, _tables(base_set), "csv", "rad/s"))
    np.testing.assert_array_equal(ds.startups[0].speed, _tables(base_set)["startup"]["speed"].to_numpy())


def test_unknown_speed_unit_is_refused(tmp_path, base_set):
    folder = _write_set(tmp_path / "ds", base_set, _tables(base_set), "csv", "RPMs")
    with pytest.raises(DataError) as err:
        load_startup_dataset(folder)
    assert "meta.yaml: key 'speed_unit' must be one of ['rad/s', 'rpm'], got 'RPMs'" in str(err.value)


def test_rpm_not_declared_says_how_to_declare_it(tmp_path, base_set):
    tables = _tables(base_set)
    tables["startup"]["speed"] *= 30 / np.pi
    folder = _write_set(tmp_path / "ds", base_set, tables, "csv", None)
    with pytest.raises(DataError) as err:
        load_startup_dataset(folder)
    assert "startup.csv, column 'speed'" in str(err.value) and "speed_unit: rpm" in str(err.value)


def _mat_set(tmp_path, base_set, startup_vars: dict):
    folder = tmp_path / "ds"
    _write_set(folder, base_set, {"stop": _tables(base_set)["stop"]}, "mat", None)
    scipy.io.savemat(folder / "startup.mat", startup_vars)
    return folder


def _startup_vars(base_set) -> dict:
    st = _tables(base_set)["startup"]
    return {c: st[c].to_numpy().copy() for c in st.columns}


@pytest.mark.parametrize("name, expected", [
    ("i_beta", ["startup.mat, column 'i_beta'", "missing variable(s) ['i_beta']", "found ['t', 'v_alpha'"]),
    ("Speed", ["startup.mat, column 'speed'", "no variable 'speed' (found 'Speed': names are case-sensitive)"]),
])
def test_missing_variable_names_the_file_and_the_variable(tmp_path, base_set, name, expected):
    v = _startup_vars(base_set)
    if name == "Speed":
        v[name] = v.pop("speed")
    else:
        v.pop(name)
    with pytest.raises(DataError) as err:
        load_startup_dataset(_mat_set(tmp_path, base_set, v))
    for s in expected:
        assert s in str(err.value), str(err.value)


def test_simulink_structure_with_time_says_how_to_save_the_signals(tmp_path, base_set):
    """Simulink's 'To Workspace' block in 'Structure With Time' format saves one struct whose
    ``signals.values`` matrix has no column names: the message says how to save named vectors."""
    v = _startup_vars(base_set)
    values = np.column_stack([v[c] for c in v if c != "t"])
    simout = {"time": v["t"], "signals": {"values": values, "dimensions": values.shape[1]}}
    with pytest.raises(DataError) as err:
        load_startup_dataset(_mat_set(tmp_path, base_set, {"simout": simout}))
    msg = str(err.value)
    assert "startup.mat, column 't'" in msg and "found ['simout']" in msg, msg
    assert "['simout'] hold structs" in msg and "t = simout.time;" in msg and "'-v7')" in msg, msg


def test_a_record_without_a_speed_column_is_a_record_without_a_speed_sensor(tmp_path, base_set):
    """No speed variable: the record loads with its speed all NaN, says so, and keeps the rest."""
    v = _startup_vars(base_set)
    v.pop("speed")
    with pytest.warns(DataWarning, match="no speed column: a record without a speed sensor"):
        ds = load_startup_dataset(_mat_set(tmp_path, base_set, v))
    rec = ds.startups[0]
    assert not rec.has_speed and not ds.has_speed and np.isnan(rec.speed).all()
    np.testing.assert_array_equal(rec.i_beta, v["i_beta"])


@pytest.mark.parametrize("change, expected", [
    (lambda v: v["i_beta"].__setitem__(16, np.nan), "startup.mat, column 'i_beta', row 17: not a finite number"),
    (lambda v: v.__setitem__("v_beta", v["v_beta"][:-5]),
     f"startup.mat, column 'v_beta', row {N_STARTUP - 4}: has {N_STARTUP - 5} values where 't' has"),
    (lambda v: v.__setitem__("i_alpha", np.stack([v["i_alpha"], v["i_alpha"]])),
     f"startup.mat, column 'i_alpha': is a 2x{N_STARTUP} matrix, expected a vector"),
    (lambda v: v.__setitem__("speed", "fast"), "startup.mat, column 'speed': holds text"),
    (lambda v: v.__setitem__("speed", v["speed"] + 1j), "startup.mat, column 'speed': holds complex values"),
    (lambda v: v["t"].__setitem__(100, v["t"][99]), "startup.mat, column 't', row 101: time must increase"),
])
def test_bad_variable_names_the_file_variable_and_row(tmp_path, base_set, change, expected):
    v = _startup_vars(base_set)
    change(v)
    with pytest.raises(DataError) as err:
        load_startup_dataset(_mat_set(tmp_path, base_set, v))
    assert expected in str(err.value), str(err.value)


def test_v73_and_foreign_files_are_refused_clearly(tmp_path, base_set):
    folder = _mat_set(tmp_path, base_set, _startup_vars(base_set))
    # a MATLAB v7.3 file: the 128-byte MAT header with version 0x0200, then HDF5 (not needed here)
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2026 HDF5 schema 1.00 ."
    header = header.ljust(116) + b"\0" * 8 + b"\x00\x02" + b"IM"
    (folder / "startup.mat").write_bytes(header + b"\0" * 400 + b"\x89HDF\r\n\x1a\n")
    with pytest.raises(DataError) as err:
        load_startup_dataset(folder)
    assert "startup.mat: a MATLAB v7.3 (HDF5) .mat file" in str(err.value)
    assert "'-v7'" in str(err.value) and "CSV" in str(err.value)
    for junk in (b"", b"t,speed\n0,1\n", bytes(range(256)) * 3):
        (folder / "startup.mat").write_bytes(junk)
        with pytest.raises(DataError) as err:
            load_startup_dataset(folder)
        assert str(err.value).startswith(str(folder / "startup.mat")), str(err.value)


def test_same_record_as_csv_and_mat_is_refused(tmp_path, base_set):
    folder = _mat_set(tmp_path, base_set, _startup_vars(base_set))
    shutil.copy(base_set / "startup.csv", folder / "startup.csv")
    with pytest.raises(DataError) as err:
        load_startup_dataset(folder)
    assert "startup.csv and startup.mat hold the same record" in str(err.value)


def test_identification_from_a_mat_set_equals_its_csv_twin(tmp_path, base_set):
    """The whole path: the harness identifies a .mat folder as it does the CSV folder (same
    cost bit for bit), and the run's fingerprint covers the .mat files."""
    from benchmark.core.harness import resolved, run, run_fingerprint

    tables = _as_phase_rpm(_tables(base_set))
    recs = {}
    for fmt in ("csv", "mat"):
        folder = _write_set(tmp_path / fmt, base_set, tables, fmt, "rpm")
        cfg = compose_config([f"data.path={folder}", "budget=100", "figures=false", "checkpoint=false"])
        out = run(cfg, tmp_path / f"run_{fmt}")
        recs[fmt] = out.record
        if fmt == "mat":
            before = run_fingerprint(resolved(cfg), out.problem)
            scipy.io.savemat(folder / "stop.mat", {"t": tables["stop"]["t"].to_numpy(),
                                                   "speed": tables["stop"]["speed"].to_numpy() + 1.0})
            assert run_fingerprint(resolved(cfg), out.problem) != before
    assert recs["mat"]["cost"] == recs["csv"]["cost"]
    assert recs["mat"]["estimate"] == recs["csv"]["estimate"]
