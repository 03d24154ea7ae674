"""Reading and writing the data-set folders of MODEL.md section 7, with validation.

Every problem found in a file is raised as :class:`benchmark.errors.DataError` naming the
file, the column and the row (1-based data row, the header being row 0), so a user can find
it in a spreadsheet.
"""

from __future__ import annotations

import io
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from benchmark.errors import DataError

#: Largest table read, in bytes; a larger file is refused before it is parsed.
MAX_TABLE_BYTES = 512 * 1024 * 1024


def read_meta(folder: Path, required: dict[str, type | tuple[type, ...]]) -> dict:
    """Read ``folder/meta.yaml`` and check that each required key is present with a usable type."""
    path = Path(folder) / "meta.yaml"
    if not Path(folder).is_dir():
        raise DataError(folder, "data set folder does not exist")
    if not path.is_file():
        raise DataError(path, "missing: every data set folder needs a meta.yaml (MODEL.md section 7)")
    try:
        meta = yaml.safe_load(path.read_text(encoding="utf-8-sig"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise DataError(path, f"not valid YAML: {exc}") from None
    if not isinstance(meta, dict):
        raise DataError(path, "must be a mapping of keys to values")
    for key, kind in required.items():
        if key not in meta:
            raise DataError(path, f"missing key '{key}'")
        meta[key] = check_meta_type(path, key, meta[key], kind)
    return meta


def check_meta_type(path: Path, key: str, value, kind):
    """Check a meta.yaml value's type and return it (a float written as ``1e-3``, which YAML
    reads as a string, is accepted as the number)."""
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if float in kinds and isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            pass
    ok = any(
        isinstance(value, k) and not (k in (int, float) and isinstance(value, bool)) for k in kinds
    )
    if float in kinds and isinstance(value, int) and not isinstance(value, bool):
        ok = True
    if not ok:
        names = " or ".join(k.__name__ for k in kinds)
        raise DataError(path, f"key '{key}' must be {names}, got {value!r}")
    return value


def read_table(
    path: Path,
    alternatives: Sequence[Sequence[str]],
    optional: Sequence[str] = (),
) -> tuple[pd.DataFrame, tuple[str, ...]]:
    """Read a CSV table whose header must hold one of the column sets in ``alternatives``.

    Every returned column is finite float64. Returns the table (only the matched and optional
    columns) and the matched column set.
    """
    path = Path(path)
    size = path.stat().st_size
    if size == 0:
        raise DataError(path, "file is empty")
    if size > MAX_TABLE_BYTES:
        raise DataError(path, f"file is {size / 2**20:.0f} MiB, larger than the {MAX_TABLE_BYTES // 2**20} MiB limit")
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise DataError(path, "not UTF-8 text") from None
    try:
        df = pd.read_csv(io.StringIO(text), dtype=str, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise DataError(path, f"not a readable CSV table: {str(exc).strip()}") from None
    df.columns = [str(c).strip() for c in df.columns]
    if len(df) == 0:
        raise DataError(path, "has a header but no data rows")
    cols = set(df.columns)
    chosen = next((tuple(a) for a in alternatives if set(a) <= cols), None)
    if chosen is None:
        best = max(alternatives, key=lambda a: len(set(a) & cols))
        missing = [c for c in best if c not in cols]
        options = " or ".join("(" + ", ".join(a) + ")" for a in alternatives)
        raise DataError(
            path,
            f"missing column(s) {missing}; expected {options}; found {list(df.columns)}",
            column=missing[0],
        )
    keep = list(chosen) + [c for c in optional if c in cols and c not in chosen]
    out = {}
    for c in keep:
        out[c] = _to_float(path, c, df[c])
    return pd.DataFrame(out), chosen


def _to_float(path: Path, column: str, s: pd.Series) -> np.ndarray:
    stripped = s.fillna("").astype(str).str.strip()
    values = pd.to_numeric(stripped, errors="coerce").to_numpy(dtype=float)
    bad = ~np.isfinite(values)
    if bad.any():
        k = int(np.argmax(bad))
        cell = stripped.iloc[k]
        hint = ""
        if "," in cell:
            hint = " (a comma decimal separator? use '.' for decimals and ',' between columns)"
        what = "empty" if cell == "" else f"not a finite number: {cell!r}"
        raise DataError(path, what + hint, column=column, row=k + 1)
    return values


def check_time_column(path: Path, t: np.ndarray, column: str = "t", rel_tol: float = 1e-3) -> float:
    """Check a time column strictly increases with a uniform step; return the step (s)."""
    if len(t) < 2:
        raise DataError(path, "needs at least two rows", column=column)
    dt = np.diff(t)
    bad = dt <= 0
    if bad.any():
        k = int(np.argmax(bad)) + 1
        raise DataError(path, f"time must increase: {t[k]!r} follows {t[k - 1]!r}", column=column, row=k + 1)
    step = float(np.median(dt))
    irregular = np.abs(dt - step) > rel_tol * step + 1e-12
    if irregular.any():
        k = int(np.argmax(irregular)) + 1
        raise DataError(
            path,
            f"irregular sampling: step {dt[k - 1]:.6g} s where the record's step is {step:.6g} s",
            column=column,
            row=k + 1,
        )
    return step


def write_table_atomic(path: Path, table: dict[str, np.ndarray], float_format: str = "%.9g") -> None:
    """Write a CSV table so that a crash never leaves a half-written file."""
    df = pd.DataFrame(table)
    write_text_atomic(path, df.to_csv(index=False, float_format=float_format, lineterminator="\n"))


def write_text_atomic(path: Path, text: str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_yaml_atomic(path: Path, data: dict) -> None:
    write_text_atomic(path, yaml.safe_dump(data, sort_keys=False))
