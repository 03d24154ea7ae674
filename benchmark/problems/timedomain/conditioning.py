"""Conditioning on load: what a bench record needs before the model may be fitted to it.

:func:`condition_dataset` runs :func:`benchmark.problems.timedomain.record_conditioning.condition_record`
on every start-up record (phase quantities recovered from alpha-beta; a three-wire record has no
zero sequence) and applies what it finds:

* switch-on: a pre-trigger (zero voltage before the contactor closes) is trimmed to a few
  samples, so the simulation starts from rest at zero voltage; contact bounce is kept (the
  model is fed the measured voltages);
* switching steps (measured voltages): the poles close, and their arcs end, between samples,
  and a linearly interpolated sampled step puts up to half a sample of volt-seconds too many
  or too few into the model, whose flux error lasts for the machine's time constants. The
  steps in the first 20 ms after the switch-on are found, the fraction of its sample each
  step falls in is estimated from the current's response
  (:func:`benchmark.problems.timedomain.switch_on.switching_steps`), the voltage
  sample before each step corrected so that the volt-seconds are the measured ones, and the
  current samples of the switching window (which the interpolation cannot follow within a
  sample) masked, with the count reported;
* sensor offsets: estimated from the pre-trigger, else from whole supply periods of the
  steady tail, and removed when they are significant: larger than
  :data:`OFFSET_SIGNIFICANCE` of the channel's amplitude (0.3 V on a 325 V phase, 9 mA on a
  9 A no-load current) and three of the estimate's own standard errors (coloured noise taken
  into account), so that clean and merely noisy records are left bit for bit as they are: a
  short pre-trigger of a probe whose zero drifts has a mean of a few tens of milliamperes that
  is noise, and removing it would put that bias into the whole record. Voltages computed from
  switch states (``input_hold: zoh``) are not measured and get no voltage offset;
* clipped (hard) or flattened (soft-saturated probe) current samples are masked:
  ``StartupRecord.weight`` is False there, with the count reported. The soft test looks for a
  third harmonic that flattens the peaks, which an inverter's six-step or PWM currents
  imitate (their 5th and 7th harmonics flatten peaks too): it runs on grid-fed records only;
* the speed's rest offset (pre-trigger) is removed, and its gain is checked against the
  synchronous speed at the end of an unloaded start (reported, never corrected).

Every step says what it did in ``StartupDataset.conditioning`` (lines for report.md). A data
set whose ``meta.yaml`` says ``conditioning: false`` is left as it is.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from benchmark.problems.timedomain.data import StartupDataset, StartupRecord
from benchmark.problems.timedomain.frames import clarke, inverse_clarke
from benchmark.problems.timedomain.record_conditioning import (
    SPEED_OFFSET_ROUNDING,
    condition_record,
    estimate_offsets,
    speed_offset_note,
)
from benchmark.problems.timedomain.switch_on import (
    SwitchingSteps,
    has_pretrigger,
    pretrigger_segment,
    sampled_volt_seconds,
    switching_steps,
)

#: Key of ``StartupRecord.removed`` holding the pre-trigger samples the offsets were measured on.
AT_REST = "sensor_offset_at_rest"
#: Key of ``StartupRecord.removed`` holding the offsets measured on the steady tail, removed or not,
#: pre-trigger or none (:func:`tail_offsets`, read back by :func:`offsets_left`).
MEASURED = "sensor_offset_measured"
#: The alpha-beta offset components, in the order of ``StartupRecord.removed["sensor_offset"]``.
OFFSET_COMPONENTS = ("v_alpha", "v_beta", "i_alpha", "i_beta")

#: An offset is removed only when it exceeds this fraction of its channel's amplitude.
OFFSET_SIGNIFICANCE = 1e-3
#: ... and this many of its own standard errors (the noise's own mean over the segment is no offset).
OFFSET_STANDARD_ERRORS = 3.0


def significant(value: float, standard_error: float, amplitude: float) -> bool:
    """An estimated offset is removed when it exceeds both :data:`OFFSET_SIGNIFICANCE` of the
    channel's amplitude and :data:`OFFSET_STANDARD_ERRORS` of its own standard error."""
    return abs(value) > max(OFFSET_SIGNIFICANCE * amplitude, OFFSET_STANDARD_ERRORS * standard_error)


