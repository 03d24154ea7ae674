"""The tests engineers run, as data (``kind: loadtest``): load points, a no-load test at several
voltages, a locked-rotor test and the DC stator resistance, read from a folder and converted to
the per-phase admittance readings the steady-state problem fits (``docs/steady_state.md`` is
the format's reference; every conversion and assumption is listed in ``AdmittanceData.notes``).

Folder
------
``meta.yaml``: ``kind: loadtest``, ``frequency`` (Hz, rated), ``pole_pairs``, ``connection``
(``star`` or ``delta``: how the winding is connected in the tests); optional ``voltage`` (V
line-to-line, for tables without a voltage column), ``stator_dc_resistance`` (``{value: ohm,
temperature: deg C, between: terminals | phase}``; ``terminals`` is the default: line-to-line,
as measured), ``reference_temperature`` (deg C the fitted resistances are referred to),
``friction_windage`` (W at no-load speed, when known), ``instrument_accuracy`` (relative
standard error of the voltage, current and power readings, default 0.002: class 0.2 instruments),
``power_factor_resolution`` (the last digit of a power-factor column, default 0.001),
``speed_resolution`` (rpm, the last digit of the speed column, default 1),
``description``, ``source``.

``load.csv`` (load points), ``noload.csv`` (no-load test, any number of voltages), ``locked.csv``
(locked-rotor test), at least one of them. Columns (SI units, three-phase totals for power):
``line_voltage`` or ``phase_voltage`` (V RMS; or the meta ``voltage``), ``line_current`` or
``phase_current`` (A RMS), ``power`` (W input) and/or ``power_factor``; ``load.csv`` also
``speed_rpm``; optional everywhere ``temperature`` (deg C, winding), ``frequency`` (Hz, default
the rated one: a locked-rotor test at reduced frequency), and in ``load.csv`` ``torque`` (N m),
``shaft_power`` (W), ``efficiency`` (per unit), kept for reports.

Conversion (per phase of the winding as connected): star ``V_ph = V_line/sqrt(3)``, ``I_ph =
I_line``; delta ``V_ph = V_line``, ``I_ph = I_line/sqrt(3)``; ``Y = (P - jQ)/(3 V_ph^2)`` with
``Q = sqrt((3 V_ph I_ph)^2 - P^2)`` (lagging: a motor draws reactive power); ``P`` is the power
column when given (a wattmeter has more digits than a rounded power factor), else ``3 V_ph I_ph
pf``. Load points: slip from speed and the reading's frequency. No-load readings: slip 0, the
friction and windage loss taken out of the input power (:mod:`benchmark.problems.admittance.noload`).
Locked rotor: slip 1 at frequency ratio ``f/f_rated``. DC resistance between terminals: star
``R_ph = R/2``, delta ``R_ph = 3R/2``.

Standard errors of each reading's G and B (the misfit unit, ``normalisation: instrument``),
first-order from the instruments: ``|Y| = I/V`` with relative error ``sqrt(2) a``; the power
factor with ``sqrt(3) a pf`` from a power reading, or the rounding of a power-factor column
(``resolution/sqrt(12)``) with ``a pf``; then ``G = |Y| pf``, ``B = -|Y| sqrt(1 - pf^2)``. A
no-load reading's G (a small power factor) is thereby known far better than |Y| in absolute
terms, and it is what fixes the core loss. To these add, in quadrature, the slip's error on a load
point (the speed's rounding, ``resolution/sqrt(12)``, times ``dY/ds`` between neighbouring load
points: at light load it dominates) and the friction and windage loss's on a no-load reading.
"""

from __future__ import annotations

import itertools
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmark.core.errors import DataError, DataWarning
from benchmark.core.io import write_table_atomic, write_yaml_atomic
from benchmark.core.meta_file import read_meta
from benchmark.core.tables import read_table
from benchmark.problems.admittance.circuit import copper_factor
from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.noload import FrictionWindage, friction_windage

__all__ = ["TestTable", "LoadTest", "read_loadtest", "load_loadtest", "write_loadtest", "TEST_FILES"]

