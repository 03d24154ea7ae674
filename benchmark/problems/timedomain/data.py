"""Time-domain data sets (``kind: startup``, docs/data_format.md): load, validate, write.

A folder holds ``meta.yaml``, one or more ``startup*.csv`` and optionally ``stop*.csv``.
Start-up columns: ``t``; voltages ``v_alpha, v_beta``, phase ``v_r, v_s, v_t`` or line-to-line
``v_rs, v_st`` (a three-wire supply's two line voltages, ``v_R - v_S`` and ``v_S - v_T``); currents
``i_alpha, i_beta`` or phase ``i_r, i_s`` (the third from a zero sum); ``speed``, mechanical
rad/s. Phase quantities are turned into alpha-beta with the amplitude-invariant Clarke
transform (:func:`benchmark.problems.timedomain.frames.clarke`). Stop columns: ``t``, ``speed``.

Each record may instead be a MATLAB file, ``startup*.mat`` / ``stop*.mat`` (versions 4 to 7),
holding vectors named like the columns (:func:`benchmark.core.matfiles.read_mat_table`); a record
name given both as ``.csv`` and ``.mat`` is refused. ``speed_unit`` in ``meta.yaml`` (``rad/s``,
the default, or ``rpm``) says how the speed columns are written; rpm is converted on load
(``rad/s = rpm * pi / 30``), so a data set always holds rad/s.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmark.core.errors import DataError, DataWarning
from benchmark.core.io import write_table_atomic, write_yaml_atomic
from benchmark.core.matfiles import read_mat_table
from benchmark.core.meta_file import check_meta_type, parse_nameplate, read_meta
from benchmark.core.spelling import found_instead
from benchmark.core.tables import _short_repr, check_time_column, read_table
from benchmark.problems.timedomain.channel_timing import (
    CURRENT_CHANNELS,
    check_mapping_columns,
    parse_channel_skew,
    realign,
)
from benchmark.problems.timedomain.decimation import skew_decimated, startups_read, stop_read
from benchmark.problems.timedomain.frames import clarke, inverse_clarke, line_to_line_clarke
from benchmark.problems.timedomain.load_checks import check_records, check_speed_plausibility
from benchmark.problems.timedomain.rotation import turn_forwards
from benchmark.problems.timedomain.speed_filter import parse_speed_filter
from benchmark.problems.timedomain.stator_prior import WINDING_TEMPERATURE_RANGE_C

VOLTAGE_COLUMNS = (("v_alpha", "v_beta"), ("v_r", "v_s", "v_t"), ("v_rs", "v_st"))
CURRENT_COLUMNS = (("i_alpha", "i_beta"), ("i_r", "i_s"))

#: A mechanical speed above this (rad/s, about 15 000 rpm) is implausible for a motor in
#: this benchmark; a column that exceeds it is probably in rpm.
PLAUSIBLE_SPEED_LIMIT = 1600.0
#: Keys meta.yaml may hold for a time-domain data set; others are reported and ignored.
META_KEYS = ("kind", "pole_pairs", "sample_time", "input_hold", "dc_link_voltage", "supply_frequency",
             "inertia", "speed_unit", "description", "stator_dc_resistance", "winding_temperature", "nameplate",
             "conditioning", "chord_voltage", "channel_skew", "speed_filter", "decimate")
#: Optional start-up columns: ``speed`` (a record without a speed sensor has none) and ``torque``
#: (N m, a measured shaft torque).
OPTIONAL_COLUMNS = ("speed", "torque")
#: Units the speed columns may be written in (``speed_unit`` in meta.yaml; rad/s by default).
SPEED_UNITS = ("rad/s", "rpm")
#: File types a record may be stored in, read by these table readers.
RECORD_READERS = {".csv": read_table, ".mat": read_mat_table}
MAX_POLE_PAIRS = 100


@dataclass
class StartupRecord:
    """One start-up record, alpha-beta (amplitude-invariant), SI units.

    Attributes: t (s), v_alpha, v_beta (V), i_alpha, i_beta (A), speed (mechanical rad/s; all
    NaN when the record has no speed sensor), torque (N m, measured shaft torque, or None),
    weight (False where a current sample is masked by the conditioning, e.g. clipped; None: all
    samples count), switch_on_sample (the sample just after a measured switch-on's switching
    steps, whose volt-seconds the conditioning corrected from the current's response: what is
    left of their error is estimated with the parameters as a stator flux step there; None: no
    such switch-on), columns (the file's column names of ``voltage`` and ``current``, for
    messages; None for a record made in memory), removed (what the conditioning removed, to
    put back: ``{"sensor_offset": (v_alpha, v_beta, i_alpha, i_beta) offsets, "current_sensor_saturation":
    mask of the samples masked as flattened, "sensor_offset_at_rest": {phase channel: its
    pre-trigger samples} where the offsets were their means, "sensor_offset_measured": the steady
    tail's offsets, removed or not}``; the diagnosis checks each removal by its rule).
    """

    t: np.ndarray
    v_alpha: np.ndarray
    v_beta: np.ndarray
    i_alpha: np.ndarray
    i_beta: np.ndarray
    speed: np.ndarray
    source: str = "memory"
    torque: np.ndarray | None = None
    weight: np.ndarray | None = None
    switch_on_sample: int | None = None
    columns: dict | None = None  # the file's columns of each quantity ("voltage": "v_r, v_s, v_t"), for messages
    removed: dict | None = None

    @property
    def has_speed(self) -> bool:
        """True when the record has a speed channel."""
        return bool(np.any(np.isfinite(self.speed)))


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
    chord_voltage : True when a ``linear`` input is exactly the straight line between its samples
        (data made by a simulator that interpolates its sampled input linearly, as this project's
        generator does, or samples the conditioning has already restored); False (the default)
        for a continuous voltage, whose volt-seconds the conditioning restores
        (:func:`benchmark.problems.timedomain.switch_on.sampled_volt_seconds`).
    dc_link_voltage, supply_frequency, inertia : V, Hz, kg m^2, or None when not given.
    stator_dc_resistance : ohm per phase measured with DC (prior knowledge), or None.
    winding_temperature : deg C of the winding when the DC resistance was measured, or None.
    nameplate : {rated_power (W), voltage (V line-line rms), current (A rms), speed (rpm),
        frequency (Hz)}, any subset, or None.
    channel_skew : the acquisition's documented skew of the current channels behind the voltage
        channels, samples (a number, or a (low, high) range), or a multiplexed card's sequence
        (a mapping of phase channels to samples, :mod:`~benchmark.problems.timedomain.channel_timing`;
        its voltage skews are undone on reading), or None (channels sampled at once, or not
        stated): ``channel_delay`` is a candidate only where it is stated.
    speed_filter : the time constant of the speed channel's filter, s (a tachogenerator's RC
        filter; half an encoder's gate time, over which it averages), as the instrument's data
        sheet or the drive's setting gives it, or None (not stated: the speed is read
        unfiltered). The diagnosis's models read their speed through it
        (:mod:`~benchmark.problems.timedomain.speed_filter`).
    conditioning : what the conditioning on load did (plain-English lines for report.md).
    conditioning_removed : the effects it found and removed (``sensor_offset``,
        ``current_sensor_saturation``): the diagnosis checks each by its rule and lists those kept.
    """

    pole_pairs: int
    sample_time: float
    startups: list[StartupRecord]
    stops: list[StopRecord] = field(default_factory=list)
    input_hold: str = "linear"
    chord_voltage: bool = False
    dc_link_voltage: float | None = None
    supply_frequency: float | None = None
    inertia: float | None = None
    folder: str | None = None
    stator_dc_resistance: float | None = None
    winding_temperature: float | None = None
    nameplate: dict | None = None
    channel_skew: float | tuple[float, float] | dict[str, float] | None = None
    speed_filter: float | None = None
    conditioning: list[str] = field(default_factory=list)
    conditioning_removed: list[str] = field(default_factory=list)

    @property
    def has_speed(self) -> bool:
        """True when every start-up record has a speed channel."""
        return all(r.has_speed for r in self.startups)

    def facts(self) -> dict:
        """What the experiment is, for screening candidate effects: ``dc_link_voltage``,
        ``input_hold``, ``supply_frequency``, ``has_speed``, ``has_stop``, ``channel_skew``,
        ``speed_filter``, ``nameplate``."""
        return {"dc_link_voltage": self.dc_link_voltage, "input_hold": self.input_hold,
                "supply_frequency": self.supply_frequency, "has_speed": self.has_speed,
                "has_stop": bool(self.stops), "channel_skew": self.channel_skew, "speed_filter": self.speed_filter,
                "nameplate": self.nameplate}

    def meta(self) -> dict:
        m = {
            "kind": "startup",
            "pole_pairs": int(self.pole_pairs),
            "sample_time": float(self.sample_time),
            "input_hold": self.input_hold,
        }
        if self.chord_voltage:
            m["chord_voltage"] = True
        for key in ("dc_link_voltage", "supply_frequency", "inertia", "stator_dc_resistance",
                    "winding_temperature", "speed_filter"):
            if getattr(self, key) is not None:
                m[key] = float(getattr(self, key))
        if self.nameplate:
            m["nameplate"] = {k: float(v) for k, v in self.nameplate.items()}
        skew = self.channel_skew
        if isinstance(skew, dict):  # the voltages were realigned on reading: the currents' skews are left
            m["channel_skew"] = {k: float(v) for k, v in skew.items() if k in CURRENT_CHANNELS}
        elif skew is not None:
            m["channel_skew"] = [float(v) for v in skew] if np.ndim(skew) else float(skew)
        return m


def load_startup_dataset(folder, *, max_bytes: int | None = None) -> StartupDataset:
    """Read and validate a ``kind: startup`` folder. Raises DataError naming file/column/row;
    data that load but look wrong (a speed that may be in rpm, unknown ``meta.yaml`` keys,
    unused columns) raise a :class:`benchmark.core.errors.DataWarning`. ``max_bytes`` overrides the
    table size limit (:func:`benchmark.core.tables.max_table_bytes`)."""
    folder = Path(folder)
    meta = read_meta(folder, {"pole_pairs": int, "sample_time": float})
    meta_path = folder / "meta.yaml"
    kind = meta.get("kind", "startup")
    if kind != "startup":
        raise DataError(meta_path, f"kind is {kind!r}; this problem reads 'startup' data sets")
    unknown = [str(k) for k in meta if k not in META_KEYS]
    if unknown:
        hints = "".join(found_instead(k, META_KEYS) for k in unknown)
        warnings.warn(DataWarning.at(meta_path, f"unknown key(s) {unknown} ignored{hints}; known keys: "
                                                f"{list(META_KEYS)}"), stacklevel=2)
    p = meta["pole_pairs"]
    if not 1 <= p <= MAX_POLE_PAIRS:
        raise DataError(meta_path, f"key 'pole_pairs' must be between 1 and {MAX_POLE_PAIRS}, got {p}")
    ts = float(meta["sample_time"])
    if not ts > 0:
        raise DataError(meta_path, f"key 'sample_time' must be > 0 s, got {ts}")
    hold = meta.get("input_hold", "linear")
    if not isinstance(hold, str) or hold not in ("zoh", "linear"):
        raise DataError(meta_path, f"key 'input_hold' must be 'zoh' or 'linear', got {_short_repr(hold)}")
    unit = _speed_unit(meta_path, meta.get("speed_unit", "rad/s"))
    optional = {}
    for key in ("dc_link_voltage", "supply_frequency", "inertia", "stator_dc_resistance"):
        if meta.get(key) is not None:
            meta[key] = check_meta_type(meta_path, key, meta[key], float)
            if not meta[key] > 0:
                raise DataError(meta_path, f"key '{key}' must be > 0, got {meta[key]}")
            optional[key] = float(meta[key])
    if meta.get("winding_temperature") is not None:
        theta = check_meta_type(meta_path, "winding_temperature", meta["winding_temperature"], float)
        lo, hi = WINDING_TEMPERATURE_RANGE_C
        if not lo <= theta <= hi:
            raise DataError(meta_path, f"key 'winding_temperature' must be in deg C ({lo:g} to {hi:g}), got {theta}")
        optional["winding_temperature"] = float(theta)
    if meta.get("nameplate") is not None:
        optional["nameplate"] = parse_nameplate(meta_path, meta["nameplate"])
    if meta.get("channel_skew") is not None:
        optional["channel_skew"] = parse_channel_skew(meta_path, meta["channel_skew"])
    if meta.get("speed_filter") is not None:
        optional["speed_filter"] = parse_speed_filter(meta_path, meta["speed_filter"])
    chord = meta.get("chord_voltage", False)
    if not isinstance(chord, bool):
        raise DataError(meta_path, f"key 'chord_voltage' must be true or false, got {_short_repr(chord)}")
    conditioning_on = meta.get("conditioning", True)
    if not isinstance(conditioning_on, bool):
        raise DataError(meta_path, f"key 'conditioning' must be true or false, got {_short_repr(conditioning_on)}")

    startup_files = _record_files(folder, "startup")
    if not startup_files:
        raise DataError(folder, "no startup*.csv (or startup*.mat) file: a time-domain data set needs at least "
                                "one start-up record")
    skew = optional.get("channel_skew")
    startups = [_read_startup(f, ts, max_bytes, speed_unit=unit, skew=skew) for f in startup_files]
    for rec in startups:
        check_mapping_columns(meta_path, skew, rec.columns)
    stops, notes = [], []
    for f in _record_files(folder, "stop"):
        stop, note = stop_read(*_read_stop(f, max_bytes, speed_unit=unit))
        stops.append(stop)
        notes += [note] if note else []
    check_speed_plausibility(meta_path, startups, stops, p, optional.get("supply_frequency"), speed_unit=unit)
    check_records(startups, optional.get("nameplate"), p, hold, meta_path, optional.get("supply_frequency"),
                  optional.get("stator_dc_resistance"))
    startups, stops, turned = turn_forwards(startups, stops, skew, meta_path)
    notes = ([turned] if turned else []) + notes
    startups, k, lines = startups_read(meta_path, meta.get("decimate", 1), startups, ts, hold,
                                       optional.get("supply_frequency"))
    if k > 1:
        ts, chord, notes = ts * k, False, notes + lines
        if skew is not None:
            optional["channel_skew"] = skew_decimated(skew, k)
    ds = StartupDataset(
        pole_pairs=p,
        sample_time=ts,
        startups=startups,
        stops=stops,
        input_hold=hold,
        chord_voltage=chord,
        folder=str(folder),
        conditioning=notes,
        **optional,
    )
    if conditioning_on:
        from benchmark.problems.timedomain.conditioning import condition_dataset

        ds = condition_dataset(ds)
    return ds


def _record_files(folder: Path, prefix: str) -> list[Path]:
    """``prefix*.csv`` and ``prefix*.mat`` in name order (also folders and broken links with
    such names, which the table reader then reports). The same record name as both CSV and
    MAT (``startup.csv`` and ``startup.mat``) is a DataError: it would be read twice."""
    files = sorted(f for ext in RECORD_READERS for f in folder.glob(f"{prefix}*{ext}"))
    seen: dict[str, Path] = {}
    for f in files:
        if f.stem in seen:
            raise DataError(folder, f"{seen[f.stem].name} and {f.name} hold the same record: keep one of them "
                                    "(each file is one record)")
        seen[f.stem] = f
    return files


def rpm_to_rad_per_s(speed) -> np.ndarray:
    """Mechanical speed in rpm -> rad/s: ``rpm * pi / 30``."""
    return np.asarray(speed, float) * np.pi / 30


def _speed_unit(meta_path: Path, value) -> str:
    """``speed_unit`` of meta.yaml: ``rad/s`` or ``rpm`` (any case), else a DataError."""
    unit = value.strip().lower() if isinstance(value, str) else None
    if unit not in SPEED_UNITS:
        hint = found_instead(str(value), SPEED_UNITS) if isinstance(value, str) else ""
        raise DataError(meta_path, f"key 'speed_unit' must be one of {list(SPEED_UNITS)}, got "
                                   f"{_short_repr(value)}{hint}")
    return unit


def _read_records_table(path: Path, alternatives, max_bytes: int | None, optional=()):
    reader = RECORD_READERS.get(path.suffix.lower(), read_table)
    return reader(path, alternatives, optional, max_bytes=max_bytes, warn_unused=True)


def _read_startup(path: Path, sample_time: float, max_bytes: int | None = None, *,
                  speed_unit: str = "rad/s", skew=None) -> StartupRecord:
    alternatives = [("t", *v, *i) for v in VOLTAGE_COLUMNS for i in CURRENT_COLUMNS]
    df, cols = _read_records_table(path, alternatives, max_bytes, optional=OPTIONAL_COLUMNS)
    t = df["t"].to_numpy()
    step = check_time_column(path, t)
    if abs(step - sample_time) > 1e-3 * sample_time:
        ratio = step / sample_time
        hint = ""
        for factor, unit in ((1e3, "ms"), (1e6, "us")):
            if abs(ratio / factor - 1) < 0.01:
                hint = f" (is t in {unit}? t must be in seconds)"
        raise DataError(
            path, f"time step {step:.6g} s differs from meta.yaml sample_time {sample_time:.6g} s{hint}",
            column="t"
        )
    with np.errstate(all="ignore"):
        if "v_alpha" in cols:
            v_a, v_b = df["v_alpha"].to_numpy(), df["v_beta"].to_numpy()
        elif "v_rs" in cols:  # two line-to-line voltages (a three-wire supply)
            v_a, v_b = line_to_line_clarke(df["v_rs"].to_numpy(), df["v_st"].to_numpy())
        else:
            v3 = realign(df[["v_r", "v_s", "v_t"]].to_numpy(float), skew)  # a stated sequence's voltage skews
            v_a, v_b = clarke(v3[:, 0], v3[:, 1], v3[:, 2])
        if "i_alpha" in cols:
            i_a, i_b = df["i_alpha"].to_numpy(), df["i_beta"].to_numpy()
        else:
            i_r, i_s = df["i_r"].to_numpy(), df["i_s"].to_numpy()
            i_a, i_b = clarke(i_r, i_s, -i_r - i_s)
    vcols = next(", ".join(c) for c in VOLTAGE_COLUMNS if c[0] in cols)
    for name, x, source in (("v_alpha", v_a, vcols), ("v_beta", v_b, vcols),
                             ("i_alpha", i_a, "i_r, i_s"), ("i_beta", i_b, "i_r, i_s")):
        if not np.all(np.isfinite(x)):
            k = int(np.argmax(~np.isfinite(x)))
            raise DataError(path, f"phase values too large: {name} computed from columns {source} overflows "
                                  "in the Clarke transform", row=k + 1)
    if "speed" in df:
        speed = _speed_in_rad_per_s(path, df["speed"].to_numpy(), speed_unit)
    else:
        speed = np.full(len(t), np.nan)
        warnings.warn(DataWarning.at(path, "no speed column: a record without a speed sensor (the speed is "
                                           "simulated, not fitted; J then comes from the currents alone)"),
                      stacklevel=3)
    torque = df["torque"].to_numpy() if "torque" in df else None
    columns = {"voltage": vcols,
               "current": "i_alpha, i_beta" if "i_alpha" in cols else "i_r, i_s"}
    return StartupRecord(t=t - t[0], v_alpha=v_a, v_beta=v_b, i_alpha=i_a, i_beta=i_b, speed=speed,
                         source=str(path), torque=torque, columns=columns)


def _read_stop(path: Path, max_bytes: int | None = None, *, speed_unit: str = "rad/s") -> tuple[StopRecord, float]:
    """The stop record of ``path`` and its time step (s)."""
    df, _ = _read_records_table(path, [("t", "speed")], max_bytes)
    t = df["t"].to_numpy()
    step = check_time_column(path, t)
    speed = _speed_in_rad_per_s(path, df["speed"].to_numpy(), speed_unit)
    return StopRecord(t=t - t[0], speed=speed, source=str(path)), step


def _speed_in_rad_per_s(path: Path, speed: np.ndarray, unit: str) -> np.ndarray:
    if unit == "rpm":
        speed = rpm_to_rad_per_s(speed)
    _check_speed(path, speed, unit)
    return speed


def _check_speed(path: Path, speed: np.ndarray, unit: str = "rad/s") -> None:
    """Hard limit: beyond :data:`PLAUSIBLE_SPEED_LIMIT` no motor of this benchmark turns."""
    k = int(np.argmax(np.abs(speed)))
    if abs(speed[k]) > PLAUSIBLE_SPEED_LIMIT:
        if unit == "rpm":
            msg = (f"speed {speed[k] * 30 / np.pi:.6g} rpm ({speed[k]:.6g} rad/s) is implausible (above "
                   f"{PLAUSIBLE_SPEED_LIMIT * 30 / np.pi:.0f} rpm; meta.yaml declares speed_unit: rpm)")
        else:
            msg = (f"speed {speed[k]:.6g} is implausible in rad/s (above {PLAUSIBLE_SPEED_LIMIT:.0f} rad/s, "
                   f"{PLAUSIBLE_SPEED_LIMIT * 30 / np.pi:.0f} rpm; is the column in rpm? rad/s = rpm * pi / 30, "
                   "or declare speed_unit: rpm in meta.yaml)")
        raise DataError(path, msg, column="speed", row=k + 1)


def write_startup_dataset(folder, ds: StartupDataset, truth: dict | None = None) -> Path:
    """Write a data set in the section 7 format (alpha-beta columns; phase currents where a card's
    sequence gives them their own skews); ``truth`` -> truth.yaml."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for k, r in enumerate(ds.startups):
        name = "startup.csv" if len(ds.startups) == 1 else f"startup_{k + 1}.csv"
        table = {"t": r.t, "v_alpha": r.v_alpha, "v_beta": r.v_beta, "i_alpha": r.i_alpha, "i_beta": r.i_beta}
        if isinstance(ds.channel_skew, dict):
            i_r, i_s, _ = inverse_clarke(r.i_alpha, r.i_beta)
            table = {"t": r.t, "v_alpha": r.v_alpha, "v_beta": r.v_beta, "i_r": i_r, "i_s": i_s}
        if r.has_speed:
            table["speed"] = r.speed
        if r.torque is not None:
            table["torque"] = r.torque
        write_table_atomic(folder / name, table, float_format="%.17g")
    for k, r in enumerate(ds.stops):
        name = "stop.csv" if len(ds.stops) == 1 else f"stop_{k + 1}.csv"
        write_table_atomic(folder / name, {"t": r.t, "speed": r.speed}, float_format="%.17g")
    write_yaml_atomic(folder / "meta.yaml", ds.meta())
    if truth is not None:
        write_yaml_atomic(folder / "truth.yaml", truth)
    return folder