#: Supply periods a switch-on's electrical start lasts (the flux build-up and the DC-offset
#: current peaks): a record no longer than that holds nothing settled to condition by (it is not
#: conditioned), and the diagnosis's first segment is that long (:mod:`.diagnosis.folds`).
ELECTRICAL_START_PERIODS = 3.0

#: A record whose supply period is shorter than 1/this many samples is not conditioned: its
#: switch-on, offsets and peaks cannot be told from the waveform (a frequency estimated from the
#: zero crossings of samples that alternate in sign is the sampling's, not a supply's).
MAX_PERIOD_FRACTION = 0.25


#: The tail is steady when the RMS current of its supply periods varies by less than this.
STEADY_TOLERANCE = 0.02


def steady_tail(i: np.ndarray, ts: float, f0: float, periods: int = 5) -> bool:
    """True when the RMS current of each of the last ``periods`` supply periods is within
    :data:`STEADY_TOLERANCE` of their mean (a start-up that has settled)."""
    m = int(round(1.0 / (f0 * ts)))
    n = i.shape[-1]
    if m < 4 or n < periods * m:
        return False
    tail = i[..., n - periods * m:].reshape(i.shape[0], periods, m)
    rms = np.sqrt(np.mean(tail**2, axis=(0, 2)))
    return bool(np.ptp(rms) <= STEADY_TOLERANCE * np.mean(rms))


def condition_dataset(ds: StartupDataset) -> StartupDataset:
    """The data set with every start-up record conditioned (see the module docstring)."""
    records, lines, removed, speed_offsets = [], [], [], []
    for k, rec in enumerate(ds.startups):
        name = f"startup record {k + 1}" if len(ds.startups) > 1 else "start-up record"
        new, said, found, speed_offset = condition_startup(
            rec, ds.sample_time, ds.pole_pairs, ds.supply_frequency, measured_voltage=ds.input_hold != "zoh",
            continuous_voltage=ds.input_hold == "linear" and not ds.chord_voltage)
        records.append(new)
        lines += [f"{name}: {s}" for s in said]
        removed += [e for e in found if e not in removed]
        speed_offsets.append(speed_offset)
    stops = list(ds.stops)
    if stops and len(speed_offsets) == 1 and speed_offsets[0] != 0.0:
        # the same tachometer records the free stop: its rest offset is there too
        stops = [replace(st, speed=np.asarray(st.speed, float) - speed_offsets[0]) for st in stops]
        if abs(speed_offsets[0]) >= SPEED_OFFSET_ROUNDING:  # else a speed that reads zero at rest
            lines.append(f"stop record: the start-up's speed offset {speed_offsets[0]:+.4g} rad/s removed "
                         "(same sensor)")
    # restored samples are what the model's linear interpolation must see: written back, they
    # are not restored a second time
    return replace(ds, startups=records, stops=stops, conditioning=list(ds.conditioning) + lines,
                   conditioning_removed=list(ds.conditioning_removed) + removed,
                   chord_voltage=ds.chord_voltage or ds.input_hold == "linear")