#: The tables of a load-test folder and the column each needs beyond voltage, current and power.
TEST_FILES = {"load": "load.csv", "noload": "noload.csv", "locked": "locked.csv"}
OPTIONAL = {
    "load": ("temperature", "frequency", "torque", "shaft_power", "efficiency"),
    "noload": ("temperature", "frequency", "speed_rpm"),
    "locked": ("temperature", "frequency", "torque"),
}
META_KEYS = {"kind", "frequency", "pole_pairs", "connection", "voltage", "stator_dc_resistance",
             "reference_temperature", "friction_windage", "instrument_accuracy", "power_factor_resolution",
             "speed_resolution", "description", "source", "nameplate"}
#: Largest |pf(power) - pf(column)| accepted silently when both are given.
PF_TOLERANCE = 0.01
SQ3 = float(np.sqrt(3.0))


@dataclass
class TestTable:
    """One test converted to per phase of the winding as connected.

    Attributes
    ----------
    name : ``load``, ``noload`` or ``locked``.  file : its file name.  V, I : phase voltage and
    current, V and A RMS.  P, Q : three-phase input power (W) and reactive power (var).
    frequency : Hz per reading.  speed_rpm, temperature : per reading or None.  extra : other
    columns kept for reports (torque, shaft_power, efficiency).
    """

    name: str
    file: str
    V: np.ndarray
    I: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    frequency: np.ndarray
    speed_rpm: np.ndarray | None = None
    temperature: np.ndarray | None = None
    extra: dict = field(default_factory=dict)
    sigma_pf: np.ndarray | None = None

    @property
    def Y(self) -> np.ndarray:
        """Per-phase input admittance, S (B < 0: lagging)."""
        return (self.P - 1j * self.Q) / (3.0 * self.V**2)

    def standard_errors(self, accuracy: float) -> tuple[np.ndarray, np.ndarray]:
        """``(sigma_G, sigma_B)``, S, of each reading (module docstring)."""
        Ymag = self.I / self.V
        pf = self.P / (3.0 * self.V * self.I)
        sin = np.sqrt(np.maximum(1.0 - pf**2, 1e-6))
        s_Y = np.sqrt(2.0) * accuracy * Ymag
        s_pf = self.sigma_pf
        return np.hypot(pf * s_Y, Ymag * s_pf), np.hypot(sin * s_Y, Ymag * pf / sin * s_pf)


@dataclass
class LoadTest:
    """The tests of a folder. ``R1_dc``: stator DC resistance per phase (ohm) at ``theta_dc``
    (deg C), or None. ``theta_ref``: deg C the resistances are referred to. ``friction``: the
    friction and windage loss, or None."""

    frequency: float
    pole_pairs: int
    connection: str
    tables: dict[str, TestTable]
    R1_dc: float | None
    theta_dc: float | None
    theta_ref: float | None
    friction: FrictionWindage | None
    source: str
    description: str = ""
    notes: list[str] = field(default_factory=list)
    accuracy: float = 0.002
    speed_resolution: float = 1.0

    def R1_at(self, theta) -> np.ndarray | float | None:
        """The stator resistance per phase at winding temperature ``theta`` (deg C), from the DC value."""
        if self.R1_dc is None:
            return None
        if theta is None or self.theta_dc is None:
            return self.R1_dc
        return self.R1_dc * copper_factor(theta, self.theta_dc)


def _meta(folder: Path) -> dict:
    meta = read_meta(folder, {"kind": str, "frequency": float, "pole_pairs": int, "connection": str})
    path = folder / "meta.yaml"
    if meta["connection"] not in ("star", "delta"):
        raise DataError(path, f"key 'connection' must be star or delta, got {meta['connection']!r}")
    if not meta["frequency"] > 0 or meta["pole_pairs"] < 1:
        raise DataError(path, "keys 'frequency' (Hz) and 'pole_pairs' must be positive")
    unknown = sorted(str(k) for k in meta if k not in META_KEYS)
    if unknown:
        warnings.warn(DataWarning.at(path, f"key(s) {unknown} not used; known: {sorted(META_KEYS)}"), stacklevel=3)
    for key in ("voltage", "reference_temperature", "friction_windage", "instrument_accuracy",
                "power_factor_resolution", "speed_resolution"):
        v = meta.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v)):
            raise DataError(path, f"key '{key}' must be a number, got {v!r}")
    for key in ("voltage", "instrument_accuracy", "power_factor_resolution", "speed_resolution"):
        if meta.get(key) is not None and not meta[key] > 0:
            raise DataError(path, f"key '{key}' must be positive, got {meta[key]}")
    return meta


