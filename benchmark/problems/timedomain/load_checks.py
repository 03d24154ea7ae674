"""Checks on load of a start-up record for mistakes that still produce a result: wiring (phase
labels swapped or rotated between the voltage and the current channels, a current probe or a
tachometer reversed, line-to-line voltages given as phase voltages), units (a current, voltage
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
from benchmark.problems.timedomain.frames import clarke, fundamental, inverse_clarke, phasor_speed

if TYPE_CHECKING:  # the records' type (data.py imports this module)
    from benchmark.problems.timedomain.data import StartupRecord

#: A motor's current lags its voltage by 0-90 degrees; a phase angle outside this window (deg)
#: is no motor's: labels rotated by 120 degrees move it by 120.
PHASE_ANGLE_WINDOW = (-30.0, 120.0)
#: A current lagging the voltage by more than this (deg) returns power to the supply: only a
#: machine driven above synchronous speed does that (line-to-line voltages under the phase
#: columns add 30 degrees to a motor's 70-90 at no load).
GENERATING_LAG = 100.0
#: A current whose sequences are mixed is taken for a reversed probe when negating one channel
#: makes one sequence this many times the other (a healthy record's is hundreds).
REVERSED_PROBE_RATIO = 10.0
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


def _tail(rec) -> slice:
    n = len(rec.t)
    return slice(int(0.8 * n), n)


def electrical_speed(rec) -> float:
    """Signed rotation speed (rad/s) of the voltage phasor over the record's last fifth."""
    tail = _tail(rec)
    return phasor_speed(rec.v_alpha[tail], rec.v_beta[tail], rec.t[tail])


def final_speed(rec) -> float:
    """Mean speed (rad/s, signed) over the record's last fifth."""
    return float(np.mean(rec.speed[_tail(rec)]))


def input_power(rec) -> np.ndarray:
    """Electrical power (W) the machine takes in at each sample, ``1.5 (v_alpha i_alpha + v_beta
    i_beta)``: summed over a record and times its sample time, the energy it took."""
    return 1.5 * (rec.v_alpha * rec.i_alpha + rec.v_beta * rec.i_beta)


def _columns(rec, kind: str) -> str:
    cols = getattr(rec, "columns", None) or {}
    return cols.get(kind, "v_alpha, v_beta" if kind == "voltage" else "i_alpha, i_beta")


def current_lag(v_phasor: complex, i_phasor: complex, w_e: float) -> float:
    """The angle (deg) by which the current phasor lags the voltage phasor, both taken at the
    supply's signed speed ``w_e`` (rad/s): positive for a motor's inductive current."""
    S = v_phasor * np.conj(i_phasor)
    return math.degrees(math.atan2(S.imag, S.real)) * float(np.sign(w_e))


def check_phase_sequence(rec, pole_pairs: int | None = None) -> None:
    """Voltage and current phasors must turn the same way and the current lag the voltage by a
    motor's angle; a DataError says which labels to change. A lag beyond :data:`GENERATING_LAG`
    below synchronous speed (``pole_pairs`` given) is a warning: line-to-line voltages?"""
    tail = _tail(rec)
    t = rec.t[tail]
    v = rec.v_alpha[tail] + 1j * rec.v_beta[tail]
    i = rec.i_alpha[tail] + 1j * rec.i_beta[tail]
    w_e = electrical_speed(rec)
    if not abs(w_e) > 0 or not np.any(np.abs(i) > 0):
        return
    fwd, bwd = abs(fundamental(i, t, abs(w_e))), abs(fundamental(i, t, -abs(w_e)))
    i_sign = 1.0 if fwd >= bwd else -1.0
    vcols, icols = _columns(rec, "voltage"), _columns(rec, "current")
    if max(fwd, bwd) < 3 * min(fwd, bwd):
        _check_reversed_probe(rec, v, i, t, w_e, icols, fwd, bwd)
        return  # no clear sequence in the currents (a record that ends stopped): nothing to compare
    if np.sign(w_e) != i_sign:
        swap = _sequence_fix(rec, i, t, vcols, icols) if "v_r" in vcols else "negate v_beta"
        raise DataError(rec.source, f"the voltage ({vcols}) and current ({icols}) phase sequences disagree: the "
                                    f"voltage phasor turns {'forwards' if w_e > 0 else 'backwards'}, the current "
                                    f"phasor {'forwards' if i_sign > 0 else 'backwards'}, so two phase labels are "
                                    f"swapped in one of them; {swap}", column=vcols)
    angle = current_lag(fundamental(v, t, w_e), fundamental(i, t, w_e), w_e)
    lo, hi = PHASE_ANGLE_WINDOW
    if lo <= angle <= hi:
        if angle > GENERATING_LAG:
            _warn_generating(rec, angle, abs(w_e), vcols, pole_pairs)
        return
    fixed = {k: (angle - 120.0 * k + 180.0) % 360.0 - 180.0 for k in (1, -1)}
    k = min(fixed, key=lambda k: abs(fixed[k] - 45.0))
    if "v_r" in vcols:
        # k = 1: the file's voltage leads the true one by 120 degrees (its v_r column holds phase T)
        rename = ("rename v_r, v_s, v_t to v_t, v_r, v_s" if k == 1 else "rename v_r, v_s, v_t to v_s, v_t, v_r")
    else:
        rename = f"rotate the voltage phasor by {-120 * k:+d} degrees (relabel the phases before the Clarke transform)"
    flipped = (angle + 360.0) % 360.0 - 180.0  # every current probe reversed: 180 degrees off
    also = ""
    if 0.0 <= flipped <= 90.0:
        also = (f"; or every current probe is reversed: negate {icols} (then the current lags by "
                f"{flipped:.0f} degrees)")
    raise DataError(rec.source, f"the current lags the voltage by {angle:.0f} degrees, which no motor does (0 to 90): "
                                f"the voltage and current phase labels are rotated by 120 degrees against each other; "
                                f"{rename} (then the current lags by {fixed[k]:.0f} degrees){also}", column=vcols)


