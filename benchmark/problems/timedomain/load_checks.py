"""Checks on load of a start-up record for mistakes that still produce a result: wiring
(:mod:`~benchmark.problems.timedomain.wiring_checks`), units (a current, voltage
or speed scale the nameplate contradicts, an inertia the rated power contradicts, a stated DC
resistance the record's energy contradicts, a speed beyond the synchronous one), pole pairs the
settled speed contradicts, a supply frequency the voltages contradict, and the input hold
(inverter levels read as a continuous voltage). Each says what is wrong and how to fix it in one line: an error
(:class:`~benchmark.core.errors.DataError`, exit status 2) where the data cannot be right, a
warning (:class:`~benchmark.core.errors.DataWarning`) where they only look wrong. Run on the
records as read, before the conditioning (:func:`check_records`).

The fundamental of a channel is its phasor demodulated at the supply frequency over the record's
last fifth (a start-up ends near its steady state); the supply frequency is the voltage phasor's
rotation there.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from benchmark.core.errors import DataError, DataWarning
from benchmark.problems.timedomain.frames import fundamental, phasor_speed

if TYPE_CHECKING:  # the records' type (data.py imports this module)
    from benchmark.problems.timedomain.data import StartupRecord

#: Declared and measured supply frequency may differ by this share (a grid's 1 %, and the end
#: of a record being short of whole periods).
FREQUENCY_TOLERANCE = 0.05
#: Steady-state current over the nameplate's rated current: a motor near no load draws 0.1-1
#: times it; outside this range it looks wrong (a warning) ...
CURRENT_RATIO_PLAUSIBLE = (0.05, 2.0)
#: ... and outside this one it cannot be right (an error: mA for A, kA for A).
CURRENT_RATIO_POSSIBLE = (0.005, 20.0)
#: Supply voltage (line-to-line rms of the fundamental) over the nameplate voltage: plausible (a
#: reduced-voltage or V/f inverter start is lower) and possible (V, not mV or kV).
VOLTAGE_RATIO_PLAUSIBLE = (0.4, 1.25)
VOLTAGE_RATIO_POSSIBLE = (0.02, 5.0)
#: Final speed over the nameplate speed: plausible (a loaded start ends lower) and possible.
SPEED_RATIO_PLAUSIBLE = (0.5, 1.3)
SPEED_RATIO_POSSIBLE = (0.15, 4.0)
#: Typical rotor inertia of a motor of rated power P: ``J_TYPICAL * (P / 1 kW)^J_EXPONENT`` kg m^2
#: (the zoo's 26 published motors, 1-150 kW, lie within a factor 7 of it) ...
J_TYPICAL, J_EXPONENT = 0.005, 1.25
#: ... and the energy bound on J (``2 E_in / w^2``: losses and a coupled load included) is
#: suspect beyond this factor of it either way.
J_RATIO_PLAUSIBLE = 1000.0
#: Efficiency times power factor of a motor at its rated point: a nameplate without a current
#: bounds it by ``P / (sqrt(3) V x)`` over this range (small motors 0.5, large ones up to 0.85).
RATED_EFFICIENCY_POWER_FACTOR = (0.3, 0.9)
#: The stator's copper loss at ``stator_dc_resistance`` over a start-up record may reach this many
#: times the electrical energy the record takes in before the data are refused. Physics allows 1
#: (the copper loss is part of what goes in; on 57 synthetic records of the three sources and
#: the example it was 0.15-0.74): the margin holds a winding measured hot and started cold and a
#: delta winding's phase resistance given for its star equivalent (3 times it).
RS_ENERGY_RATIO_POSSIBLE = 5.0
#: A speed above this multiple of the synchronous speed (plus 1 rad/s) cannot come from a
#: motor starting on its supply (see :func:`check_speed_plausibility`).
SYNC_SPEED_MARGIN = 1.5
#: An inverter's voltage holds its level: at least this share of samples repeat the one before.
HELD_SHARE = 0.5
#: ... on at most this many distinct levels per channel.
INVERTER_LEVELS = 64


def steady_tail(rec) -> slice:
    n = len(rec.t)
    return slice(int(0.8 * n), n)


def electrical_speed(rec) -> float:
    """Signed rotation speed (rad/s) of the voltage phasor over the record's last fifth."""
    tail = steady_tail(rec)
    return phasor_speed(rec.v_alpha[tail], rec.v_beta[tail], rec.t[tail])


