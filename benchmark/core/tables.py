"""Reading and writing the data-set folders of docs/data_format.md, with validation.

Every problem found in a file is raised as :class:`benchmark.core.errors.DataError` naming the
file, the column and the row (1-based data row, the header being row 0, so row ``n`` is line
``n + 1`` of the file), so a user can find it in a spreadsheet. Nothing else escapes the
readers: whatever bytes a file holds, they either load or raise ``DataError``
(``tests/test_fuzz.py``).

Accepted text: UTF-8 with or without a byte-order mark, or UTF-16/32 with one (what
spreadsheets write as "Unicode text"). Accepted tables: the header on the first line,
columns separated by ``,``, ``;`` or a tab (whichever the header uses); in a ``;``- or
tab-separated table decimals may be written with a comma (``1,5``) as long as no cell of
the table uses a point, so that the reading is unambiguous. Blank lines at the end are
ignored; a blank line between data rows is an error (rows would shift).

MATLAB ``.mat`` files (versions 4 to 7; a path ending in ``.mat``) are read by :func:`read_table`
too (:func:`benchmark.core.matfiles.read_mat_columns`), with the same return and the same kind of
errors: the variable stands for the column, the 1-based index in
the vector for the row.
"""

from __future__ import annotations

import contextlib
import csv
import io
import re
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from benchmark.core.errors import DataError
from benchmark.core.spelling import found_instead

#: Largest table read, in bytes; a larger file is refused before it is read. The harness
#: sets it from ``data.max_file_mib`` for the duration of a run (:func:`table_size_limit`).
MAX_TABLE_BYTES = 512 * 1024 * 1024
#: Largest ``meta.yaml`` (or other YAML side file) read, in bytes.
MAX_YAML_BYTES = 1024 * 1024

_size_limit_override: int | None = None

SEPARATORS = {",": "comma", ";": "semicolon", "\t": "tab"}
_BOMS = (
    (b"\x00\x00\xfe\xff", "utf-32-be"),
    (b"\xff\xfe\x00\x00", "utf-32-le"),
    (b"\xef\xbb\xbf", "utf-8-sig"),
    (b"\xff\xfe", "utf-16"),
    (b"\xfe\xff", "utf-16"),
)


def max_table_bytes() -> int:
    """The size limit in force (see :data:`MAX_TABLE_BYTES`)."""
    return _size_limit_override if _size_limit_override is not None else MAX_TABLE_BYTES


@contextlib.contextmanager
def table_size_limit(max_bytes: int | None):
    """Within the block, tables larger than ``max_bytes`` are refused (None: the default)."""
    global _size_limit_override
    saved = _size_limit_override
    _size_limit_override = None if max_bytes is None else int(max_bytes)
    try:
        yield
    finally:
        _size_limit_override = saved


def read_text(path: Path, max_bytes: int | None = None, what: str = "file") -> str:
    """Read a text file: size limit, byte-order mark, encoding and NUL bytes checked; any
    problem (also an unreadable file or a folder in its place) is a DataError."""
    return decode_text(Path(path), read_bytes(path, max_bytes, what))


def read_bytes(path: Path, max_bytes: int | None = None, what: str = "file") -> bytes:
    """The bytes of a file under the size limit (:func:`max_table_bytes` unless ``max_bytes``);
    a missing or unreadable file, a folder in its place or a file over the limit is a DataError."""
    path = Path(path)
    limit = max_table_bytes() if max_bytes is None else int(max_bytes)
    try:
        if not path.is_file():
            raise DataError(path, "not a regular file" if path.exists() else "does not exist")
        size = path.stat().st_size
        if size > limit:
            raise DataError(
                path,
                f"{what} is {_human_bytes(size)}, larger than the {_human_bytes(limit)} limit "
                "(data.max_file_mib raises it)",
            )
        raw = path.read_bytes()
    except OSError as exc:
        raise DataError(path, f"cannot read: {exc.strerror or exc}") from None
    if len(raw) > limit:  # grew while being read
        raise DataError(path, f"{what} is larger than the {_human_bytes(limit)} limit")
    return raw