def _sequence_fix(rec, i, t, vcols: str, icols: str) -> str:
    """The relabelling that gives voltage and current one sequence with the current lagging by a
    motor's angle: of the three swaps of two voltage columns (each reverses the sequence; they
    differ by 120 degrees), the one whose lag is nearest 45 degrees. Swapping ``v_r`` and ``v_s``
    is swapping ``i_r`` and ``i_s`` (the data cannot tell which were labelled wrong: both are named);
    the other two have no current-column equivalent (the third current is not recorded)."""
    tail = _tail(rec)
    phases = dict(zip(("v_r", "v_s", "v_t"), inverse_clarke(rec.v_alpha[tail], rec.v_beta[tail]), strict=True))
    lags = {}
    for a, b in (("v_r", "v_s"), ("v_s", "v_t"), ("v_r", "v_t")):
        swapped = {**phases, a: phases[b], b: phases[a]}
        va, vb = clarke(swapped["v_r"], swapped["v_s"], swapped["v_t"])
        v = va + 1j * vb
        w = phasor_speed(va, vb, t)
        lags[(a, b)] = current_lag(fundamental(v, t, w), fundamental(i, t, w), w)
    (a, b), lag = min(lags.items(), key=lambda kv: abs(kv[1] - 45.0))
    fix = f"swap the columns {a} and {b}"
    if (a, b) == ("v_r", "v_s") and "i_r" in icols:
        fix = ("swap the columns i_r and i_s, or else v_r and v_s (either gives the same record: change the pair "
               "mislabelled)")
    return f"{fix} (then the current lags the voltage by {lag:.0f} degrees)"


def _check_reversed_probe(rec, v, i, t, w_e: float, icols: str, fwd: float, bwd: float) -> None:
    """Currents ``i`` that hold both sequences (``fwd``, ``bwd``: their phasors at +-``w_e``)
    where one phase channel negated gives one sequence, the voltage ``v``'s (speed ``w_e``),
    lagging it by a motor's angle: a probe mounted the wrong way round (a DataError naming the
    channel to negate). Anything else is left alone (a record that ends stopped)."""
    if "i_r" not in icols:
        return  # an alpha-beta channel negated reverses the sequence: the check above tells that
    i_r, i_s, _ = inverse_clarke(i.real, i.imag)
    V = fundamental(v, t, w_e)
    for col, r, s in (("i_r", -i_r, i_s), ("i_s", i_r, -i_s)):
        a, b = clarke(r, s, -r - s)
        x = a + 1j * b
        with_v, against = fundamental(x, t, w_e), abs(fundamental(x, t, -w_e))
        # the other channel negated is this fix negated (one sequence, 180 degrees off): the fix
        # is the one whose current lags the voltage by a motor's angle
        lag = current_lag(V, with_v, w_e)
        if abs(with_v) >= REVERSED_PROBE_RATIO * against and PHASE_ANGLE_WINDOW[0] <= lag <= PHASE_ANGLE_WINDOW[1]:
            raise DataError(rec.source, f"the currents ({icols}) hold both phase sequences (forward {fwd:.3g} A, "
                                        f"backward {bwd:.3g} A at the record's end), which no balanced motor "
                                        f"draws, and with {col} negated they hold one: is its probe reversed? "
                                        f"Negate the column {col}", column=col)