def condition_startup(rec: StartupRecord, ts: float, pole_pairs: int, supply_frequency: float | None,
                      measured_voltage: bool = True, continuous_voltage: bool = False,
                      ) -> tuple[StartupRecord, list[str], list[str], float]:
    """One record conditioned, what was done (plain-English lines), the effects it found and
    removed (``sensor_offset``: offsets removed; ``current_sensor_saturation``: clipped or
    flattened current samples masked; the switching window's masked samples are no effect), and
    the speed sensor's rest offset it removed (rad/s; 0 when none).

    ``continuous_voltage``: the voltages are samples of a continuous voltage (``input_hold:
    linear`` without ``chord_voltage``): the volt-seconds the model's linear interpolation loses
    between samples are restored from the supply's switch-on (after its switching steps) on, or
    over the whole record when it starts energised."""
    n = len(rec.t)
    v = np.vstack(inverse_clarke(rec.v_alpha, rec.v_beta))
    i_r, i_s, _ = inverse_clarke(rec.i_alpha, rec.i_beta)
    i = np.vstack([i_r, i_s])
    if not np.any(v) or n < 16:
        return rec, ["not conditioned: no voltage or too few samples"], [], 0.0
    speed = rec.speed if rec.has_speed else None
    with np.errstate(all="ignore"):
        try:
            cond, report = condition_record(v, i, ts, speed, f0=supply_frequency, p=pole_pairs,
                                            soft=measured_voltage)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError, IndexError) as exc:
            return rec, [f"not conditioned ({type(exc).__name__}: {exc})"], [], 0.0
    if not np.isfinite(report.f0) or report.f0 <= 0 or n * ts * report.f0 < ELECTRICAL_START_PERIODS:
        return rec, [f"not conditioned: fewer than {ELECTRICAL_START_PERIODS:g} supply periods"], [], 0.0
    if report.f0 * ts > MAX_PERIOD_FRACTION:  # a supply the sampling does not resolve: nothing to trim by
        return rec, [f"not conditioned: a supply of {report.f0:.4g} Hz has fewer than {1 / MAX_PERIOD_FRACTION:.0f} "
                     f"samples per period"], [], 0.0
    said = [f"supply frequency {report.f0:.3f} Hz ({report.f0_source})"]
    first = cond.first
    if report.switch_on is not None:
        said.append(f"switch-on at t = {report.switch_on * ts:.4f} s: {first} pre-trigger samples trimmed "
                    f"({report.n_kept_before} kept before it; contact bounce kept)")
    else:
        said.append("no pre-trigger: the record starts energised")
    said.extend(report.notes)
    removed, kept = [], []
    offsets = {name: (value, unit, how, se) for name, value, unit, how, se in report.offsets}
    from_tail = not has_pretrigger(report.switch_on)  # the offsets came from the steady tail
    steady = steady_tail(i, ts, report.f0)
    if from_tail and not steady:
        said.append("sensor offsets not estimated: no pre-trigger and the record does not reach a steady state "
                    "(its last supply periods still change)")
        offsets = {name: (0.0, unit, how, se) for name, (value, unit, how, se) in offsets.items()}
    v_out, i_out = v.copy(), i.copy()
    at_rest = {}  # channel -> its pre-trigger samples (None: the offset came from the steady tail)
    for row, name in enumerate(("v_r", "v_s", "v_t")):
        value, unit, how, se = offsets[name]
        amplitude = np.sqrt(2.0) * np.std(v[row, n // 2:])
        if measured_voltage and significant(value, se, amplitude):
            v_out[row] -= value
            removed.append(f"{name} {value:+.2f} V ({how.split(' over ')[0]})")
            at_rest[name] = pretrigger_segment(v[row], report.switch_on)
        else:
            kept.append(f"{name} {value:+.3g} +- {se:.2g} V")
    for row, name in enumerate(("i_r", "i_s")):
        value, unit, how, se = offsets[name]
        amplitude = np.sqrt(2.0) * np.std(i[row, n // 2:])
        if significant(value, se, amplitude):
            i_out[row] -= value
            removed.append(f"{name} {value:+.3f} A ({how.split(' over ')[0]})")
            at_rest[name] = pretrigger_segment(i[row], report.switch_on)
        else:
            kept.append(f"{name} {value:+.3g} +- {se:.2g} A")
    if removed:
        said.append("offsets removed: " + ", ".join(removed))
    elif "sensor offsets not estimated" not in said[-1]:
        said.append("no significant sensor offset")
    if kept and removed:
        said.append("offsets below significance left in place: " + ", ".join(kept))
    weight = cond.weight.all(axis=0)  # already trimmed: (m,) from the first kept sample
    n_masked = int((~weight).sum())
    if n_masked:
        said.append(f"{n_masked} current samples masked: {sum(report.n_clipped)} hard-clipped, "
                    f"{sum(report.n_saturated)} on flattened (soft-saturated) peaks")
    found = (["sensor_offset"] if removed else []) + (["current_sensor_saturation"] if n_masked else [])
    put_back = {}  # what was removed, for the diagnosis's check of each removal (:func:`restored`)
    if removed:
        d_v, d_i = v - v_out, i - i_out
        put_back["sensor_offset"] = (*clarke(d_v[0, 0], d_v[1, 0], d_v[2, 0]),
                                     *clarke(d_i[0, 0], d_i[1, 0], -d_i[0, 0] - d_i[1, 0]))
        at_rest = {k: x.copy() for k, x in at_rest.items() if x is not None}
        if at_rest:  # the pre-trigger the offsets were measured on: the diagnosis checks them there
            put_back[AT_REST] = at_rest
    if n_masked:
        put_back["current_sensor_saturation"] = ~weight
    measured = tail_offsets(v, i, ts, report.f0, cond.weight, measured_voltage) if steady else None
    if measured is not None:
        put_back[MEASURED] = measured
    speed_out, speed_offset = rec.speed, 0.0
    if speed is not None and np.isfinite(report.speed_offset):
        speed_out, speed_offset = rec.speed - report.speed_offset, float(report.speed_offset)
        said.append(speed_offset_note(report.speed_offset))
    if report.speed_check is not None:
        said.append(report.speed_check.line())
    steps = None
    if measured_voltage and report.switch_on is not None:
        v_a, v_b = clarke(v_out[0], v_out[1], v_out[2])
        i_a, i_b = clarke(i_out[0], i_out[1], -i_out[0] - i_out[1])
        steps = switching_steps(v_a[first:], v_b[first:], i_a[first:], i_b[first:], report.switch_on - first, ts)
        if steps.steps:
            said.append(switching_line(steps, ts, int((steps.mask & weight).sum())))
            weight = weight & ~steps.mask
        else:
            steps = None
    n_masked = int((~weight).sum())
    continuous = continuous_voltage or steps is not None  # a measured switch-on: a continuous supply
    if (first == 0 and not removed and not n_masked and speed_out is rec.speed and steps is None
            and not continuous):
        return (rec if not put_back else replace(rec, removed=put_back)), said, found, speed_offset
    v_a, v_b = clarke(v_out[0], v_out[1], v_out[2])
    i_a, i_b = clarke(i_out[0], i_out[1], -i_out[0] - i_out[1])
    sl = slice(first, n)
    v_a, v_b = (v_a[sl], v_b[sl]) if steps is None else (steps.v_a, steps.v_b)
    if continuous:
        if steps is not None:
            after = steps.steps[-1] + 2
        elif report.switch_on is not None:
            after = report.switch_on - first + 2
        else:
            after = 1
        v_a, v_b = sampled_volt_seconds(v_a, after), sampled_volt_seconds(v_b, after)
        in_file = (f" of the trimmed record ({rec.t[min(after + first, n - 1)]:.4f} s after the file's first sample)"
                   if first else "")
        said.append(f"measured supply voltages from t = {after * ts:.4f} s{in_file} on: the volt-seconds the linear "
                    "interpolation loses between samples of a continuous voltage restored (second difference / 12)")
    return StartupRecord(
        t=rec.t[sl] - rec.t[first], v_alpha=v_a, v_beta=v_b, i_alpha=i_a[sl], i_beta=i_b[sl],
        speed=speed_out[sl], source=rec.source, torque=None if rec.torque is None else rec.torque[sl],
        weight=None if not n_masked else weight,
        switch_on_sample=None if steps is None else steps.steps[-1] + 1,
        removed=put_back or None, columns=rec.columns,
    ), said, found, speed_offset


def tail_offsets(v: np.ndarray, i: np.ndarray, ts: float, f0: float, weight: np.ndarray,
                 measured_voltage: bool) -> dict[str, tuple[float, float]] | None:
    """Each channel's offset measured on the steady tail (:func:`~benchmark.problems.timedomain.
    record_conditioning.estimate_offsets` without a pre-trigger: after the start, where a probe's
    remanence from the inrush is in it too) as alpha-beta components (:data:`OFFSET_COMPONENTS`,
    V and A) -> (value, standard error), the phases' errors taken as independent. ``v`` (3, n),
    ``i`` (2, n) phase channels; ``weight`` (2, m) the currents' kept samples from the end; the
    voltages only when measured (``measured_voltage``); the tail must be steady
    (:func:`steady_tail`, the caller's test). None when it is too short."""
    mask = np.zeros(i.shape, bool)
    mask[:, i.shape[1] - weight.shape[1]:] = ~weight
    channels = [("v", v, (None,) * 3, clarke)] if measured_voltage else []
    channels.append(("i", i, mask, lambda r, s: clarke(r, s, -r - s)))  # three wires: i_t = -i_r - i_s
    out = {}
    for kind, x, m, to_ab in channels:
        try:
            found = [estimate_offsets(row, ts, None, f0, mask=mk) for row, mk in zip(x, m, strict=True)]
        except (ValueError, np.linalg.LinAlgError):
            continue
        values = to_ab(*(value for value, _, _ in found))
        gains = np.array([to_ab(*unit) for unit in np.eye(len(found))])  # (phase, alpha/beta)
        ses = np.sqrt(np.array([se for _, _, se in found]) ** 2 @ gains**2)
        for j, part in enumerate(("alpha", "beta")):
            out[f"{kind}_{part}"] = (float(values[j]), float(ses[j]))
    return out or None


def offsets_left(ds: StartupDataset) -> dict[str, tuple[float, float]]:
    """The offsets the conditioning measured on the records' steady tails and left in ``ds``
    (measured less removed): alpha-beta component (:data:`OFFSET_COMPONENTS`) -> (value, standard
    error), V and A, pooled over the records by inverse variance; empty where no record has a
    steady tail. What a fitted ``sensor_offset`` is checked against
    (:meth:`benchmark.problems.timedomain.offset_effect.SensorOffset.contradicted`)."""
    pooled = {}
    for rec in ds.startups:
        removed = rec.removed or {}
        taken = dict(zip(OFFSET_COMPONENTS, removed.get("sensor_offset", (0.0,) * 4), strict=True))
        for name, (value, se) in (removed.get(MEASURED) or {}).items():
            if se > 0 and np.isfinite(value):
                pooled.setdefault(name, []).append((value - float(taken[name]), se))
    out = {}
    for name, rows in pooled.items():
        w = np.array([1.0 / se**2 for _, se in rows])
        out[name] = (float(np.sum(w * [v for v, _ in rows]) / np.sum(w)), float(1.0 / np.sqrt(np.sum(w))))
    return out


def restored(ds: StartupDataset, effect: str) -> StartupDataset:
    """``ds`` with the conditioning's removal of ``effect`` (``sensor_offset``: the offsets are
    added back; ``current_sensor_saturation``: the flattened or clipped samples count again) put
    back on every record: the data the diagnosis compares with when it checks whether the removal
    earns its place (:mod:`benchmark.problems.timedomain.diagnosis.conditioning_check`)."""
    records = []
    for rec in ds.startups:
        undo = (rec.removed or {}).get(effect)
        if undo is not None:
            rest = {k: v for k, v in rec.removed.items() if k not in (effect, f"{effect}_at_rest")} or None
            if effect == "sensor_offset":
                d_va, d_vb, d_ia, d_ib = (float(x) for x in undo)
                rec = replace(rec, v_alpha=rec.v_alpha + d_va, v_beta=rec.v_beta + d_vb,
                              i_alpha=rec.i_alpha + d_ia, i_beta=rec.i_beta + d_ib, removed=rest)
            else:
                weight = np.asarray(rec.weight, bool) | undo
                rec = replace(rec, weight=None if weight.all() else weight, removed=rest)
        records.append(rec)
    return replace(ds, startups=records, conditioning_removed=[e for e in ds.conditioning_removed if e != effect])


def switching_line(steps: SwitchingSteps, ts: float, n_masked: int) -> str:
    """The report line of the switching steps of a switch-on."""
    k1, k2 = steps.steps[0], steps.steps[-1]
    span = 1e3 * (k2 + 1 - k1) * ts
    where = (f"{len(steps.steps)} voltage steps between samples in the switch-on's first {span:.3g} ms "
             "(contactor poles closing, arcs ending)")
    if steps.inductance is None:
        how = "their volt-seconds could not be estimated from the current (left as sampled)"
    else:
        how = (f"their volt-seconds corrected from the current's response (the steps' samples fitted with an "
               f"inductance of {1e3 * steps.inductance:.4g} mH, a local fit, not the machine's leakage; fractions of "
               "the sample after the step "
               + ", ".join(f"{f:.2f}" for f in steps.fractions) + ")")
    return f"{where}: {how}; {n_masked} current samples of the switching window masked"