def _dc_resistance(path: Path, meta: dict, connection: str) -> tuple[float | None, float | None, str | None]:
    d = meta.get("stator_dc_resistance")
    if d is None:
        return None, None, None
    if not isinstance(d, dict) or "value" not in d or "temperature" not in d:
        raise DataError(path, "key 'stator_dc_resistance' must be a mapping {value: ohm, temperature: deg C, "
                              f"between: terminals | phase}}, got {d!r}")
    try:
        R, theta = float(d["value"]), float(d["temperature"])
    except (TypeError, ValueError):
        raise DataError(path, f"key 'stator_dc_resistance': value and temperature must be numbers, got {d!r}") from None
    between = d.get("between", "terminals")
    if not (R > 0 and np.isfinite(R) and np.isfinite(theta)) or between not in ("terminals", "phase"):
        raise DataError(path, f"key 'stator_dc_resistance': a positive value and between: terminals | phase, got {d!r}")
    if between == "phase":
        return R, theta, f"DC stator resistance {R:.5g} ohm per phase at {theta:g} C"
    R_ph = R / 2.0 if connection == "star" else 1.5 * R
    return R_ph, theta, (f"DC stator resistance {R:.5g} ohm between terminals at {theta:g} C -> {R_ph:.5g} ohm per "
                         f"phase ({connection}: {'R/2' if connection == 'star' else '3R/2'})")


def _alternatives(name: str, meta_voltage: bool) -> list[tuple[str, ...]]:
    volts = [("line_voltage",), ("phase_voltage",)] + ([()] if meta_voltage else [])
    amps = [("line_current",), ("phase_current",)]
    watts = [("power", "power_factor"), ("power",), ("power_factor",)]
    speed = ("speed_rpm",) if name == "load" else ()
    return [v + a + w + speed for v, a, w in itertools.product(volts, amps, watts)]


def _positive(path, df, col):
    bad = ~(df[col].to_numpy() > 0)
    if bad.any():
        raise DataError(path, f"{col} must be positive, got {df[col].iloc[int(np.argmax(bad))]!r}",
                        column=col, row=int(np.argmax(bad)) + 1)


def _read_test(folder: Path, name: str, meta: dict, notes: list[str]) -> TestTable | None:
    path = folder / TEST_FILES[name]
    if not path.is_file():
        return None
    df, chosen = read_table(path, _alternatives(name, meta.get("voltage") is not None), optional=OPTIONAL[name])
    n, delta = len(df), meta["connection"] == "delta"
    if "line_voltage" in df:
        _positive(path, df, "line_voltage")
        V = df["line_voltage"].to_numpy() / (1.0 if delta else SQ3)
    elif "phase_voltage" in df:
        _positive(path, df, "phase_voltage")
        V = df["phase_voltage"].to_numpy()
    else:
        V = np.full(n, float(meta["voltage"]) / (1.0 if delta else SQ3))
    cur = "line_current" if "line_current" in df else "phase_current"
    _positive(path, df, cur)
    I = df[cur].to_numpy() / (SQ3 if cur == "line_current" and delta else 1.0)
    S = 3.0 * V * I
    if "power_factor" in df:
        pf = df["power_factor"].to_numpy()
        bad = ~((pf >= 0) & (pf <= 1))
        if bad.any():
            k = int(np.argmax(bad))
            raise DataError(path, f"power_factor must be within [0, 1], got {pf[k]!r}", column="power_factor",
                            row=k + 1)
    if "power" in df:
        P = df["power"].to_numpy()
        over = np.abs(P) > 1.005 * S
        if over.any():
            k = int(np.argmax(over))
            raise DataError(path, f"power {P[k]:g} W exceeds the apparent power {S[k]:.6g} VA of the voltage and "
                                  "current (power factor > 1): a single-phase reading, or a star/delta mix-up?",
                            column="power", row=k + 1)
        if "power_factor" in df:
            gap = np.abs(P / S - pf)
            if gap.max() > PF_TOLERANCE:
                k = int(np.argmax(gap))
                warnings.warn(DataWarning.at(path, f"power_factor {pf[k]:g} disagrees with power/(sqrt(3) V I) = "
                                                   f"{P[k] / S[k]:.4f}; the power column is used",
                                             column="power_factor", row=k + 1), stacklevel=3)
    else:
        P = S * pf
    a = float(meta.get("instrument_accuracy", 0.002))
    if "power" in df:
        sigma_pf = np.sqrt(3.0) * a * np.abs(P / S)
    else:
        sigma_pf = np.hypot(float(meta.get("power_factor_resolution", 0.001)) / np.sqrt(12.0), a * pf)
    Q = np.sqrt(np.maximum(S**2 - P**2, 0.0))
    if "frequency" in df:
        _positive(path, df, "frequency")
        f = df["frequency"].to_numpy()
    else:
        f = np.full(n, float(meta["frequency"]))
    temp = None
    if "temperature" in df:
        temp = df["temperature"].to_numpy()
        bad = ~((temp > -60) & (temp < 260))
        if bad.any():
            k = int(np.argmax(bad))
            raise DataError(path, f"temperature {temp[k]!r} deg C is not a winding temperature",
                            column="temperature", row=k + 1)
    speed = df["speed_rpm"].to_numpy() if "speed_rpm" in df else None
    if speed is not None and (speed < 0).any():
        k = int(np.argmax(speed < 0))
        raise DataError(path, f"speed_rpm must be >= 0, got {speed[k]!r}", column="speed_rpm", row=k + 1)
    extra = {c: df[c].to_numpy() for c in ("torque", "shaft_power", "efficiency") if c in df}
    volt = "phase" if "phase_voltage" in df else "line"
    watts = "power" if "power" in df else "power factor"
    notes.append(f"{path.name}: {n} reading(s); {volt} voltage, {cur.replace('_', ' ')}, {watts} -> per-phase "
                 f"G, B ({meta['connection']})")
    return TestTable(name, path.name, V, I, P, Q, f, speed, temp, extra, sigma_pf)


