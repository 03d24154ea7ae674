"""Hostile data sets (issue 7, item 1): each one either loads (possibly with a warning) or is
refused with one clear message naming the file, and the column and row where they apply.

The loader is exercised directly on every data set (fast); a handful go through the command
line, run in parallel: exit status 2, the message on one line, no traceback unless
``IMBENCH_DEBUG=1``.

Speed plausibility (the decision documented in ``benchmark/problems/timedomain/data.py``):

* above 1600 rad/s (about 15 000 rpm) no motor of this benchmark turns: error;
* with ``supply_frequency`` in ``meta.yaml``, a speed above 1.5 times the synchronous speed
  ``2 pi f / p`` is impossible for a motor starting on that supply: error;
* without it, the synchronous speed is estimated from the rotation of the currents, and the
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

REPO = Path(__file__).resolve().parents[2]
RPM = 30 / np.pi


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


# -- mutations of a valid set ---------------------------------------------------------------------
def lines(path: Path) -> list[str]:
    return path.read_text().split("\n")


def write_lines(path: Path, ls: list[str]) -> None:
    path.write_text("\n".join(ls))


def edit_cell(folder: Path, row: int, column: str, value: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    header = ls[0].split(",")
    cells = ls[row].split(",")
    cells[header.index(column)] = value
    ls[row] = ",".join(cells)
    write_lines(path, ls)


def edit_header(folder: Path, old: str, new: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    ls[0] = ",".join(new if c == old else c for c in ls[0].split(","))
    write_lines(path, ls)


def drop_column(folder: Path, column: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    k = ls[0].split(",").index(column)
    write_lines(
        path, [",".join(c for j, c in enumerate(line.split(",")) if j != k) if line else line for line in ls]
    )


def add_column(folder: Path, column: str, name: str = "startup.csv") -> None:
    path = folder / name
    ls = lines(path)
    write_lines(path, [ls[0] + "," + column] + [line + ",20.5" if line else line for line in ls[1:]])


def scale_column(folder: Path, column: str, factor: float, name: str) -> None:
    path = folder / name
    ls = lines(path)
    k = ls[0].split(",").index(column)
    out = [ls[0]]
    for line in ls[1:]:
        if line:
            cells = line.split(",")
            cells[k] = repr(float(cells[k]) * factor)
            line = ",".join(cells)
        out.append(line)
    write_lines(path, out)


def set_meta(folder: Path, text: str) -> None:
    (folder / "meta.yaml").write_text(text)


META = "kind: startup\npole_pairs: 1\nsample_time: 8.333333333333333e-05\ninput_hold: zoh\n"


def m_missing_column(f):
    drop_column(f, "i_beta")


def m_misnamed_case(f):
    edit_header(f, "speed", "Speed")


def m_misspelt(f):
    edit_header(f, "i_alpha", "i_alfa")


def m_extra_column(f):
    add_column(f, "temperature")


def m_duplicate_column(f):
    add_column(f, "t")


def m_trailing_separator(f):
    path = f / "startup.csv"
    ls = lines(path)
    write_lines(path, [line + "," if line else line for line in ls])


def m_nan(f):
    edit_cell(f, 7, "v_beta", "nan")


def m_inf(f):
    edit_cell(f, 12, "i_alpha", "-inf")


def m_overflow(f):
    edit_cell(f, 3, "i_beta", "1e999")


def m_empty_cell(f):
    edit_cell(f, 9, "speed", "")


def m_text_cell(f):
    edit_cell(f, 5, "v_alpha", "12 V")


def m_empty_file(f):
    (f / "startup.csv").write_bytes(b"")


def m_whitespace_file(f):
    (f / "stop.csv").write_text("\n \n\n")


def m_header_only(f):
    path = f / "startup.csv"
    path.write_text(lines(path)[0] + "\n")


def m_empty_meta(f):
    set_meta(f, "")


def m_time_backwards(f):
    ls = lines(f / "startup.csv")
    ls[20], ls[21] = ls[21], ls[20]
    write_lines(f / "startup.csv", ls)


def m_time_repeated(f):
    ls = lines(f / "stop.csv")
    ls[30] = ls[29]
    write_lines(f / "stop.csv", ls)


def m_time_gap(f):
    ls = lines(f / "startup.csv")
    del ls[100]
    write_lines(f / "startup.csv", ls)


def m_variable_step(f):
    """A variable-step solver's output: the step doubles and halves as the dynamics allow."""
    ls = lines(f / "startup.csv")
    head, rows = ls[0], [r for r in ls[1:] if r]
    t, step = 0.0, 1 / 12000
    out = [head]
    for k, r in enumerate(rows):
        out.append(",".join([repr(t)] + r.split(",")[1:]))
        t += step * (2.0 if (k // 7) % 2 else 1.0)
    write_lines(f / "startup.csv", out)


def m_time_jitter(f):
    """Timestamps 10 % of a step off the grid: not a gap, still not uniform."""
    edit_cell(f, 50, "t", repr(49.1 / 12000))


def m_time_ms(f):
    scale_column(f, "t", 1000.0, "startup.csv")


def m_time_rounded(f):
    """t written with 6 decimals (0.6 % of a step): accepted."""
    path = f / "startup.csv"
    ls = lines(path)
    out = [ls[0]]
    for line in ls[1:]:
        if line:
            cells = line.split(",")
            cells[0] = f"{float(cells[0]):.6f}"
            line = ",".join(cells)
        out.append(line)
    write_lines(path, out)


def m_extra_field(f):
    ls = lines(f / "startup.csv")
    ls[40] += ",3"
    write_lines(f / "startup.csv", ls)


def m_short_row(f):
    ls = lines(f / "startup.csv")
    ls[41] = ",".join(ls[41].split(",")[:-1])
    write_lines(f / "startup.csv", ls)


def m_blank_line(f):
    ls = lines(f / "startup.csv")
    ls.insert(60, "")
    write_lines(f / "startup.csv", ls)


def m_trailing_blank_lines(f):
    path = f / "startup.csv"
    path.write_text(path.read_text() + "\n\n   \n")


def m_unclosed_quote(f):
    edit_cell(f, 15, "v_alpha", '"200')


def m_different_lengths(f):
    """Two start-up records of different lengths (and a stop record): must load."""
    ls = lines(f / "startup.csv")
    write_lines(f / "startup_2.csv", ls[:1000])
    (f / "startup.csv").rename(f / "startup_1.csv")


def m_bom_utf8(f):
    path = f / "startup.csv"
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    (f / "meta.yaml").write_bytes(b"\xef\xbb\xbf" + (f / "meta.yaml").read_bytes())


def m_utf16(f):
    path = f / "startup.csv"
    path.write_bytes(path.read_text().encode("utf-16"))  # with its byte-order mark


def m_semicolon_decimal_comma(f):
    path = f / "startup.csv"
    path.write_text(path.read_text().replace(",", ";").replace(".", ","))


def m_comma_decimal_comma(f):
    path = f / "startup.csv"
    ls = lines(path)
    write_lines(path, [ls[0]] + [line.replace(".", ",") for line in ls[1:]])


def m_semicolon_mixed(f):
    path = f / "startup.csv"
    text = path.read_text().replace(",", ";")
    ls = text.split("\n")
    ls[25] = ls[25].replace(".", ",")
    write_lines(path, ls)


def m_binary(f):
    (f / "stop.csv").write_bytes(bytes(np.random.default_rng(0).integers(0, 256, 4000, dtype=np.uint8)))


def m_latin1(f):
    path = f / "startup.csv"
    path.write_bytes(path.read_bytes().replace(b"v_alpha", "v_\xe1lpha".encode("latin-1"), 1))


def m_folder_named_csv(f):
    (f / "stop.csv").unlink()
    (f / "stop.csv").mkdir()


def m_no_meta(f):
    (f / "meta.yaml").unlink()


def m_no_startup(f):
    (f / "startup.csv").rename(f / "start-up.csv")


def m_meta_missing_key(f):
    set_meta(f, "kind: startup\nsample_time: 8.333333333333333e-05\n")


def m_meta_misspelt_key(f):
    set_meta(f, "kind: startup\npole_pairs: 1\nsampel_time: 8.333333333333333e-05\n")


def m_meta_float_pole_pairs(f):
    set_meta(f, META.replace("pole_pairs: 1", "pole_pairs: 1.5"))


def m_meta_text_sample_time(f):
    set_meta(f, META.replace("sample_time: 8.333333333333333e-05", "sample_time: fast"))


def m_meta_inf_sample_time(f):
    set_meta(f, META.replace("sample_time: 8.333333333333333e-05", "sample_time: .inf"))


def m_meta_huge_inertia(f):
    set_meta(f, META + "inertia: " + "9" * 400 + "\n")


def m_meta_list_hold(f):
    set_meta(f, META.replace("input_hold: zoh", "input_hold: [zoh]"))


def m_meta_bool_pole_pairs(f):
    set_meta(f, META.replace("pole_pairs: 1", "pole_pairs: true"))


def m_meta_bad_yaml(f):
    set_meta(f, "kind: startup\npole_pairs: [1\nsample_time: 8.3e-05\n")


def m_meta_bad_date(f):
    set_meta(f, META + "recorded: 2021-02-30\n")


def m_meta_list(f):
    set_meta(f, "- kind\n- startup\n")


def m_meta_unknown_key(f):
    set_meta(f, META + "intertia: 0.0064\n")


def m_speed_rpm_declared_supply(f):
    scale_column(f, "speed", RPM, "startup.csv")  # up to 1593 rpm in 0.2 s, 5 x synchronous


def m_speed_over_limit(f):
    scale_column(f, "speed", 10.0, "startup.csv")  # 1660 rad/s


def m_phase_overflow(f):
    path = f / "startup.csv"
    ls = lines(path)
    out = ["t,v_r,v_s,v_t,i_r,i_s,speed"]
    for k, line in enumerate(ls[1:]):
        if line:
            t, va, vb, ia, ib, w = line.split(",")
            vr = "1.7e308" if k == 4 else va
            out.append(",".join([t, vr, "-1.7e308" if k == 4 else "0", "0", ia, ib, w]))
    write_lines(path, out)


def m_stop_too_short(f):
    ls = lines(f / "stop.csv")
    write_lines(f / "stop.csv", ls[:10])


# name, mutation, outcome ("error" | "warning" | "ok"), substrings of the message
CASES = [
    ("missing column", m_missing_column, "error", ["startup.csv", "column 'i_beta'", "missing column"]),
    (
        "misnamed column (case)",
        m_misnamed_case,
        "error",
        ["startup.csv", "column 'speed'", "found 'Speed'", "case-sensitive"],
    ),
    ("misspelt column", m_misspelt, "error", ["startup.csv", "column 'i_alpha'", "found 'i_alfa': misspelt"]),
    ("extra column", m_extra_column, "warning", ["startup.csv", "['temperature'] not used"]),
    ("duplicate column", m_duplicate_column, "error", ["startup.csv", "column 't', row 0", "appears twice"]),
    ("trailing separator", m_trailing_separator, "error", ["startup.csv", "row 0", "trailing comma"]),
    ("NaN", m_nan, "error", ["startup.csv", "column 'v_beta', row 7", "not a finite number: 'nan'"]),
    ("inf", m_inf, "error", ["startup.csv", "column 'i_alpha', row 12", "'-inf'"]),
    ("overflowing number", m_overflow, "error", ["startup.csv", "column 'i_beta', row 3", "out of range"]),
    ("empty cell", m_empty_cell, "error", ["startup.csv", "column 'speed', row 9", "empty"]),
    ("text in a number cell", m_text_cell, "error", ["startup.csv", "column 'v_alpha', row 5", "'12 V'"]),
    ("empty file", m_empty_file, "error", ["startup.csv", "file is empty"]),
    ("blank-lines-only file", m_whitespace_file, "error", ["stop.csv", "file is empty"]),
    ("header only", m_header_only, "error", ["startup.csv", "no data rows"]),
    ("empty meta.yaml", m_empty_meta, "error", ["meta.yaml", "must be a mapping"]),
    (
        "time goes backwards",
        m_time_backwards,
        "error",
        ["startup.csv", "column 't', row 21", "time must increase"],
    ),
    ("time repeated", m_time_repeated, "error", ["stop.csv", "column 't', row 30", "time must increase"]),
    (
        "missing sample (gap)",
        m_time_gap,
        "error",
        ["startup.csv", "column 't', row 100", "irregular sampling"],
    ),
    (
        "variable-step simulation",
        m_variable_step,
        "error",
        ["startup.csv", "column 't'", "irregular sampling", "variable-step solver", "resample"],
    ),
    ("jittered time", m_time_jitter, "error", ["startup.csv", "column 't', row 50", "off the uniform grid"]),
    ("time in ms", m_time_ms, "error", ["startup.csv", "column 't'", "is t in ms?"]),
    ("rounded time stamps", m_time_rounded, "ok", []),
    (
        "row with an extra field",
        m_extra_field,
        "error",
        ["startup.csv", "row 40", "7 fields where the header has 6"],
    ),
    (
        "row with a missing field",
        m_short_row,
        "error",
        ["startup.csv", "column 'speed', row 41", "5 fields where the header has 6"],
    ),
    ("blank line between rows", m_blank_line, "error", ["startup.csv", "row 60", "blank line"]),
    ("blank lines at the end", m_trailing_blank_lines, "ok", []),
    ("unclosed quote", m_unclosed_quote, "error", ["startup.csv", "row 15", "never closed"]),
    ("records of different lengths", m_different_lengths, "ok", []),
    ("UTF-8 byte-order mark", m_bom_utf8, "ok", []),
    ("UTF-16 with byte-order mark", m_utf16, "ok", []),
    ("';' separated, decimal comma", m_semicolon_decimal_comma, "ok", []),
    (
        "',' separated, decimal comma",
        m_comma_decimal_comma,
        "error",
        ["startup.csv", "row 2", "8 fields where the header has 6", "comma decimal separator"],
    ),
    (
        "';' separated, mixed decimals",
        m_semicolon_mixed,
        "error",
        ["startup.csv", "mixes decimal separators"],
    ),
    ("binary garbage", m_binary, "error", ["stop.csv", "not UTF-8 text"]),
    ("latin-1 text", m_latin1, "error", ["startup.csv", "not UTF-8 text", "line 1"]),
    ("folder named like a table", m_folder_named_csv, "error", ["stop.csv", "not a regular file"]),
    ("no meta.yaml", m_no_meta, "error", ["meta.yaml", "missing"]),
    ("no start-up table", m_no_startup, "error", ["no startup*.csv"]),
    ("meta: missing key", m_meta_missing_key, "error", ["meta.yaml", "missing key 'pole_pairs'"]),
    (
        "meta: misspelt key",
        m_meta_misspelt_key,
        "error",
        ["meta.yaml", "missing key 'sample_time'", "found 'sampel_time'"],
    ),
    (
        "meta: float pole pairs",
        m_meta_float_pole_pairs,
        "error",
        ["meta.yaml", "'pole_pairs' must be int", "1.5"],
    ),
    ("meta: bool pole pairs", m_meta_bool_pole_pairs, "error", ["meta.yaml", "'pole_pairs' must be int"]),
    (
        "meta: text sample time",
        m_meta_text_sample_time,
        "error",
        ["meta.yaml", "'sample_time' must be float"],
    ),
    ("meta: infinite sample time", m_meta_inf_sample_time, "error", ["meta.yaml", "'sample_time'", "finite"]),
    ("meta: 400-digit inertia", m_meta_huge_inertia, "error", ["meta.yaml", "'inertia'", "finite"]),
    (
        "meta: list input_hold",
        m_meta_list_hold,
        "error",
        ["meta.yaml", "'input_hold' must be 'zoh' or 'linear'"],
    ),
    ("meta: bad YAML", m_meta_bad_yaml, "error", ["meta.yaml", "not valid YAML"]),
    (
        "meta: impossible date",
        m_meta_bad_date,
        "error",
        ["meta.yaml", "not valid YAML", "day is out of range"],
    ),
    ("meta: a list", m_meta_list, "error", ["meta.yaml", "must be a mapping"]),
    ("meta: unknown key", m_meta_unknown_key, "warning", ["meta.yaml", "'intertia'", "found 'inertia'"]),
    (
        "speed over the hard limit",
        m_speed_over_limit,
        "error",
        ["startup.csv", "column 'speed', row 2400", "implausible in rad/s", "1600 rad/s", "rpm"],
    ),
    (
        "speed in rpm, supply declared",
        m_speed_rpm_declared_supply,
        "error",
        [
            "startup.csv",
            "column 'speed', row 2400",
            "impossible",
            "5.07 times the synchronous speed 314.2 rad/s",
            "(1592.74 rpm = 166.8 rad/s)",
        ],
    ),
    ("phase values overflow", m_phase_overflow, "error", ["startup.csv", "row 5", "overflows"]),
]


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
        and "estimated from the rotation of the currents (about 5" in m
        for m in msgs
    ), msgs
    assert any("stop.csv" in m for m in msgs), msgs
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
        "nan": (m_nan, ["error: ", "startup.csv, column 'v_beta', row 7: not a finite number"], ()),
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