def final_speed(rec) -> float:
    """Mean speed (rad/s, signed) over the record's last fifth."""
    return float(np.mean(rec.speed[steady_tail(rec)]))


def input_power(rec) -> np.ndarray:
    """Electrical power (W) the machine takes in at each sample, ``1.5 (v_alpha i_alpha + v_beta
    i_beta)``: summed over a record and times its sample time, the energy it took."""
    return 1.5 * (rec.v_alpha * rec.i_alpha + rec.v_beta * rec.i_beta)


def columns_of(rec, kind: str) -> str:
    cols = getattr(rec, "columns", None) or {}
    return cols.get(kind, "v_alpha, v_beta" if kind == "voltage" else "i_alpha, i_beta")


def check_supply_frequency(rec, declared: float | None, meta_path) -> None:
    """``supply_frequency`` of meta.yaml (Hz) against the voltage phasor's rotation over the
    record's last fifth, where it is steady (the two halves of that fifth within
    :data:`FREQUENCY_TOLERANCE`: an inverter's V/f ramp cut short of its final frequency is not
    checked): beyond :data:`FREQUENCY_TOLERANCE` apart, a DataError naming the key (the
    conditioning and the diagnosis's folds are cut by it)."""
    measured = abs(electrical_speed(rec)) / (2.0 * math.pi)
    if not declared or not measured > 0 or abs(measured / declared - 1.0) <= FREQUENCY_TOLERANCE:
        return
    tail = np.arange(len(rec.t))[steady_tail(rec)]
    halves = [abs(phasor_speed(rec.v_alpha[k], rec.v_beta[k], rec.t[k])) for k in np.array_split(tail, 2)]
    if abs(halves[1] - halves[0]) > FREQUENCY_TOLERANCE * max(halves):
        return  # the supply's frequency still moves (a ramp): the record's end says nothing of the key
    raise DataError(meta_path, f"key 'supply_frequency' is {declared:g} Hz, but the voltages of {rec.source} turn "
                               f"at {measured:.4g} Hz at the record's end: state the supply's frequency "
                               f"(supply_frequency: {measured:.3g}) or leave the key out")


def check_pole_pairs(rec, pole_pairs: int) -> None:
    """A rotor that settles at ``k / p_true`` of the synchronous speed ``w_e / pole_pairs`` with
    ``pole_pairs / p_true`` a ratio of integers where a motor's no-load speed would come out
    (0.9-1.0 of synchronous with ``p_true``): a DataWarning that ``pole_pairs`` may be too small
    (2 for a 4-pole motor given as 1 put it at 0.50 of synchronous, and the fit 284 times the
    noise off, with no word on the cause). A warning only: a heavy load can hold a motor at a
    high slip."""
    if not rec.has_speed or not pole_pairs or not settled(rec):
        return
    sync = abs(electrical_speed(rec)) / pole_pairs
    if not sync > 0:
        return
    ratio = abs(final_speed(rec)) / sync
    if not 0.0 < ratio < 0.9:
        return
    true_p = round(pole_pairs / ratio)
    if true_p > pole_pairs and 0.9 <= ratio * true_p / pole_pairs <= 1.0:
        warnings.warn(DataWarning.at(
            rec.source, f"the rotor settles at {ratio:.3f} of the synchronous speed {sync:.4g} rad/s that "
                        f"pole_pairs {pole_pairs} gives: is pole_pairs {true_p} (a {2 * true_p}-pole motor, "
                        f"{ratio * true_p / pole_pairs:.3f} of its synchronous speed)? A motor settles near "
                        "its synchronous speed unless heavily loaded", column="speed"), stacklevel=3)


def settled(rec) -> bool:
    """Whether the record ends in a steady state: over its last fifth the speed's (or without a
    speed, the current amplitude's) mean in the first and second halves agree within 2 %. A start
    that has not finished (a coupled load's inertia) still draws a large current at a low speed."""
    tail = steady_tail(rec)
    x = np.abs(rec.speed[tail]) if rec.has_speed else np.hypot(rec.i_alpha[tail], rec.i_beta[tail])
    half = len(x) // 2
    if half <= 4:
        return False
    a, b = float(np.mean(x[:half])), float(np.mean(x[half:]))
    return abs(a - b) <= 0.02 * max(abs(b), 1e-12)