def read_loadtest(folder) -> LoadTest:
    """Read and validate a ``kind: loadtest`` folder; errors name the file, key, column and row."""
    folder = Path(folder)
    meta = _meta(folder)
    mpath = folder / "meta.yaml"
    if meta["kind"] != "loadtest":
        raise DataError(mpath, f"key 'kind' is {meta['kind']!r}; this loader reads kind 'loadtest'")
    notes: list[str] = []
    tables = {name: t for name in TEST_FILES if (t := _read_test(folder, name, meta, notes)) is not None}
    if not tables:
        raise DataError(folder, f"no test table: give at least one of {list(TEST_FILES.values())}")
    R1_dc, theta_dc, note = _dc_resistance(mpath, meta, meta["connection"])
    if note:
        notes.append(note)
    temps = [t.temperature for t in tables.values()]
    theta_ref = meta.get("reference_temperature")
    if theta_ref is None and all(t is not None for t in temps):
        main = tables.get("load") or next(iter(tables.values()))
        theta_ref = float(np.round(np.median(main.temperature), 1))
        notes.append(f"resistances referred to {theta_ref:g} C (the median temperature of {main.file})")
    lt = LoadTest(float(meta["frequency"]), int(meta["pole_pairs"]), meta["connection"], tables, R1_dc, theta_dc,
                  None if theta_ref is None else float(theta_ref), None, str(folder),
                  str(meta.get("description", "")), notes, float(meta.get("instrument_accuracy", 0.002)),
                  float(meta.get("speed_resolution", 1.0)))
    lt.friction = _friction(lt, meta.get("friction_windage"))
    return lt


def _friction(lt: LoadTest, given) -> FrictionWindage | None:
    if given is not None:
        return FrictionWindage(float(given), "given in meta.yaml (friction_windage)", 0.02 * float(given))
    nl = lt.tables.get("noload")
    if nl is None:
        return None
    R1 = lt.R1_at(nl.temperature)
    fw = friction_windage(nl.V, nl.I, nl.P, 0.0 if R1 is None else R1)
    if fw is not None and R1 is None:
        fw = FrictionWindage(fw.power, fw.how + " (no DC resistance: stator copper loss not removed, the "
                                                "intercept is slightly high)")
    return fw


