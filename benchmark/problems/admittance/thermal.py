"""The winding temperature during a sweep, from the DC resistances before and after and a one-body
thermal model driven by the losses (or the current squared); copper resistances follow
R(theta) = R(theta_ref) (COPPER_INFERRED_ZERO_C + theta) / (COPPER_INFERRED_ZERO_C + theta_ref)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import PchipInterpolator

from benchmark.core.errors import ConfigError
from benchmark.problems.admittance.circuit import (
    copper_factor,
    step_temperature,
    temperature_from_resistance,
)
from benchmark.problems.admittance.data import AdmittanceData

#: Step (s) of the thermal model's integration between readings.
THERMAL_STEP_S = 0.05


# ----------------------------------------------------------------------------- temperature


@dataclass
class TemperatureProfile:
    """Estimated winding temperature at each reading and what it rests on.

    Attributes
    ----------
    theta : deg C per reading.  theta_before, theta_after : deg C at the DC readings.
    theta_ref : deg C the fitted resistances are referred to.  R1_ref : stator DC resistance at
    ``theta_ref``, ohm.  factor : copper factor ``R(theta_i)/R(theta_ref)`` per reading.
    heat_model : ``losses`` or ``current_squared``.  cooling : whether cooling rates were known.
    """

    theta: np.ndarray
    theta_before: float
    theta_after: float
    theta_ref: float
    R1_ref: float
    factor: np.ndarray
    heat_model: str
    cooling: bool
    notes: list[str] = field(default_factory=list)


def _piecewise_inputs(data: AdmittanceData, heat: np.ndarray):
    """Heat and speed as functions of time. Within a sweep table the heat follows a shape-preserving
    cubic through the readings (it is a smooth, peaked function of speed; a straight line between
    readings 100 rpm apart misses its curvature). Before a table's first reading the machine is
    taken to run energised at that reading's conditions (the paper connects the supply and lets
    conditions settle before reading); after the last reading, and in the data's ``supply_off``
    intervals, there is no heat. Speed is linear in time between readings."""
    t, n = data.time, data.speed_rpm
    sweeps = data.sweep if data.sweep is not None else np.zeros(len(t), int)
    pieces = []
    for k in np.unique(sweeps):
        m = sweeps == k
        tk, hk = t[m], heat[m]
        f = PchipInterpolator(tk, hk, extrapolate=False) if len(tk) > 1 else None
        pieces.append((tk[0], tk[-1], hk[0], f))
    pieces.sort(key=lambda q: q[0])

    def heat_at(tm):
        tm = np.asarray(tm, float)
        h = np.zeros_like(tm)
        prev_end = -np.inf
        for t0, t1, h0, f in pieces:
            h = np.where((tm > prev_end) & (tm < t0), h0, h)  # settling before the table
            if f is not None:
                inside = (tm >= t0) & (tm <= t1)
                h = np.where(inside, f(np.clip(tm, t0, t1)), h)
            prev_end = t1
        for a, b in data.supply_off or ():
            h = np.where((tm > a) & (tm < b), 0.0, h)
        return h

    def speed_at(tm):
        return np.interp(tm, t, n)

    return heat_at, speed_at


def estimate_temperatures(
    data: AdmittanceData, heat_model: str = "auto", theta_ref: float | None = None
) -> TemperatureProfile:
    """Temperature of the windings at each reading from the DC resistances before/after (see the
    module docstring). Needs ``stator_dc_resistance`` and a ``time`` column."""
    if data.stator_dc_resistance is None or data.time is None:
        raise ValueError("temperature estimation needs stator_dc_resistance and a time column")
    R_b, R_a = data.stator_dc_resistance
    notes = []
    theta_b = data.winding_temperature_before
    if theta_ref is None:
        theta_ref = data.reference_temperature
    if theta_b is None:
        theta_b = theta_ref if theta_ref is not None else 50.0
        notes.append(
            f"winding temperature at the first DC reading not given: taken as {theta_b} C "
            "(results are referred to the temperature at the start)"
        )
    if theta_ref is None:
        theta_ref = theta_b
    theta_a_end = float(temperature_from_resistance(R_a, R_b, theta_b))
    t_b, t_a = (
        data.dc_resistance_time if data.dc_resistance_time is not None else (data.time[0], data.time[-1])
    )
    if heat_model == "auto":
        heat_model = "losses" if data.torque is not None else "current_squared"
    w_mech = 2 * np.pi * data.speed_rpm / 60.0
    if heat_model == "losses":
        if data.torque is None:
            raise ConfigError("problem.heat_model: 'losses' needs a torque column in the sweep tables")
        heat = 3.0 * data.voltage**2 * data.G - data.torque * w_mech
    else:
        heat = np.abs(data.Y) ** 2 * data.voltage**2
    heat_at, speed_at = _piecewise_inputs(data, heat)
    th = data.thermal
    cooling = th is not None
    theta_amb = th["ambient_temperature"] if cooling else 0.0

    def rate(n):
        if not cooling:
            return np.zeros_like(n)
        r0, rn = th["cooling_rate_standstill"], th["cooling_rate_at_speed"]
        return r0 + (rn - r0) * np.abs(n) / th["cooling_rate_speed_rpm"]

    grid = np.unique(
        np.concatenate(
            [np.linspace(t_b, t_a, max(2, int(np.ceil((t_a - t_b) / THERMAL_STEP_S)) + 1)), data.time]
        )
    )
    grid = grid[(grid >= t_b) & (grid <= t_a)]
    # theta(t) = theta_amb + (theta_b - theta_amb)*phi(t) + h*psi(t): linear in the unknown scale h
    phi = np.empty_like(grid)
    psi = np.empty_like(grid)
    phi[0], psi[0] = 1.0, 0.0
    tm = 0.5 * (grid[1:] + grid[:-1])
    dts = np.diff(grid)
    q, r = heat_at(tm), rate(speed_at(tm))
    for i in range(len(dts)):
        phi[i + 1] = step_temperature(phi[i], 0.0, r[i], 0.0, dts[i])
        psi[i + 1] = step_temperature(psi[i], q[i], r[i], 0.0, dts[i])
    if psi[-1] <= 0:
        raise ValueError("no heat recorded between the DC readings")
    h = (theta_a_end - theta_amb - (theta_b - theta_amb) * phi[-1]) / psi[-1]
    theta_grid = theta_amb + (theta_b - theta_amb) * phi + h * psi
    theta = np.interp(data.time, grid, theta_grid)
    if h < 0:
        notes.append("the DC resistances imply cooling beyond the thermal model's: heating scale negative")
    if not cooling:
        notes.append("no cooling rates in meta.yaml (thermal): adiabatic thermal model")
    R1_ref = R_b / float(copper_factor(theta_b, theta_ref))
    return TemperatureProfile(
        theta=theta,
        theta_before=float(theta_b),
        theta_after=theta_a_end,
        theta_ref=float(theta_ref),
        R1_ref=float(R1_ref),
        factor=np.asarray(copper_factor(theta, theta_ref)),
        heat_model=heat_model,
        cooling=cooling,
        notes=notes,
    )


def measured_temperatures(data: AdmittanceData, theta_ref: float | None = None) -> TemperatureProfile:
    """The profile of readings whose winding temperature was measured (a load test's
    ``temperature`` column): no thermal model. ``R1_ref`` is the DC resistance referred to
    ``theta_ref`` (nan without one: the fitted R1_total is then scaled by the copper factor)."""
    theta = np.asarray(data.winding_temperature, float)
    if theta_ref is None:
        theta_ref = data.reference_temperature
    notes = ["winding temperature measured at each reading (temperature column)"]
    if theta_ref is None:
        theta_ref = float(np.median(theta))
        notes.append(f"resistances referred to the median reading temperature, {theta_ref:g} C")
    theta_dc = data.winding_temperature_before
    R1_ref = np.nan
    if data.stator_dc_resistance is not None and theta_dc is not None:
        R1_ref = float(np.mean(data.stator_dc_resistance)) * float(copper_factor(theta_ref, theta_dc))
    return TemperatureProfile(
        theta=theta,
        theta_before=float("nan") if theta_dc is None else float(theta_dc),
        theta_after=float("nan"),
        theta_ref=float(theta_ref),
        R1_ref=float(R1_ref),
        factor=np.asarray(copper_factor(theta, theta_ref)),
        heat_model="measured",
        cooling=False,
        notes=notes,
    )
