"""The hostile data sets of ``test_hostile_data.py``: each a mutation of a valid set, with the outcome
it must give (an error or a warning naming the file, column and row, or a clean load)."""


import numpy as np

from tests.core.csv_edits import (
    RPM,
    add_column,
    drop_column,
    edit_cell,
    edit_header,
    lines,
    scale_column,
    set_meta,
    write_lines,
)

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
