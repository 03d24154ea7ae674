"""Search bounds of the admittance problem: the user's (``bounds=``), the motor preset's (for the
preset's own synthetic data only: a data folder is another motor, unless
``use_motor_bounds_with_data=true``), or derived from the data, each parameter by itself.

Derived bounds read two readings (Lindsay and Barton's initial model A, widened):

* the **no-load reading** (the reading at rated frequency nearest synchronous speed, the highest
  voltage among equals) gives the magnetising impedance ``Z_nl = 1/Y = Z1 + Z0``;
* the **largest-slip reading** gives the series (short-circuit) impedance: the rotor path's
  impedance ``Z_r = 1/(Y_s - Y_nl/k)`` (the no-load admittance taken away, at the reading's
  frequency ratio k) is about ``R2/s + jX`` near synchronism and ``Z1 + Z2`` at standstill, so
  ``R2 ~ |s| Re(Z_r)`` and the leakage ``X ~ Im(Z_r)/k`` (at least 1 % of the no-load reactance:
  a few load points near synchronism hardly show the leakage); when the two admittances do not
  differ as a rotor path would, half the largest-slip reading's impedance stands in.

Each range then spans two or three decades around these rough values (resistances and leakage
reactances a factor 30 either side, the magnetising reactance 30 below to 3 above, the core-loss
resistance from 0 to 10 times ``Re(Z_nl)``), so that machines from a few kW to hundreds identify
without hand-set bounds; with a DC stator resistance, ``R1_total`` is searched within a decade of it.
"""

from __future__ import annotations

import math

import numpy as np

from benchmark.core.errors import ConfigError
from benchmark.problems.admittance.data import AdmittanceData

__all__ = ["derive_bounds", "choose_bounds", "WIDEN"]

#: Factor either side of the rough resistance and leakage values.
WIDEN = 30.0


def _rated(data: AdmittanceData) -> np.ndarray:
    k = data.frequency_ratio
    return np.ones(data.n, bool) if k is None else np.abs(np.asarray(k) - 1.0) < 1e-9


def rough_impedances(data: AdmittanceData) -> dict[str, float]:
    """The no-load impedance and the rough rotor resistance and leakage reactance (ohm)."""
    s, Y, V = np.asarray(data.slip, float), data.Y, np.asarray(data.voltage, float)
    k = np.ones(data.n) if data.frequency_ratio is None else np.asarray(data.frequency_ratio, float)
    rated = np.flatnonzero(_rated(data))
    if not len(rated):
        raise ConfigError("bounds: cannot derive bounds: no reading at the rated frequency; give bounds=...")
    near = rated[np.abs(s[rated]) <= np.abs(s[rated]).min() + 1e-9]
    i0 = int(near[np.argmax(V[near])])
    j = int(np.argmax(np.abs(s)))
    Z_nl = 1.0 / Y[i0]
    if abs(s[j]) < 1e-6 or not (Z_nl.imag > 0):
        raise ConfigError("bounds: cannot derive bounds: the data need a reading near synchronous speed and one "
                          "away from it (a load point, the locked rotor); give bounds=...")
    with np.errstate(all="ignore"):
        Z_r = 1.0 / (Y[j] - Y[i0] / k[j])
    if not (np.isfinite(Z_r) and Z_r.real > 0):  # no rotor path to read: half the reading's impedance
        Z_r = complex(abs((1.0 / Y[j]).real), abs((1.0 / Y[j]).imag)) / 2.0 / max(abs(s[j]), 1e-3)
    R2 = abs(s[j]) * abs(Z_r.real)
    X = max(Z_r.imag / k[j], 0.01 * Z_nl.imag)
    return {"R_nl": float(abs(Z_nl.real)), "X_nl": float(Z_nl.imag), "R2": float(R2), "X": float(X)}


def derive_bounds(data: AdmittanceData, names) -> dict[str, tuple[float, float]]:
    """Bounds from the data alone (see the module docstring). Returns ``{name: (low, high)}``."""
    with np.errstate(all="ignore"):
        r = rough_impedances(data)
    if not all(math.isfinite(v) and v > 0 for v in r.values()):
        raise ConfigError(f"bounds: cannot derive bounds from the data (rough values {r}); give bounds=...")
    R, X = r["R2"], r["X"]
    R1 = (R / WIDEN, R * WIDEN)
    if data.stator_dc_resistance is not None:
        R_dc = float(np.mean(data.stator_dc_resistance))
        R1 = (R_dc / 10.0, 10.0 * R_dc)
    b = {
        "R1_total": R1,
        "X1": (X / WIDEN, X * WIDEN / 3.0),
        "R2": (R / WIDEN, R * WIDEN),
        "X2": (X / WIDEN, X * WIDEN / 3.0),
        "R0": (0.0, 10.0 * r["R_nl"] + R),
        "X0": (r["X_nl"] / WIDEN, 3.0 * r["X_nl"]),
        "R2sigma": (0.0, 3.0 * R),
        "X3": (0.0, X),
    }
    return {n: b[n] for n in names}


def _pair(src: str, name: str, val) -> tuple[float, float]:
    if isinstance(val, (str, bytes)) or not hasattr(val, "__len__") or len(val) != 2:
        raise ConfigError(f"{src}: expected [low, high], got {val!r}")
    try:
        lo, hi = (float(v) for v in val)
    except (TypeError, ValueError):
        raise ConfigError(f"{src}: expected two numbers [low, high], got {list(val)!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ConfigError(f"{src}: bounds must be finite, got [{lo}, {hi}]")
    if lo >= hi:
        raise ConfigError(f"{src}: low {lo} >= high {hi} (did you swap low and high?)")
    if lo < 0:
        raise ConfigError(f"{src}: {name} cannot be negative; low bound {lo} is not physical")
    return lo, hi


def choose_bounds(user: dict | None, preset: dict | None, names, data: AdmittanceData) -> dict:
    """Per parameter: the user's bounds, else the preset's, else derived from the data."""
    if user is not None:
        unknown = sorted(set(user) - set(names))
        if unknown:
            raise ConfigError(f"bounds: {unknown} not searched here; searched: {list(names)}")
    out, derived = {}, None
    for n in names:
        if user is not None and n in user:
            out[n] = _pair(f"bounds.{n}", n, user[n])
        elif preset is not None and n in preset:
            out[n] = _pair(f"motor.bounds.{n}", n, preset[n])
        else:
            if derived is None:
                derived = derive_bounds(data, names)
            out[n] = derived[n]
    return out
