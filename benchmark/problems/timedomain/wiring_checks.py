"""Checks on load of a start-up record's wiring: phase labels swapped or rotated between the voltage and
the current channels, a current probe or a tachometer reversed, line-to-line voltages given as phase
voltages. Each says what is wrong and how to fix it in one line (part of
:func:`benchmark.problems.timedomain.load_checks.check_records`)."""

from __future__ import annotations

import math
import warnings

import numpy as np

from benchmark.core.errors import DataError, DataWarning
from benchmark.problems.timedomain.frames import clarke, fundamental, inverse_clarke, phasor_speed
from benchmark.problems.timedomain.load_checks import columns_of, electrical_speed, final_speed, steady_tail

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

def current_lag(v_phasor: complex, i_phasor: complex, w_e: float) -> float:
    """The angle (deg) by which the current phasor lags the voltage phasor, both taken at the
    supply's signed speed ``w_e`` (rad/s): positive for a motor's inductive current."""
    S = v_phasor * np.conj(i_phasor)
    return math.degrees(math.atan2(S.imag, S.real)) * float(np.sign(w_e))


def check_phase_sequence(rec, pole_pairs: int | None = None) -> None:
    """Voltage and current phasors must turn the same way and the current lag the voltage by a
    motor's angle; a DataError says which labels to change. A lag beyond :data:`GENERATING_LAG`
    below synchronous speed (``pole_pairs`` given) is a warning: line-to-line voltages?"""
    tail = steady_tail(rec)
    t = rec.t[tail]
    v = rec.v_alpha[tail] + 1j * rec.v_beta[tail]
    i = rec.i_alpha[tail] + 1j * rec.i_beta[tail]
    w_e = electrical_speed(rec)
    if not abs(w_e) > 0 or not np.any(np.abs(i) > 0):
        return
    fwd, bwd = abs(fundamental(i, t, abs(w_e))), abs(fundamental(i, t, -abs(w_e)))
    i_sign = 1.0 if fwd >= bwd else -1.0
    vcols, icols = columns_of(rec, "voltage"), columns_of(rec, "current")
    if max(fwd, bwd) < 3 * min(fwd, bwd):
        _check_reversed_probe(rec, v, i, t, w_e, icols, fwd, bwd)
        return  # no clear sequence in the currents (a record that ends stopped): nothing to compare
    if np.sign(w_e) != i_sign:
        swap = _sequence_fix(rec, i, t, vcols, icols, w_e, pole_pairs)
        raise DataError(rec.source, f"the voltage ({vcols}) and current ({icols}) phase sequences disagree: the "
                                    f"voltage phasor turns {'forwards' if w_e > 0 else 'backwards'}, the current "
                                    f"phasor {'forwards' if i_sign > 0 else 'backwards'}, so two phase labels are "
                                    f"swapped in one of them; {swap}",
                        column=icols if "currents are mislabelled" in swap else vcols)
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


def _sequence_fix(rec, i, t, vcols: str, icols: str, w_e: float, pole_pairs: int | None) -> str:
    """The relabelling that gives voltage and current one sequence with the current lagging by a
    motor's angle. A rotor that ends turning with the voltage (more than half the synchronous speed,
    ``pole_pairs`` given) says the voltage's labels are right: the fix is the current's (``i_r`` and
    ``i_s`` swapped, or one of them holding phase T's current, ``-(i_r + i_s)`` the one it lacks); one
    turning with the current says it is the voltage's. Without a speed either may be wrong: the voltage
    swaps (each of the three reverses the sequence; they differ by 120 degrees) are named, the one whose
    lag is nearest 45 degrees, with its current-column equivalent where there is one."""
    final = final_speed(rec) if rec.has_speed and pole_pairs else 0.0
    turning = np.sign(final) if abs(final) > 0.5 * abs(w_e) / max(pole_pairs or 1, 1) else 0.0
    tail = steady_tail(rec)
    if turning == np.sign(w_e):  # the rotor turns with the voltage: the currents are mislabelled
        if "i_r" not in icols:
            return "the rotor turns with the voltage, so the currents are mislabelled: negate i_beta"
        i_r, i_s, i_t = inverse_clarke(i.real, i.imag)
        v = rec.v_alpha[tail] + 1j * rec.v_beta[tail]
        fixes = {"swap the columns i_r and i_s": (i_s, i_r),
                 "i_s holds phase T's current: replace the column i_s by -(i_r + i_s)": (i_r, i_t),
                 "i_r holds phase T's current: replace the column i_r by -(i_r + i_s)": (i_t, i_s)}
        lags = {}
        for fix, (r, s_) in fixes.items():
            a, b = clarke(r, s_, -r - s_)
            lags[fix] = current_lag(fundamental(v, t, w_e), fundamental(a + 1j * b, t, w_e), w_e)
        fix, lag = min(lags.items(), key=lambda kv: abs(kv[1] - 45.0))
        return f"the rotor turns with the voltage, so the currents are mislabelled: {fix} (then the current lags " \
               f"the voltage by {lag:.0f} degrees)"
    if "v_r" not in vcols:
        return "negate v_beta" if turning else "negate v_beta (or i_beta)"
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
    if turning:
        fix = f"the rotor turns with the current, so the voltages are mislabelled: {fix}"
    elif (a, b) == ("v_r", "v_s") and "i_r" in icols:
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
    tail = steady_tail(rec)
    if rec.has_speed and p and float(np.mean(np.abs(rec.speed[tail]))) > w_e / p:
        return  # above synchronous speed: a generator returns power, as it should
    fix = ("name two of them v_rs, v_st (v_R - v_S, v_S - v_T)" if "v_r" in vcols else
           "give phase (line-to-neutral) voltages")
    warnings.warn(DataWarning.at(
        rec.source, f"the current lags the voltage by {angle:.0f} degrees at the record's end, so the machine "
                    f"returns power to the supply, which a motor below synchronous speed cannot do: are {vcols} "
                    f"line-to-line voltages (30 degrees ahead of the phase voltages)? Then {fix}",
        column=vcols), stacklevel=4)


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