def decode_text(path: Path, raw: bytes) -> str:
    """Bytes -> str: a byte-order mark selects UTF-8/16/32; without one, UTF-8."""
    encoding = next((enc for bom, enc in _BOMS if raw.startswith(bom)), "utf-8")
    try:
        text = raw.decode(encoding)
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise DataError(
            path,
            f"not {encoding.upper().replace('-SIG', '')} text: byte 0x{raw[exc.start]:02x} on line {line} "
            "(save the file as UTF-8 text)",
        ) from None
    text = text.lstrip("\ufeff")
    nul = text.find("\x00")
    if nul >= 0:
        raise DataError(path, f"contains a NUL character on line {text.count(chr(10), 0, nul) + 1} "
                              "(a binary file, or text in an encoding without a byte-order mark?)")
    return text


def read_table(
    path: Path,
    alternatives: Sequence[Sequence[str]],
    optional: Sequence[str] = (),
    *,
    max_bytes: int | None = None,
    warn_unused: bool = False,
) -> tuple[pd.DataFrame, tuple[str, ...]]:
    """Read a CSV table whose header must hold one of the column sets in ``alternatives``.

    Every returned column is finite float64. Returns the table (only the matched and optional
    columns) and the matched column set. ``max_bytes`` overrides the size limit
    (:func:`max_table_bytes`); ``warn_unused`` warns (:class:`DataWarning`) about columns that
    are neither matched nor optional. A path ending in ``.mat`` is read as a MATLAB file whose
    variables are the columns (:func:`benchmark.core.matfiles.read_mat_columns`).
    """
    path = Path(path)
    if path.suffix.lower() == ".mat":
        from benchmark.core.matfiles import read_mat_columns

        return read_mat_columns(path, alternatives, optional, max_bytes, warn_unused)
    text = read_text(path, max_bytes=max_bytes, what="table")
    if not text.strip():
        raise DataError(path, "file is empty")
    header_line = re.split(r"\r\n|\r|\n", text, maxsplit=1)[0]
    if not header_line.strip():
        raise DataError(path, "the first line must be the header (column names), found a blank line", row=0)
    sep = _separator(header_line)
    try:
        names = [c.strip() for c in next(csv.reader([header_line], delimiter=sep))]
    except (csv.Error, StopIteration) as exc:
        raise DataError(path, f"unreadable header: {exc}", row=0) from None
    _check_header(path, names)
    df = _parse(path, text, sep, len(names))
    if len(df.columns) != len(names):
        raise DataError(path, f"the header has {len(names)} columns but pandas read {len(df.columns)}", row=0)
    df.columns = names
    # blank lines at the end are harmless; elsewhere they shift rows
    empty_row = (df == "").all(axis=1).to_numpy()
    n = len(df)
    while n and empty_row[n - 1]:
        n -= 1
    df = df.iloc[:n]
    if n == 0:
        raise DataError(path, "has a header but no data rows")
    if empty_row[:n].any():
        k = int(np.argmax(empty_row[:n]))
        raise DataError(path, "blank line between data rows (delete it)", row=k + 1)

    chosen, keep = select_columns(path, names, alternatives, optional, warn_unused, "column")
    decimal_comma = sep != "," and _uses_decimal_comma(path, df[keep])
    out = {}
    for c in keep:
        out[c] = _to_float(path, c, df[c], decimal_comma=decimal_comma, text=text, sep=sep,
                           n_fields=len(names))
    return pd.DataFrame(out), chosen


