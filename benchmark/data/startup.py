"""Time-domain data sets (``kind: startup``, MODEL.md section 7): load, validate, write.

A folder holds ``meta.yaml``, one or more ``startup*.csv`` and optionally ``stop*.csv``.
Start-up columns: ``t``; voltages ``v_alpha, v_beta`` or phase ``v_r, v_s, v_t``; currents
``i_alpha, i_beta`` or phase ``i_r, i_s`` (the third from a zero sum); ``speed``, mechanical
rad/s. Phase quantities are turned into alpha-beta with the amplitude-invariant Clarke
transform (:func:`benchmark.model.experiment.clarke`). Stop columns: ``t``, ``speed``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmark.data.tables import (
    check_meta_type,
    check_time_column,
    read_meta,
    read_table,
    write_table_atomic,
    write_yaml_atomic,
)
from benchmark.errors import DataError
from benchmark.model.experiment import clarke

VOLTAGE_COLUMNS = (("v_alpha", "v_beta"), ("v_r", "v_s", "v_t"))
CURRENT_COLUMNS = (("i_alpha", "i_beta"), ("i_r", "i_s"))

#: A mechanical speed above this (rad/s, about 15 000 rpm) is implausible for a motor in
#: this benchmark; a column that exceeds it is probably in rpm.
PLAUSIBLE_SPEED_LIMIT = 1600.0


@dataclass
class StartupRecord:
    """One start-up record, alpha-beta (amplitude-invariant), SI units.

    Attributes: t (s), v_alpha, v_beta (V), i_alpha, i_beta (A), speed (mechanical rad/s).
    """

    t: np.ndarray
    v_alpha: np.ndarray
    v_beta: np.ndarray
    i_alpha: np.ndarray
    i_beta: np.ndarray
    speed: np.ndarray
    source: str = "memory"


@dataclass
class StopRecord:
    """One free-stop record: t (s, from supply removal), speed (mechanical rad/s)."""

    t: np.ndarray
    speed: np.ndarray
    source: str = "memory"


@dataclass
class StartupDataset:
    """A time-domain data set: what ``meta.yaml`` says plus its records.

    Attributes
    ----------
    pole_pairs : pole pairs p.
    sample_time : sample time of the start-up records, s.
    input_hold : ``zoh`` (switch-state voltages) or ``linear`` (sampled continuous voltages).
    dc_link_voltage, supply_frequency, inertia : V, Hz, kg m^2, or None when not given.
    """

    pole_pairs: int
    sample_time: float
    startups: list[StartupRecord]
    stops: list[StopRecord] = field(default_factory=list)
    input_hold: str = "linear"
    dc_link_voltage: float | None = None
    supply_frequency: float | None = None
    inertia: float | None = None
    folder: str | None = None

    def meta(self) -> dict:
        m = {
            "kind": "startup",
            "pole_pairs": int(self.pole_pairs),
            "sample_time": float(self.sample_time),
            "input_hold": self.input_hold,
        }
        for key in ("dc_link_voltage", "supply_frequency", "inertia"):
            if getattr(self, key) is not None:
                m[key] = float(getattr(self, key))
        return m


def load_startup_dataset(folder) -> StartupDataset:
    """Read and validate a ``kind: startup`` folder. Raises DataError naming file/column/row."""
    folder = Path(folder)
    meta = read_meta(folder, {"pole_pairs": int, "sample_time": float})
    meta_path = folder / "meta.yaml"
    kind = meta.get("kind", "startup")
    if kind != "startup":
        raise DataError(meta_path, f"kind is {kind!r}; this problem reads 'startup' data sets")
    p = meta["pole_pairs"]
    if p < 1:
        raise DataError(meta_path, f"key 'pole_pairs' must be >= 1, got {p}")
    ts = float(meta["sample_time"])
    if not ts > 0:
        raise DataError(meta_path, f"key 'sample_time' must be > 0 s, got {ts}")
    hold = meta.get("input_hold", "linear")
    if hold not in ("zoh", "linear"):
        raise DataError(meta_path, f"key 'input_hold' must be 'zoh' or 'linear', got {hold!r}")
    optional = {}
    for key in ("dc_link_voltage", "supply_frequency", "inertia"):
        if meta.get(key) is not None:
            meta[key] = check_meta_type(meta_path, key, meta[key], float)
            if not meta[key] > 0:
                raise DataError(meta_path, f"key '{key}' must be > 0, got {meta[key]}")
            optional[key] = float(meta[key])

    startup_files = sorted(folder.glob("startup*.csv"))
    if not startup_files:
        raise DataError(folder, "no startup*.csv file: a time-domain data set needs at least one start-up record")
    startups = [_read_startup(f, ts) for f in startup_files]
    stops = [_read_stop(f) for f in sorted(folder.glob("stop*.csv"))]
    return StartupDataset(
        pole_pairs=p,
        sample_time=ts,
        startups=startups,
        stops=stops,
        input_hold=hold,
        folder=str(folder),
        **optional,
    )


def _read_startup(path: Path, sample_time: float) -> StartupRecord:
    alternatives = [("t", *v, *i, "speed") for v in VOLTAGE_COLUMNS for i in CURRENT_COLUMNS]
    df, cols = read_table(path, alternatives)
    t = df["t"].to_numpy()
    step = check_time_column(path, t)
    if abs(step - sample_time) > 1e-3 * sample_time:
        raise DataError(
            path, f"time step {step:.6g} s differs from meta.yaml sample_time {sample_time:.6g} s", column="t"
        )
    if "v_alpha" in cols:
        v_a, v_b = df["v_alpha"].to_numpy(), df["v_beta"].to_numpy()
    else:
        v_a, v_b = clarke(df["v_r"], df["v_s"], df["v_t"])
    if "i_alpha" in cols:
        i_a, i_b = df["i_alpha"].to_numpy(), df["i_beta"].to_numpy()
    else:
        i_r, i_s = df["i_r"].to_numpy(), df["i_s"].to_numpy()
        i_a, i_b = clarke(i_r, i_s, -i_r - i_s)
    speed = df["speed"].to_numpy()
    _check_speed(path, speed)
    return StartupRecord(t=t - t[0], v_alpha=v_a, v_beta=v_b, i_alpha=i_a, i_beta=i_b, speed=speed, source=str(path))


def _read_stop(path: Path) -> StopRecord:
    df, _ = read_table(path, [("t", "speed")])
    t = df["t"].to_numpy()
    check_time_column(path, t)
    speed = df["speed"].to_numpy()
    _check_speed(path, speed)
    return StopRecord(t=t - t[0], speed=speed, source=str(path))


def _check_speed(path: Path, speed: np.ndarray) -> None:
    k = int(np.argmax(np.abs(speed)))
    if abs(speed[k]) > PLAUSIBLE_SPEED_LIMIT:
        raise DataError(
            path,
            f"speed {speed[k]:.6g} is implausible in rad/s (is the column in rpm? "
            f"rad/s = rpm * pi / 30)",
            column="speed",
            row=k + 1,
        )


def write_startup_dataset(folder, ds: StartupDataset, truth: dict | None = None) -> Path:
    """Write a data set in the section 7 format (alpha-beta columns); ``truth`` -> truth.yaml."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for k, r in enumerate(ds.startups):
        name = "startup.csv" if len(ds.startups) == 1 else f"startup_{k + 1}.csv"
        write_table_atomic(
            folder / name,
            {"t": r.t, "v_alpha": r.v_alpha, "v_beta": r.v_beta, "i_alpha": r.i_alpha, "i_beta": r.i_beta,
             "speed": r.speed},
            float_format="%.17g",
        )
    for k, r in enumerate(ds.stops):
        name = "stop.csv" if len(ds.stops) == 1 else f"stop_{k + 1}.csv"
        write_table_atomic(folder / name, {"t": r.t, "speed": r.speed}, float_format="%.17g")
    write_yaml_atomic(folder / "meta.yaml", ds.meta())
    if truth is not None:
        write_yaml_atomic(folder / "truth.yaml", truth)
    return folder