def _ratio_check(path, column, what, ratio, plausible, possible, hint, steady: bool,
                 against: str = "the nameplate's") -> None:
    """An error beyond ``possible`` (its lower end only for a record in its steady state: an
    unfinished start is slow and draws much current), a warning beyond ``plausible`` (steady only)."""
    low = possible[0] if steady else 0.0
    if low <= ratio <= possible[1]:
        if steady and not plausible[0] <= ratio <= plausible[1]:
            warnings.warn(DataWarning.at(path, f"{what} is {ratio:.3g} times {against}: {hint}", column=column),
                          stacklevel=4)
        return
    raise DataError(path, f"{what} is {ratio:.3g} times {against}, which cannot be: {hint}", column=column)


def check_scales(rec, nameplate: dict | None, pole_pairs: int) -> None:
    """Current, voltage, speed and the energy's inertia against the nameplate (``current`` A rms,
    ``voltage`` V line-to-line rms, ``speed`` rpm, ``rated_power`` W): an error where the scale
    cannot be right (a current in mA), a warning where it only looks wrong."""
    if not nameplate:
        return
    tail = steady_tail(rec)
    t = rec.t[tail]
    w_e = electrical_speed(rec)
    i = rec.i_alpha[tail] + 1j * rec.i_beta[tail]
    icols = columns_of(rec, "current")
    steady = settled(rec)
    current_hint = "are the currents in A (not mA or kA), and the probe's scale right?"
    i_rms = abs(fundamental(i, t, w_e)) / math.sqrt(2.0) if abs(w_e) > 0 else math.nan
    if nameplate.get("current") and abs(w_e) > 0:
        _ratio_check(rec.source, icols, f"the steady-state current {i_rms:.4g} A rms", i_rms / nameplate["current"],
                     CURRENT_RATIO_PLAUSIBLE, CURRENT_RATIO_POSSIBLE, current_hint, steady)
    elif nameplate.get("rated_power") and nameplate.get("voltage") and abs(w_e) > 0:
        # no rated current: the one a motor of this power and voltage can have (an error only)
        apparent = nameplate["rated_power"] / (math.sqrt(3.0) * nameplate["voltage"])
        lo, hi = (apparent / x for x in reversed(RATED_EFFICIENCY_POWER_FACTOR))
        ratio = i_rms / hi if i_rms > hi else i_rms / lo if i_rms < lo else 1.0
        motor = f"{nameplate['rated_power'] / 1e3:.3g} kW, {nameplate['voltage']:.4g} V motor"
        _ratio_check(rec.source, icols, f"the steady-state current {i_rms:.4g} A rms", ratio, (0.0, math.inf),
                     CURRENT_RATIO_POSSIBLE, current_hint, steady,
                     against=f"the rated current a {motor} can have ({lo:.3g}-{hi:.3g} A rms; the nameplate states "
                             "no current)")
    if nameplate.get("voltage") and abs(w_e) > 0:
        vcols = columns_of(rec, "voltage")
        v_ll = abs(fundamental(rec.v_alpha[tail] + 1j * rec.v_beta[tail], t, w_e)) * math.sqrt(1.5)
        ratio = v_ll / nameplate["voltage"]
        hint = "are the voltages in V, and nameplate.voltage the line-to-line rms?"
        if "v_r" in vcols and abs(ratio / math.sqrt(3.0) - 1.0) < 0.15:
            hint = (f"{vcols} look like line-to-line voltages (sqrt(3) times a phase voltage): name two of them "
                    "v_rs, v_st (v_R - v_S, v_S - v_T) and drop the third, or give the phase voltages")
        _ratio_check(rec.source, vcols, f"the supply voltage {v_ll:.4g} V rms line-to-line", ratio,
                     VOLTAGE_RATIO_PLAUSIBLE, VOLTAGE_RATIO_POSSIBLE, hint, steady)
    if nameplate.get("speed") and rec.has_speed:
        final = final_speed(rec)
        rated = nameplate["speed"] * math.pi / 30.0
        _ratio_check(rec.source, "speed", f"the final speed {final:.4g} rad/s", abs(final) / rated,
                     SPEED_RATIO_PLAUSIBLE, SPEED_RATIO_POSSIBLE,
                     "is the speed in rad/s (or speed_unit: rpm in meta.yaml) and mechanical, not electrical?",
                     steady)
    if nameplate.get("rated_power") and rec.has_speed and steady:
        w_end = float(np.mean(np.abs(rec.speed[tail])))
        energy = float(np.sum(input_power(rec))) * float(np.median(np.diff(rec.t)))
        if w_end > 0 and energy > 0:
            j_max = 2.0 * energy / w_end**2
            j_typ = J_TYPICAL * (nameplate["rated_power"] / 1e3) ** J_EXPONENT
            if not 1.0 / J_RATIO_PLAUSIBLE <= j_max / j_typ <= J_RATIO_PLAUSIBLE:
                warnings.warn(DataWarning.at(
                    rec.source, f"the energy the start-up took bounds the inertia at {j_max:.3g} kg m^2, "
                                f"{j_max / j_typ:.3g} times a typical {nameplate['rated_power'] / 1e3:.3g} kW motor's "
                                f"{j_typ:.2g} kg m^2: are the currents ({icols}) and voltages in A and V?",
                    column=icols), stacklevel=3)