def load_loadtest(folder) -> AdmittanceData:
    """The folder's tests as admittance readings (load, then no-load, then locked rotor)."""
    lt = read_loadtest(folder)
    f, p = lt.frequency, lt.pole_pairs
    parts = []
    for k, (name, t) in enumerate(lt.tables.items()):
        Y = t.Y
        if name == "load":
            if t.speed_rpm is None:
                raise DataError(Path(folder) / t.file, "load points need speed_rpm", column="speed_rpm")
            s = 1.0 - t.speed_rpm * p / (60.0 * t.frequency)
        elif name == "noload":
            s = np.zeros(len(Y))
            if lt.friction is not None:
                Y = Y - lt.friction.power / (3.0 * t.V**2)
        else:
            s = np.ones(len(Y))
        parts.append((name, k, s, Y, t))
    notes = list(lt.notes)
    if "noload" in lt.tables:
        notes.append("no-load readings at slip 0 with friction and windage removed from the input power: "
                     + (lt.friction.how if lt.friction else "none known (give friction_windage in meta.yaml or "
                        "a no-load series at three or more voltages): it is left in, and R0 absorbs it"))
    if "locked" in lt.tables:
        k = lt.tables["locked"].frequency / f
        notes.append(f"locked-rotor readings at slip 1, frequency ratio {', '.join(f'{x:.3g}' for x in np.unique(k))}: "
                     "reactances scaled by the ratio, the magnetising branch's resistance by its square")
    V = np.concatenate([t.V for *_, t in parts])
    freq = np.concatenate([t.frequency for *_, t in parts])
    temps = [t.temperature for *_, t in parts]
    theta = np.concatenate(temps) if all(x is not None for x in temps) else None
    if theta is None and any(x is not None for x in temps):
        notes.append("temperature compensation off: some tables have no temperature column")
    sig = [_reading_errors(lt, name, t, s, y) for name, _, s, y, t in parts]
    slip = np.concatenate([s for _, _, s, _, _ in parts])
    Y = np.concatenate([y for _, _, _, y, _ in parts])
    if len(slip) < 4:
        raise DataError(folder, f"only {len(slip)} readings in the test tables; at least 4 are needed")
    return AdmittanceData(
        frequency=f, pole_pairs=p, slip=slip, G=Y.real, B=Y.imag, voltage=V,
        sweep=np.concatenate([np.full(len(s), k) for _, k, s, _, _ in parts]),
        stator_dc_resistance=None if lt.R1_dc is None else (lt.R1_dc, lt.R1_dc),
        winding_temperature_before=lt.theta_dc, reference_temperature=lt.theta_ref,
        source=str(folder), description=lt.description, files=[t.file for *_, t in parts],
        frequency_ratio=freq / f, winding_temperature=theta,
        test=np.concatenate([np.full(len(s), name) for name, _, s, _, _ in parts]),
        sigma_G=np.concatenate([g for g, _ in sig]), sigma_B=np.concatenate([b for _, b in sig]),
        notes=notes, loadtest=lt,
    )


def _reading_errors(lt: LoadTest, name: str, t: TestTable, s: np.ndarray, Y: np.ndarray):
    """``(sigma_G, sigma_B)`` of a test's readings: the instruments', and the slip's (load) or the
    friction and windage loss's (no-load) in quadrature."""
    sG, sB = t.standard_errors(lt.accuracy)
    if name == "load" and len(np.unique(s)) >= 2:
        order = np.argsort(s, kind="stable")
        u, first = np.unique(s[order], return_index=True)
        dY = np.gradient(Y[order][first], u) if len(u) >= 2 else np.zeros(len(u), complex)
        dYds = np.interp(s, u, dY.real) + 1j * np.interp(s, u, dY.imag)
        sigma_s = lt.speed_resolution / np.sqrt(12.0) * lt.pole_pairs / (60.0 * t.frequency)
        sG, sB = np.hypot(sG, np.abs(dYds.real) * sigma_s), np.hypot(sB, np.abs(dYds.imag) * sigma_s)
    if name == "noload" and lt.friction is not None:
        sG = np.hypot(sG, lt.friction.sigma / (3.0 * t.V**2))
    return sG, sB


def write_loadtest(folder, meta: dict, tables: dict[str, dict], truth: dict | None = None) -> Path:
    """Write a load-test folder: ``meta.yaml``, one CSV per test (``tables[name]`` = columns) and
    ``truth.yaml`` (synthetic data only)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, file in TEST_FILES.items():
        (folder / file).unlink(missing_ok=True)
        if name in tables:
            write_table_atomic(folder / file, tables[name], float_format="%.10g")
    write_yaml_atomic(folder / "meta.yaml", {"kind": "loadtest", **meta})
    if truth is not None:
        write_yaml_atomic(folder / "truth.yaml", truth)
    return folder