def read_all_columns(path: Path, *, max_bytes: int | None = None) -> pd.DataFrame:
    """Every column of a CSV table (or every variable of a ``.mat`` file) as finite float64, in
    the file's order: :func:`read_table` with the file's own header as the column set (the same
    separators, decimal commas and errors naming file, column and row)."""
    path = Path(path)
    if path.suffix.lower() == ".mat":
        import scipy.io

        try:
            names = [name for name, _, _ in scipy.io.whosmat(str(path))]
        except Exception as exc:
            raise DataError(path, f"not a readable MATLAB .mat file: {_one_line(exc)}") from None
    else:
        text = read_text(path, max_bytes=max_bytes, what="table")
        header = re.split(r"\r\n|\r|\n", text, maxsplit=1)[0]
        names = [c.strip() for c in next(csv.reader([header], delimiter=_separator(header)), [])]
    df, _ = read_table(path, [tuple(names)], max_bytes=max_bytes)
    return df


def _separator(header: str) -> str:
    counts = {s: header.count(s) for s in SEPARATORS}
    if counts[","]:
        return ","
    if counts[";"]:
        return ";"
    if counts["\t"]:
        return "\t"
    return ","


def _check_header(path: Path, names: list[str]) -> None:
    seen: dict[str, int] = {}
    for k, name in enumerate(names):
        if name == "":
            if k == len(names) - 1 and len(names) > 1:
                raise DataError(path, f"the header ends with a separator: column {k + 1} has no name "
                                      "(a trailing comma?)", row=0)
            raise DataError(path, f"column {k + 1} of the header has no name", row=0)
        if name in seen:
            raise DataError(path, f"column '{name}' appears twice in the header (columns {seen[name] + 1} "
                                  f"and {k + 1})", column=name, row=0)
        seen[name] = k


def _parse(path: Path, text: str, sep: str, n_fields: int) -> pd.DataFrame:
    """All cells as stripped strings ('' when missing), one row per data line."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", pd.errors.ParserWarning)
            df = pd.read_csv(io.StringIO(text), sep=sep, dtype=str, header=0, skipinitialspace=True,
                             skip_blank_lines=False, index_col=False, keep_default_na=False, na_filter=False,
                             quoting=csv.QUOTE_MINIMAL, engine="c")
    except (pd.errors.ParserError, pd.errors.ParserWarning, pd.errors.EmptyDataError, ValueError,
            csv.Error, OverflowError) as exc:
        m = re.search(r"EOF inside string starting at row (\d+)", str(exc))
        if m:
            raise DataError(path, 'a quote (") opened here is never closed', row=int(m.group(1))) from None
        row, count = _ragged_row(text, sep, n_fields)
        if row is not None:
            raise DataError(path, f"has {count} fields where the header has {n_fields}"
                                  + _ragged_hint(sep, count, n_fields), row=row) from None
        raise DataError(path, f"not a readable CSV table: {_one_line(exc)}") from None
    return df.apply(lambda s: s.astype(str).str.strip()) if len(df.columns) else df


def _ragged_row(text: str, sep: str, n_fields: int) -> tuple[int | None, int]:
    """First data row whose number of fields differs from the header's (None if none)."""
    try:
        reader = csv.reader(io.StringIO(text), delimiter=sep, skipinitialspace=True)
        for k, fields in enumerate(reader):
            if k > 0 and fields and len(fields) != n_fields:
                return k, len(fields)
    except csv.Error:
        return None, 0
    return None, 0


def _ragged_hint(sep: str, count: int, n_fields: int) -> str:
    if sep == "," and count > n_fields:
        return (" (a comma decimal separator? use '.' for decimals, or separate the columns with ';' "
                "and keep the comma decimals)")
    return ""


_COMMA_NUMBER = re.compile(r"^[+-]?(\d+,\d*|,\d+)([eE][+-]?\d+)?$")