def check_stator_resistance(rec, stator_dc_resistance: float | None, meta_path) -> None:
    """``stator_dc_resistance`` against the energy of a start-up record: the stator's copper loss
    ``1.5 Rs sum(i_alpha^2 + i_beta^2) Ts`` is part of the electrical energy taken in,
    ``1.5 sum(v_alpha i_alpha + v_beta i_beta) Ts``; at more than :data:`RS_ENERGY_RATIO_POSSIBLE`
    times it the resistance and the record cannot both be right (currents in mA, voltages in kV,
    a resistance in milliohm): a DataError naming the key and the file. Needs no nameplate."""
    if not stator_dc_resistance or stator_dc_resistance <= 0:
        return
    copper = 1.5 * (rec.i_alpha**2 + rec.i_beta**2)
    energy, squares = float(np.sum(input_power(rec))), float(np.sum(copper))  # both times Ts: the ratio drops it
    if not (squares > 0 and energy > 0):
        return  # no current, or a record that gives back more than it takes (a machine driven as a generator)
    ratio = stator_dc_resistance * squares / energy
    if ratio > RS_ENERGY_RATIO_POSSIBLE:
        ts = float(np.median(np.diff(rec.t)))
        raise DataError(meta_path, f"key 'stator_dc_resistance' is {stator_dc_resistance:.4g} ohm, but at that "
                                   f"resistance the stator's copper loss over {Path(rec.source).name} "
                                   f"({stator_dc_resistance * squares * ts:.3g} J) would be {ratio:.3g} times the "
                                   f"electrical energy its voltages and currents take in ({energy * ts:.3g} J), which "
                                   "cannot be: are the currents in A (not mA), the voltages in V (not kV), and the "
                                   "resistance the winding's ohm per phase?")


def check_input_hold(rec, input_hold: str, meta_path) -> None:
    """Voltages held at a few levels (an inverter's switch states) while meta.yaml says ``linear``:
    a warning to set ``input_hold: zoh``."""
    if input_hold != "linear":
        return
    held = min(float(np.mean(np.diff(x) == 0.0)) for x in (rec.v_alpha, rec.v_beta))
    levels = max(len(np.unique(x)) for x in (rec.v_alpha, rec.v_beta))
    if held >= HELD_SHARE and levels <= INVERTER_LEVELS:
        warnings.warn(DataWarning.at(
            meta_path, f"input_hold is linear, but the voltages of {rec.source} hold {levels} levels for "
                       f"{100 * held:.0f} % of the samples, as an inverter's switch states do: set input_hold: zoh "
                       "(the model would otherwise ramp between the levels)", column=None), stacklevel=3)


def synchronous_speed_estimate(rec: StartupRecord, pole_pairs: int, sample_time: float) -> float:
    """Mechanical synchronous speed (rad/s) estimated from the rotation of the current phasor:
    the fastest mean rotation over ten windows of the record (0 if it cannot be told)."""
    i = rec.i_alpha + 1j * rec.i_beta
    n = len(i)
    if n < 20:
        return 0.0
    mag = np.abs(i)
    if not mag.max() > 0:
        return 0.0
    phase = np.unwrap(np.angle(i))
    best = 0.0
    edges = np.linspace(0, n - 1, 11).astype(int)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if b - a < 2 or np.median(mag[a:b + 1]) < 0.05 * mag.max():
            continue
        best = max(best, abs(phase[b] - phase[a]) / ((b - a) * sample_time))
    return best / pole_pairs


