"""The data set a user holds in memory: a folder's ``meta.yaml`` as a mapping and its tables as
pandas DataFrames (the format: ``docs/data_format.md``)."""

from __future__ import annotations

import hashlib
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from benchmark.core.errors import DataError
from benchmark.core.harness import DATA_KIND_PROBLEM
from benchmark.core.io import write_table_atomic, write_yaml_atomic
from benchmark.core.meta_file import read_meta, read_yaml
from benchmark.core.tables import read_all_columns

#: Tables a data folder may hold, by the start of their file name (``startup_2.csv``, ``sweep_up.mat``).
TABLE_PREFIXES = ("startup", "stop", "sweep")
TABLE_SUFFIXES = (".csv", ".mat")


@dataclass
class DataSet:
    """A data set: what its folder holds, in memory.

    Attributes
    ----------
    meta
        the contents of ``meta.yaml`` (``kind``, ``pole_pairs``, ``sample_time`` in s, ...;
        SI units, the keys of ``docs/data_format.md``).
    tables
        one DataFrame per record, keyed by its file name without suffix (``startup``,
        ``stop``, ``startup_2``, ``sweep``), columns as in the files (``t`` in s, ``v_alpha`` in V,
        ``i_alpha`` in A, ``speed`` in rad/s or rpm as ``meta["speed_unit"]`` says, ...).
    truth
        the generator's ``truth.yaml`` (true parameters, injected effects) or None. An
        identification reads it only to score its errors; a diagnosis never does.
    folder
        the folder it was loaded from, or None when made in memory.

    Example
    -------
    >>> import numpy as np, pandas as pd
    >>> from benchmark.api import DataSet
    >>> t = np.arange(3) * 1e-4
    >>> ds = DataSet(meta={"kind": "startup", "pole_pairs": 1, "sample_time": 1e-4},
    ...              tables={"startup": pd.DataFrame({"t": t, "v_alpha": 0 * t, "v_beta": 0 * t,
    ...                                               "i_alpha": 0 * t, "i_beta": 0 * t})})
    >>> ds.kind, ds.problem, list(ds.tables)
    ('startup', 'timedomain', ['startup'])
    """

    meta: dict
    tables: dict[str, pd.DataFrame]
    truth: dict | None = None
    folder: Path | None = None
    _loaded: str | None = field(default=None, repr=False, compare=False)

    @property
    def kind(self) -> str:
        """``startup`` (a start-up record, ``problem=timedomain``) or ``admittance`` (a slip sweep)."""
        return str(self.meta.get("kind", "startup"))

    @property
    def problem(self) -> str:
        """The problem that reads this kind of data set."""
        if self.kind not in DATA_KIND_PROBLEM:
            raise DataError("meta.yaml", f"kind {self.kind!r} is not one of {sorted(DATA_KIND_PROBLEM)}")
        return DATA_KIND_PROBLEM[self.kind]

    def write(self, folder, *, truth: bool = True) -> Path:
        """Write the data set as a folder (``meta.yaml``, one CSV per table with 17 significant
        digits, so that reading it back gives the same numbers bit for bit; ``truth.yaml`` if
        ``truth`` and there is one). Returns the folder."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        for name, table in self.tables.items():
            write_table_atomic(folder / f"{name}.csv", {c: table[c].to_numpy() for c in table.columns},
                               float_format="%.17g")
        write_yaml_atomic(folder / "meta.yaml", self.meta)
        if truth and self.truth is not None:
            write_yaml_atomic(folder / "truth.yaml", self.truth)
        return folder

    def unchanged(self) -> bool:
        """True when it was loaded from a folder and nothing has been changed since."""
        return self.folder is not None and self._loaded == self._fingerprint()

    def _fingerprint(self) -> str:
        h = hashlib.sha256(repr(sorted(self.meta.items(), key=str)).encode())
        for name in sorted(self.tables):
            h.update(name.encode())
            h.update(pd.util.hash_pandas_object(self.tables[name], index=True).to_numpy().tobytes())
            h.update(repr(list(self.tables[name].columns)).encode())
        return h.hexdigest()

    def __str__(self) -> str:
        rows = ", ".join(f"{k} ({len(v)} rows: {', '.join(map(str, v.columns))})" for k, v in self.tables.items())
        where = f" from {self.folder}" if self.folder is not None else " (in memory)"
        return f"{self.kind} data set{where}: {rows}"


def read_folder(path) -> DataSet:
    """Read a data folder into a :class:`DataSet` as the files hold it (no conditioning yet:
    that happens when it is identified or diagnosed; :func:`benchmark.api.load` also checks it
    as its problem reads it). A missing or malformed ``meta.yaml`` or table raises
    :class:`benchmark.core.errors.DataError` naming the file, column and row."""
    folder = Path(path)
    meta = read_meta(folder, {})
    tables: dict[str, pd.DataFrame] = {}
    for f in sorted(folder.iterdir()):
        if f.suffix.lower() in TABLE_SUFFIXES and f.name.lower().startswith(TABLE_PREFIXES):
            if f.stem in tables:
                raise DataError(f, f"the record {f.stem} is given twice (as .csv and .mat): keep one")
            tables[f.stem] = read_all_columns(f)
    truth_file = folder / "truth.yaml"
    truth = read_yaml(truth_file) if truth_file.is_file() else None
    ds = DataSet(meta=meta, tables=tables, truth=truth, folder=folder)
    ds._loaded = ds._fingerprint()
    return ds


@contextmanager
def as_folder(data: DataSet):
    """The folder of ``data`` for the problem's loader: its own when unchanged since it was
    loaded (errors then name the user's files), else a temporary copy removed afterwards."""
    if data.unchanged():
        yield data.folder
        return
    with tempfile.TemporaryDirectory(prefix="imbench-dataset-") as tmp:
        yield data.write(Path(tmp) / "data")