def _uses_decimal_comma(path: Path, df: pd.DataFrame) -> bool:
    """In a ';'/tab table: True if numbers are written with decimal commas. A table that
    mixes '1,5' and '1.5' is ambiguous (',' could be a thousands separator) and refused."""
    comma = dot = None
    for c in df.columns:
        s = df[c]
        has_comma = s.str.contains(",", regex=False).to_numpy()
        if comma is None and has_comma.any():
            k = int(np.argmax(has_comma))
            comma = (c, k, s.iloc[k])
        has_dot = s.str.contains(".", regex=False).to_numpy()
        if dot is None and has_dot.any():
            k = int(np.argmax(has_dot))
            dot = (c, k, s.iloc[k])
    if comma is None:
        return False
    if dot is not None:
        raise DataError(
            path,
            f"mixes decimal separators: {comma[2]!r} (column '{comma[0]}', row {comma[1] + 1}) and "
            f"{dot[2]!r} (column '{dot[0]}', row {dot[1] + 1}); use one of '.' or ','",
            column=dot[0], row=dot[1] + 1,
        )
    return True


def _to_float(path: Path, column: str, s: pd.Series, decimal_comma: bool = False, text: str | None = None,
              sep: str = ",", n_fields: int = 0) -> np.ndarray:
    stripped = s.fillna("").astype(str).str.strip()
    if decimal_comma:
        ok = stripped.str.match(_COMMA_NUMBER) | ~stripped.str.contains(",", regex=False)
        converted = stripped.str.replace(",", ".", regex=False).where(ok, "not-a-number")
    else:
        converted = stripped
    with np.errstate(all="ignore"):
        values = pd.to_numeric(converted, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        k = int(np.argmax(bad))
        cell = stripped.iloc[k]
        hint = ""
        if "," in cell and not decimal_comma:
            hint = " (a comma decimal separator? use '.' for decimals and ',' between columns)"
        if cell == "":
            what = "empty"
            if text is not None:
                fields = _fields_of_row(text, sep, k + 1)
                if fields is not None and fields < n_fields:
                    what += f" (the row has {fields} fields where the header has {n_fields})"
        elif re.fullmatch(r"[+-]?(\d+\.?\d*|\.\d+)[eE][+-]?\d+", cell):
            what = f"number out of range: {_short_repr(cell)}"
        else:
            what = f"not a finite number: {_short_repr(cell)}"
        raise DataError(path, what + hint, column=column, row=k + 1)
    return values


def _fields_of_row(text: str, sep: str, row: int) -> int | None:
    try:
        for k, fields in enumerate(csv.reader(io.StringIO(text), delimiter=sep)):
            if k == row:
                return len(fields)
    except csv.Error:
        return None
    return None


#: Share of a time column's steps off its median step beyond which the record is taken for a
#: variable-step simulation's output rather than a record with a few missing samples.
VARIABLE_STEP_SHARE = 0.05


def check_time_column(path: Path, t: np.ndarray, column: str = "t", rel_tol: float = 1e-3) -> float:
    """Check a time column strictly increases on a uniform grid; return the step (s).

    Uniform means: no step differs from the median step by more than half a step (a gap or
    a doubled sample), and no time deviates from the straight line through the first and
    last times by more than 1 % of a step (timestamps rounded to a few digits pass). The
    returned step is that line's slope. ``rel_tol`` is kept for backward compatibility."""
    t = np.asarray(t, dtype=float)
    if len(t) < 2:
        raise DataError(path, "needs at least two rows", column=column)
    with np.errstate(all="ignore"):
        dt = np.diff(t)
        if not np.all(np.isfinite(dt)):
            k = int(np.argmax(~np.isfinite(dt))) + 1
            raise DataError(path, f"time step from {t[k - 1]:.9g} to {t[k]:.9g} is not finite", column=column,
                            row=k + 1)
        bad = dt <= 0
        if bad.any():
            k = int(np.argmax(bad)) + 1
            raise DataError(path, f"time must increase: {t[k]:.9g} follows {t[k - 1]:.9g}", column=column,
                            row=k + 1)
        median = float(np.median(dt))
        jump = np.abs(dt - median) > 0.5 * median
        if jump.any():
            k = int(np.argmax(jump)) + 1
            why = "(missing or repeated samples?)"
            if np.mean(jump) > VARIABLE_STEP_SHARE:
                why = (f"and {100 * np.mean(jump):.0f} % of the steps are off it, from {dt.min():.3g} to "
                       f"{dt.max():.3g} s: a variable-step solver's output? Log it at a fixed sample time "
                       "(a fixed-step solver, or the logging block's sample time) or resample every column "
                       "onto a uniform grid first")
            raise DataError(
                path,
                f"irregular sampling: step {dt[k - 1]:.6g} s where the record's step is {median:.6g} s {why}",
                column=column,
                row=k + 1,
            )
        n = len(t)
        step = float((t[-1] - t[0]) / (n - 1))
        dev = np.abs(t - (t[0] + step * np.arange(n)))
        off = dev > 0.01 * step + 4 * np.spacing(np.abs(t).max())
    if not (np.isfinite(step) and step > 0):
        raise DataError(path, f"time step {step!r} is not a positive number", column=column)
    if off.any():
        k = int(np.argmax(off))
        raise DataError(
            path,
            f"irregular sampling: t = {t[k]:.9g} is {dev[k] / step:.3g} steps off the uniform grid of step "
            f"{step:.6g} s (the model needs uniformly sampled records; timestamps rounded to too few "
            "digits?)",
            column=column,
            row=k + 1,
        )
    return step


def select_columns(path: Path, names: Sequence[str], alternatives: Sequence[Sequence[str]],
                   optional: Sequence[str], warn_unused: bool, what: str) -> tuple[tuple[str, ...], list[str]]:
    """The first column set of ``alternatives`` that ``names`` holds, and the columns to keep
    (it plus the optional ones present). A DataError names the missing ``what`` (column or
    variable) and a near miss; a DataWarning lists the unused ones when ``warn_unused``."""
    have = set(names)
    chosen = next((tuple(a) for a in alternatives if set(a) <= have), None)
    if chosen is None:
        best = max(alternatives, key=lambda a: len(set(a) & have))
        missing = [c for c in best if c not in have]
        options = " or ".join("(" + ", ".join(a) + ")" for a in alternatives)
        hint = found_instead(missing[0], [c for c in names if c not in best])
        raise DataError(path, f"missing {what}(s) {missing}{hint}; expected {options}; found {list(names)}",
                        column=missing[0])
    keep = list(chosen) + [c for c in optional if c in have and c not in chosen]
    check_optional_near_misses(path, optional, keep, names, what)
    if warn_unused:
        unused = [c for c in names if c not in keep]
        if unused:
            from benchmark.core.errors import DataWarning

            warnings.warn(DataWarning.at(path, f"{what}(s) {unused} not used (ignored); used: {keep}"),
                          stacklevel=3)
    return chosen, keep


def check_optional_near_misses(path: Path, optional: Sequence[str], keep: Sequence[str], names: Sequence[str],
                               what: str) -> None:
    """An optional column that is absent while another column looks like it (``Speed`` for
    ``speed``) is a DataError: it is probably misnamed, not missing on purpose."""
    for c in optional:
        if c in keep:
            continue
        hint = found_instead(c, [n for n in names if n not in keep])
        if hint:
            raise DataError(path, f"no {what} '{c}'{hint}; rename it '{c}' (or remove it if the record has no {c})",
                            column=c)


def _short_repr(value, limit: int = 60) -> str:
    try:
        r = repr(value)
    except Exception:  # a repr that fails (e.g. an int of 5000 digits) must not hide the message
        r = f"<{type(value).__name__}>"
    return r if len(r) <= limit else r[: limit - 3] + "..."


def _one_line(exc: BaseException, limit: int = 300) -> str:
    msg = " ".join(str(exc).split())
    return msg if len(msg) <= limit else msg[: limit - 3] + "..."


def _human_bytes(n: int) -> str:
    if n >= 2**20:
        return f"{n / 2**20:.4g} MiB"
    if n >= 2**10:
        return f"{n / 2**10:.4g} KiB"
    return f"{n} bytes"