def check_speed_plausibility(meta_path: Path, startups, stops, p: int,
                              supply_frequency: float | None, speed_unit: str = "rad/s") -> None:
    """Speed against the synchronous speed ``2 pi f / p``: an induction motor starting on its
    supply with no driving load cannot run much above it (the start-up overshoot stays well
    below: about 20 % for an 8-pole variant of the paper motor). With ``supply_frequency`` in
    meta.yaml the check is strict: above :data:`SYNC_SPEED_MARGIN` times the synchronous
    speed is an error. Without it, the
    frequency is estimated from the current phasor's rotation, and exceeding the margin is
    only a :class:`DataWarning` (the estimate can be fooled), typically a column in rpm."""
    records = [(r.source, r.speed) for r in startups if r.has_speed] + [(r.source, r.speed) for r in stops]
    if supply_frequency is not None:
        w_sync = 2 * np.pi * supply_frequency / p
        basis = f"supply_frequency {supply_frequency:g} Hz and pole_pairs {p} in meta.yaml"
        strict = True
    else:
        # the supply's own rotation at the record's end (the currents' turn faster in a start's transient),
        # else the currents'
        estimates = [abs(electrical_speed(r)) / p
                     or synchronous_speed_estimate(r, p, float(np.median(np.diff(r.t))) if len(r.t) > 1 else 1.0)
                     for r in startups]
        w_sync = max(estimates) if estimates else 0.0
        basis = (f"estimated from the supply's rotation (about {w_sync * p / (2 * np.pi):.3g} Hz) and "
                 f"pole_pairs {p}")
        strict = False
    if not w_sync > 0:
        return
    limit = SYNC_SPEED_MARGIN * w_sync + 1.0
    for source, speed in records:
        k = int(np.argmax(np.abs(speed)))
        if abs(speed[k]) <= limit:
            continue
        v = float(speed[k])
        msg = (f"speed {v:.6g} rad/s is {abs(v) / w_sync:.3g} times the synchronous speed {w_sync:.4g} rad/s "
               f"({basis})")
        as_rpm = abs(v) * np.pi / 30
        rpm_hint = (f"; if the column is in rpm, convert it: rad/s = rpm * pi / 30 ({abs(v):.6g} rpm = "
                    f"{as_rpm:.4g} rad/s), or declare speed_unit: rpm in meta.yaml")
        if speed_unit == "rpm":
            rpm_hint = " (meta.yaml declares speed_unit: rpm; the speed above is after conversion)"
        k_times = abs(v) / w_sync
        k_int = round(k_times)
        if k_int >= 2 and abs(k_times / k_int - 1.0) < 0.15 and p % k_int == 0:  # pole pairs' multiple
            electrical = f"is the speed electrical (divide it by pole_pairs {p}) or " if k_int == p else "are "
            rpm_hint = (f"; at {k_int} times it, {electrical}pole_pairs too many (then {p // k_int})?") + rpm_hint
        if strict:
            raise DataError(source, "impossible for a motor starting on that supply" + "; " + msg + rpm_hint
                            + " (or correct supply_frequency / pole_pairs)", column="speed", row=k + 1)
        warnings.warn(DataWarning.at(source, "looks like rpm, not rad/s: " + msg + rpm_hint
                                     + " (give supply_frequency in meta.yaml to make this an error)",
                                     column="speed", row=k + 1), stacklevel=3)


def check_records(startups, nameplate: dict | None, pole_pairs: int, input_hold: str, meta_path,
                  supply_frequency: float | None = None, stator_dc_resistance: float | None = None) -> None:
    """Every check above on every start-up record."""
    from benchmark.problems.timedomain.wiring_checks import check_phase_sequence, check_speed_direction

    for rec in startups:
        check_supply_frequency(rec, supply_frequency, meta_path)
        check_phase_sequence(rec, pole_pairs)
        check_speed_direction(rec, pole_pairs)
        check_pole_pairs(rec, pole_pairs)
        check_scales(rec, nameplate, pole_pairs)
        check_stator_resistance(rec, stator_dc_resistance, meta_path)
        check_input_hold(rec, input_hold, meta_path)
