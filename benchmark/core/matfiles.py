"""MATLAB records (``.mat``, versions 4 to 7, through ``scipy.io.loadmat``): vectors named like the
CSV columns; v7.3 (HDF5) files are refused with how to save them otherwise."""

from __future__ import annotations

import io
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from benchmark.core.errors import DataError
from benchmark.core.tables import _one_line, read_bytes, read_table, select_columns

#: The reader of ``.mat`` records: :func:`~benchmark.core.tables.read_table`, which reads a path
#: ending in ``.mat`` with :func:`read_mat_columns` (one signature for both formats).
read_mat_table = read_table


def read_mat_columns(path: Path, alternatives: Sequence[Sequence[str]], optional: Sequence[str],
                     max_bytes: int | None, warn_unused: bool) -> tuple[pd.DataFrame, tuple[str, ...]]:
    """Read a MATLAB ``.mat`` file whose variables are the columns: what
    :func:`~benchmark.core.tables.read_table` does for a path ending in ``.mat``, for what
    engineers save from MATLAB (``save('startup.mat', 't', 'v_r', ...)``); the arguments are
    :func:`~benchmark.core.tables.read_table`'s.

    Each variable is a numeric vector (row or column, any real numeric type) named like the
    CSV column, all of the same length; one of the column sets in ``alternatives`` must be
    present. MAT versions 4 to 7 are read (:func:`scipy.io.loadmat`); a v7.3 file (HDF5) is
    refused with a message saying to save it with ``-v7`` or to export CSV. Returns the same
    as :func:`read_table`: the matched and optional variables as finite float64 columns, and
    the matched set. Every problem is a DataError naming the file, the variable (as the
    column) and, for a bad value, its row (the 1-based index in the vector, as in MATLAB).
    """
    import scipy.io
    from scipy.io.matlab import matfile_version

    path = Path(path)
    raw = read_bytes(path, max_bytes=max_bytes, what="MAT file")
    if not raw:
        raise DataError(path, "file is empty")
    try:
        major, minor = matfile_version(io.BytesIO(raw))
    except Exception as exc:
        raise DataError(path, f"not a MATLAB .mat file ({_one_line(exc)}); save it from MATLAB with "
                              "save(..., '-v7') or export CSV") from None
    if major == 2:
        raise DataError(path, "a MATLAB v7.3 (HDF5) .mat file, which cannot be read here: save it with "
                              "save(FILE, VARIABLES..., '-v7') or export the variables as CSV")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            doc = scipy.io.loadmat(io.BytesIO(raw), squeeze_me=False, chars_as_strings=True,
                                   struct_as_record=True)
    except Exception as exc:  # scipy raises many kinds on a damaged file; all mean the same here
        raise DataError(path, f"not a readable MATLAB .mat file (version {major}): "
                              f"{type(exc).__name__}: {_one_line(exc)}") from None
    names = [str(k) for k in doc if not str(k).startswith("__")]
    if not names:
        raise DataError(path, "holds no variables")
    try:
        chosen, keep = select_columns(path, names, alternatives, optional, warn_unused, "variable")
    except DataError as exc:
        containers = [k for k in names if isinstance(doc[k], np.ndarray) and doc[k].dtype.kind in "OV"]
        if not containers:
            raise
        first = alternatives[0]
        raise DataError(path, f"{exc.message}; {containers} hold structs or cell arrays (Simulink's "
                              f"'Structure With Time'?): save each signal as its own vector named like the columns, "
                              f"e.g. {first[0]} = simout.time; {first[1]} = simout.signals.values(:, 1); ...; "
                              f"save('{path.name}', '{first[0]}', '{first[1]}', ..., '-v7')",
                        column=exc.column) from None
    out = {c: _mat_vector(path, c, doc[c]) for c in keep}
    n = len(out[keep[0]])
    for c in keep[1:]:
        if len(out[c]) != n:
            raise DataError(path, f"has {len(out[c])} values where '{keep[0]}' has {n} (every variable needs "
                                  "one value per sample)", column=c, row=min(len(out[c]), n) + 1)
    return pd.DataFrame(out), chosen


def _mat_vector(path: Path, name: str, value) -> np.ndarray:
    """A MAT variable as a finite float64 vector, or a DataError naming it."""
    if not isinstance(value, np.ndarray):
        raise DataError(path, f"is a {type(value).__name__} (a sparse matrix?), expected a numeric vector",
                        column=name)
    kind = value.dtype.kind
    if kind in "USa":
        raise DataError(path, "holds text, expected a numeric vector", column=name)
    if kind in "OV":
        raise DataError(path, "is a cell array or struct, expected a numeric vector", column=name)
    if kind == "c":
        raise DataError(path, "holds complex values, expected real numbers", column=name)
    if kind not in "fiub":
        raise DataError(path, f"has values of type {value.dtype}, expected real numbers", column=name)
    if value.size == 0:
        raise DataError(path, "is empty", column=name)
    if sum(d > 1 for d in value.shape) > 1:
        dims = "x".join(str(d) for d in value.shape)
        raise DataError(path, f"is a {dims} matrix, expected a vector (one value per sample)", column=name)
    v = value.astype(float).ravel()
    bad = ~np.isfinite(v)
    if bad.any():
        k = int(np.argmax(bad))
        raise DataError(path, f"not a finite number: {v[k]!r}", column=name, row=k + 1)
    return v
