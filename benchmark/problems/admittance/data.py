"""The admittance data set (``kind: admittance``, docs/data_format.md): read, validate, write.

Folder layout
-------------
``meta.yaml``
    ``kind: admittance``, ``frequency`` (Hz), ``pole_pairs``, ``voltage`` (V per phase, RMS; unless
    every table has a ``voltage`` column). Optional: ``full_scale_admittance`` (S; the admittance of
    a full-scale ammeter deflection, the misfit unit), ``stator_dc_resistance`` (ohm, ``[before,
    after]`` the sweeps), and, beyond section 7 (all optional, documented here):

    * ``dc_resistance_time``: ``[t_before, t_after]``, s, on the clock of the ``time`` column (default:
      the first and last reading times);
    * ``winding_temperature_before``: deg C at the first DC measurement (default: equal to the
      reference temperature, i.e. results are referred to the temperature at the start);
    * ``reference_temperature``: deg C to which fitted resistances are referred;
    * ``thermal``: cooling constants from cooling curves, ``{ambient_temperature (deg C),
      cooling_rate_standstill (1/s), cooling_rate_at_speed (1/s), cooling_rate_speed_rpm (rpm)}``
      (the cooling rate is ``K/C``, the initial slope of a cooling curve over the temperature rise);
    * ``supply_off``: list of ``[t0, t1]`` intervals (s) with the supply disconnected between sweep
      tables (for the heat estimate; by default the machine is taken to be energised, settling at the
      next table's first reading, between tables);
    * ``full_scale_torque`` (N m), ``description``.
``sweep*.csv`` (one or more, read in name order = acquisition order)
    ``speed_rpm`` or ``slip``; ``G``, ``B`` (S, per phase); optional ``torque`` (N m, electromagnetic:
    friction and windage removed), ``time`` (s), ``voltage`` (V).
``truth.yaml`` (synthetic data only; never read by the cost)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmark.core.errors import DataError
from benchmark.core.io import write_table_atomic, write_yaml_atomic
from benchmark.core.meta_file import read_meta
from benchmark.core.tables import read_table
from benchmark.problems.admittance.circuit import slip_from_speed, speed_from_slip
from benchmark.problems.admittance.sweep_checks import check_sweep_table

__all__ = ["AdmittanceData", "load_admittance", "load_steady_state", "write_admittance", "read_truth"]

THERMAL_KEYS = (
    "ambient_temperature",
    "cooling_rate_standstill",
    "cooling_rate_at_speed",
    "cooling_rate_speed_rpm",
)


@dataclass
class AdmittanceData:
    """A slip sweep (all tables concatenated in acquisition order).

    Attributes
    ----------
    frequency : Hz.  pole_pairs : p.  slip, speed_rpm : per unit, rpm.  G, B : S per phase.
    voltage : V per phase RMS, per reading.  time : s per reading, or None.  torque : N m per
    reading, or None.  sweep : index of the table each reading came from.
    full_scale_admittance : S (the misfit unit), or None (the loader's user picks a default).
    stator_dc_resistance : ``(before, after)`` ohm, or None.  dc_resistance_time : ``(t_before,
    t_after)`` s, or None.  winding_temperature_before, reference_temperature : deg C or None.
    thermal : cooling constants (see module doc) or None.  supply_off : ``[(t0, t1), ...]`` s, or
    None.  source : where the data came from.
    """

    frequency: float
    pole_pairs: int
    slip: np.ndarray
    G: np.ndarray
    B: np.ndarray
    voltage: np.ndarray
    time: np.ndarray | None = None
    torque: np.ndarray | None = None
    sweep: np.ndarray | None = None
    full_scale_admittance: float | None = None
    full_scale_torque: float | None = None
    stator_dc_resistance: tuple[float, float] | None = None
    dc_resistance_time: tuple[float, float] | None = None
    winding_temperature_before: float | None = None
    reference_temperature: float | None = None
    thermal: dict | None = None
    supply_off: list[tuple[float, float]] | None = None
    source: str = "memory"
    description: str = ""
    files: list[str] = field(default_factory=list)
    frequency_ratio: np.ndarray | None = None
    winding_temperature: np.ndarray | None = None
    test: np.ndarray | None = None
    sigma_G: np.ndarray | None = None
    sigma_B: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)
    loadtest: object = None

    @property
    def Y(self) -> np.ndarray:
        return self.G + 1j * self.B

    @property
    def speed_rpm(self) -> np.ndarray:
        return speed_from_slip(self.slip, self.frequency, self.pole_pairs)

    @property
    def n(self) -> int:
        return len(self.slip)


def _positive(path, key, value):
    if not (np.isfinite(value) and value > 0):
        raise DataError(path, f"key '{key}' must be a positive number, got {value!r}")


def _pair(path, meta, key):
    v = meta.get(key)
    if v is None:
        return None
    if not (isinstance(v, (list, tuple)) and len(v) == 2):
        raise DataError(path, f"key '{key}' must be a list [before, after] of two numbers, got {v!r}")
    try:
        out = (float(v[0]), float(v[1]))
    except (TypeError, ValueError):
        raise DataError(path, f"key '{key}' must hold two numbers, got {v!r}") from None
    if not all(np.isfinite(out)):
        raise DataError(path, f"key '{key}' must hold finite numbers, got {v!r}")
    return out


def _optional_float(path, meta, key):
    v = meta.get(key)
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
        raise DataError(path, f"key '{key}' must be a finite number, got {v!r}")
    return float(v)


def load_admittance(folder) -> AdmittanceData:
    """Read and validate an admittance data set folder; every problem raises :class:`DataError`
    naming the file, key, column and row."""
    folder = Path(folder)
    meta = read_meta(folder, {"kind": str, "frequency": float, "pole_pairs": int})
    mpath = folder / "meta.yaml"
    if meta["kind"] != "admittance":
        raise DataError(mpath, f"key 'kind' is {meta['kind']!r}; problem=admittance reads kind 'admittance' "
                        "(a slip sweep) or 'loadtest' (the tables of a motor test report)")
    f = float(meta["frequency"])
    _positive(mpath, "frequency", f)
    p = int(meta["pole_pairs"])
    if p < 1:
        raise DataError(mpath, f"key 'pole_pairs' must be a positive integer, got {p}")
    v_meta = _optional_float(mpath, meta, "voltage")
    if v_meta is not None:
        _positive(mpath, "voltage", v_meta)
    fs = _optional_float(mpath, meta, "full_scale_admittance")
    if fs is not None:
        _positive(mpath, "full_scale_admittance", fs)
    fs_t = _optional_float(mpath, meta, "full_scale_torque")
    if fs_t is not None:
        _positive(mpath, "full_scale_torque", fs_t)
    rdc = _pair(mpath, meta, "stator_dc_resistance")
    if rdc is not None and min(rdc) <= 0:
        raise DataError(mpath, f"key 'stator_dc_resistance' must hold positive resistances, got {list(rdc)}")
    tdc = _pair(mpath, meta, "dc_resistance_time")
    if tdc is not None and tdc[1] < tdc[0]:
        raise DataError(mpath, f"key 'dc_resistance_time': after ({tdc[1]}) precedes before ({tdc[0]})")
    thermal = meta.get("thermal")
    if thermal is not None:
        if not isinstance(thermal, dict):
            raise DataError(mpath, f"key 'thermal' must be a mapping with keys {list(THERMAL_KEYS)}")
        missing = [k for k in THERMAL_KEYS if k not in thermal]
        if missing:
            raise DataError(mpath, f"key 'thermal' lacks {missing}")
        thermal = {k: _optional_float(mpath, thermal, k) for k in THERMAL_KEYS}
        for k in ("cooling_rate_standstill", "cooling_rate_at_speed"):
            if thermal[k] < 0:
                raise DataError(mpath, f"key 'thermal.{k}' must be >= 0, got {thermal[k]}")
        _positive(mpath, "thermal.cooling_rate_speed_rpm", thermal["cooling_rate_speed_rpm"])

    supply_off = meta.get("supply_off")
    if supply_off is not None:
        ok = isinstance(supply_off, list) and all(
            isinstance(iv, list)
            and len(iv) == 2
            and all(isinstance(v, (int, float)) for v in iv)
            and iv[0] <= iv[1]
            for iv in supply_off
        )
        if not ok:
            raise DataError(
                mpath, f"key 'supply_off' must be a list of [t0, t1] intervals (s), got {supply_off!r}"
            )
        supply_off = [(float(a), float(b)) for a, b in supply_off]

    files = sorted(folder.glob("sweep*.csv"))
    if not files:
        raise DataError(folder, "no sweep*.csv table found (docs/data_format.md, kind admittance)")
    parts = {k: [] for k in ("slip", "G", "B", "voltage", "time", "torque", "sweep")}
    has = {"time": None, "torque": None}
    for k, path in enumerate(files):
        df, chosen = read_table(
            path, [("speed_rpm", "G", "B"), ("slip", "G", "B")], optional=("torque", "time", "voltage")
        )
        for col in ("time", "torque"):
            present = col in df.columns
            if has[col] is None:
                has[col] = present
            elif has[col] != present:
                raise DataError(path, f"column '{col}' must be in every sweep table or in none", column=col)
        s = df["slip"].to_numpy() if "slip" in chosen else slip_from_speed(df["speed_rpm"].to_numpy(), f, p)
        if "voltage" in df.columns:
            volt = df["voltage"].to_numpy()
            bad = volt <= 0
            if bad.any():
                raise DataError(
                    path, "voltage must be positive", column="voltage", row=int(np.argmax(bad)) + 1
                )
        elif v_meta is None:
            raise DataError(path, "no 'voltage' column and no 'voltage' key in meta.yaml", column="voltage")
        else:
            volt = np.full(len(df), v_meta)
        if has["time"]:
            t = df["time"].to_numpy()
            dt = np.diff(t)
            if (dt <= 0).any():
                r = int(np.argmax(dt <= 0)) + 2
                raise DataError(
                    path, f"time must increase: {t[r - 1]!r} follows {t[r - 2]!r}", column="time", row=r
                )
            if parts["time"] and t[0] <= parts["time"][-1][-1]:
                raise DataError(
                    path,
                    "time must continue the previous sweep table's clock (tables are read "
                    f"in name order; {t[0]!r} <= {parts['time'][-1][-1]!r})",
                    column="time",
                    row=1,
                )
            parts["time"].append(t)
        if has["torque"]:
            parts["torque"].append(df["torque"].to_numpy())
        check_sweep_table(path, s if "slip" in chosen else None, df["G"].to_numpy(), df["B"].to_numpy(), rdc)
        parts["slip"].append(s)
        parts["G"].append(df["G"].to_numpy())
        parts["B"].append(df["B"].to_numpy())
        parts["voltage"].append(volt)
        parts["sweep"].append(np.full(len(df), k))
    cat = {k: (np.concatenate(v) if v else None) for k, v in parts.items()}
    if len(cat["slip"]) < 6:
        raise DataError(
            folder,
            f"only {len(cat['slip'])} readings in the sweep tables; at least 6 are needed "
            "to determine the circuit",
        )
    return AdmittanceData(
        frequency=f,
        pole_pairs=p,
        slip=cat["slip"],
        G=cat["G"],
        B=cat["B"],
        voltage=cat["voltage"],
        time=cat["time"],
        torque=cat["torque"],
        sweep=cat["sweep"],
        full_scale_admittance=fs,
        full_scale_torque=fs_t,
        stator_dc_resistance=rdc,
        dc_resistance_time=tdc,
        winding_temperature_before=_optional_float(mpath, meta, "winding_temperature_before"),
        reference_temperature=_optional_float(mpath, meta, "reference_temperature"),
        thermal=thermal,
        supply_off=supply_off,
        source=str(folder),
        description=str(meta.get("description", "")),
        files=[p_.name for p_ in files],
    )


def load_steady_state(folder) -> AdmittanceData:
    """The loader of ``problem=admittance``: a slip sweep (``kind: admittance``, above) or the
    tests of a motor test report (``kind: loadtest``, :mod:`benchmark.problems.admittance.loadtest`),
    by the ``kind`` of ``meta.yaml``."""
    folder = Path(folder)
    meta = read_meta(folder, {"kind": str})
    if meta["kind"] == "loadtest":
        from benchmark.problems.admittance.loadtest import load_loadtest

        return load_loadtest(folder)
    return load_admittance(folder)


def write_admittance(folder, data: AdmittanceData, truth: dict | None = None) -> Path:
    """Write ``data`` as a section-7 folder (one ``sweepNN.csv`` per sweep index) and ``truth.yaml``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob("sweep*.csv"):  # a rewrite must not leave tables of an older, longer run
        old.unlink()
    sweeps = data.sweep if data.sweep is not None else np.zeros(data.n, int)
    one_voltage = bool(np.all(data.voltage == data.voltage[0]))
    for k in np.unique(sweeps):
        m = sweeps == k
        table = {"speed_rpm": np.round(data.speed_rpm[m], 9), "G": data.G[m], "B": data.B[m]}
        if data.torque is not None:
            table["torque"] = data.torque[m]
        if data.time is not None:
            table["time"] = data.time[m]
        if not one_voltage:
            table["voltage"] = data.voltage[m]
        write_table_atomic(folder / f"sweep{int(k) + 1:02d}.csv", table, float_format="%.10g")
    meta: dict = {
        "kind": "admittance",
        "frequency": float(data.frequency),
        "pole_pairs": int(data.pole_pairs),
        "voltage": float(data.voltage[0]),
    }
    if data.description:
        meta["description"] = data.description
    for key in (
        "full_scale_admittance",
        "full_scale_torque",
        "winding_temperature_before",
        "reference_temperature",
    ):
        v = getattr(data, key)
        if v is not None:
            meta[key] = float(v)
    for key in ("stator_dc_resistance", "dc_resistance_time"):
        v = getattr(data, key)
        if v is not None:
            meta[key] = [float(v[0]), float(v[1])]
    if data.supply_off:
        meta["supply_off"] = [[float(a), float(b)] for a, b in data.supply_off]
    if data.thermal is not None:
        meta["thermal"] = {k: float(data.thermal[k]) for k in THERMAL_KEYS}
    write_yaml_atomic(folder / "meta.yaml", meta)
    if truth is not None:
        write_yaml_atomic(folder / "truth.yaml", truth)
    return folder


def read_truth(folder) -> dict | None:
    """``truth.yaml`` of a synthetic data set, or None. For scoring only."""
    import yaml

    path = Path(folder) / "truth.yaml"
    if not path.is_file():
        return None
    try:
        t = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        raise DataError(path, f"not valid YAML: {exc}") from None
    if not isinstance(t, dict):
        raise DataError(path, "must be a mapping")
    return t