def _warn_generating(rec, angle: float, w_e: float, vcols: str, p: int | None) -> None:
    """A current lag beyond :data:`GENERATING_LAG` at the record's end: a warning, unless the
    speed shows the machine driven above synchronous speed (``p`` pole pairs)."""
    tail = _tail(rec)
    if rec.has_speed and p and float(np.mean(np.abs(rec.speed[tail]))) > w_e / p:
        return  # above synchronous speed: a generator returns power, as it should
    fix = ("name two of them v_rs, v_st (v_R - v_S, v_S - v_T)" if "v_r" in vcols else
           "give phase (line-to-neutral) voltages")
    warnings.warn(DataWarning.at(
        rec.source, f"the current lags the voltage by {angle:.0f} degrees at the record's end, so the machine "
                    f"returns power to the supply, which a motor below synchronous speed cannot do: are {vcols} "
                    f"line-to-line voltages (30 degrees ahead of the phase voltages)? Then {fix}",
        column=vcols), stacklevel=4)


def check_supply_frequency(rec, declared: float | None, meta_path) -> None:
    """``supply_frequency`` of meta.yaml (Hz) against the voltage phasor's rotation over the
    record's last fifth, where it is steady (the two halves of that fifth within
    :data:`FREQUENCY_TOLERANCE`: an inverter's V/f ramp cut short of its final frequency is not
    checked): beyond :data:`FREQUENCY_TOLERANCE` apart, a DataError naming the key (the
    conditioning and the diagnosis's folds are cut by it)."""
    measured = abs(electrical_speed(rec)) / (2.0 * math.pi)
    if not declared or not measured > 0 or abs(measured / declared - 1.0) <= FREQUENCY_TOLERANCE:
        return
    tail = np.arange(len(rec.t))[_tail(rec)]
    halves = [abs(phasor_speed(rec.v_alpha[k], rec.v_beta[k], rec.t[k])) for k in np.array_split(tail, 2)]
    if abs(halves[1] - halves[0]) > FREQUENCY_TOLERANCE * max(halves):
        return  # the supply's frequency still moves (a ramp): the record's end says nothing of the key
    raise DataError(meta_path, f"key 'supply_frequency' is {declared:g} Hz, but the voltages of {rec.source} turn "
                               f"at {measured:.4g} Hz at the record's end: state the supply's frequency "
                               f"(supply_frequency: {measured:.3g}) or leave the key out")


def check_speed_direction(rec, pole_pairs: int) -> None:
    """A rotor that ends turning against the supply's phase sequence at more than half the
    synchronous speed is a tachometer wired the other way round (a motor turns with its field):
    a DataError saying to negate the speed column."""
    if not rec.has_speed or not pole_pairs:
        return
    w_e = electrical_speed(rec)
    final = final_speed(rec)
    sync = abs(w_e) / pole_pairs
    if abs(w_e) > 0 and final * np.sign(w_e) < -0.5 * sync:
        raise DataError(rec.source, f"the rotor ends at {final:.4g} rad/s, against the supply's phase sequence "
                                    f"(synchronous {np.sign(w_e) * sync:+.4g} rad/s), which a motor does not do: "
                                    "is the tachometer wired the other way round? Negate the column speed (and "
                                    "the stop record's)", column="speed")


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
    tail = _tail(rec)
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
    tail = _tail(rec)
    t = rec.t[tail]
    w_e = electrical_speed(rec)
    i = rec.i_alpha[tail] + 1j * rec.i_beta[tail]
    icols = _columns(rec, "current")
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
        vcols = _columns(rec, "voltage")
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
        estimates = [synchronous_speed_estimate(r, p, float(np.median(np.diff(r.t))) if len(r.t) > 1 else 1.0)
                     for r in startups]
        w_sync = max(estimates) if estimates else 0.0
        basis = (f"estimated from the rotation of the currents (about {w_sync * p / (2 * np.pi):.3g} Hz) and "
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
        if round(k_times) >= 2 and abs(k_times / round(k_times) - 1.0) < 0.15:  # an integer multiple
            rpm_hint = (f"; at {round(k_times)} times it, is the speed electrical (divide it by pole_pairs {p}) or "
                        f"pole_pairs too large (then {p / round(k_times):g})?") + rpm_hint
        if strict:
            raise DataError(source, "impossible for a motor starting on that supply" + "; " + msg + rpm_hint
                            + " (or correct supply_frequency / pole_pairs)", column="speed", row=k + 1)
        warnings.warn(DataWarning.at(source, "looks like rpm, not rad/s: " + msg + rpm_hint
                                     + " (give supply_frequency in meta.yaml to make this an error)",
                                     column="speed", row=k + 1), stacklevel=3)


def check_records(startups, nameplate: dict | None, pole_pairs: int, input_hold: str, meta_path,
                  supply_frequency: float | None = None, stator_dc_resistance: float | None = None) -> None:
    """Every check above on every start-up record."""
    for rec in startups:
        check_supply_frequency(rec, supply_frequency, meta_path)
        check_phase_sequence(rec, pole_pairs)
        check_speed_direction(rec, pole_pairs)
        check_pole_pairs(rec, pole_pairs)
        check_scales(rec, nameplate, pole_pairs)
        check_stator_resistance(rec, stator_dc_resistance, meta_path)
        check_input_hold(rec, input_hold, meta_path)
