"""Conditioning of measured motor-start bench records before identification.

A measured start record (three phase voltages ``v_r, v_s, v_t`` in V, phase currents ``i_r,
i_s`` in A with ``i_t = -i_r - i_s``, optionally a mechanical speed in rad/s, sample time
``ts`` in s) differs from a simulated one in ways the model must not be asked to explain:

* it starts before switch-on (zero voltage, sensor offsets visible), and the switch-on has
  contact bounce (about 1 ms) and a supply dip of a few per cent;
* voltage channels carry DC offsets of a few volts, current channels tenths of an ampere;
* current probes saturate softly at the high starting current (flat-topped peaks) or clip hard
  at the acquisition range;
* a tachometer has an unknown gain, ripple and an offset (or there is no speed sensor).

Pure functions (arrays in, arrays and frozen dataclasses out) and one driver,
:func:`condition_record`, which returns the conditioned arrays and a
:class:`ConditioningReport` whose :meth:`~ConditioningReport.lines` are plain English.
numpy and scipy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from benchmark.problems.timedomain.probe_clipping import detect_clipping
from benchmark.problems.timedomain.switch_on import PRETRIGGER_GUARD, find_pretrigger, pretrigger_segment


def estimate_frequency(x, ts: float, tail_s: float | None = None) -> float:
    """Supply frequency (Hz) from the rising zero crossings of a steady tail.

    The tail (last ``tail_s`` s, default the last half of the record) is mean-removed;
    crossings need a hysteresis of 10 % of its std (noise does not make extra crossings) and
    are located by linear interpolation. An offset or harmonics shift every crossing of a
    steady wave alike, so the period is unbiased; with 0.5 V of noise on 325 V, 25 periods
    give about 1e-3 Hz.
    """
    x = np.asarray(x, dtype=float).ravel()
    n = len(x) // 2 if tail_s is None else min(len(x), int(round(tail_s / ts)))
    y = x[len(x) - n:] - np.mean(x[len(x) - n:])
    h = 0.1 * np.std(y)
    state = np.where(y > h, 1, np.where(y < -h, -1, 0))
    idx = np.flatnonzero(state)
    if len(idx) < 2:
        raise ValueError("estimate_frequency: the tail holds no oscillation")
    filled = state[idx]
    rise = idx[1:][(filled[:-1] < 0) & (filled[1:] > 0)]
    if len(rise) < 2:
        raise ValueError("estimate_frequency: fewer than two periods in the tail")
    last_neg = np.maximum.accumulate(np.where(y <= 0, np.arange(n), 0))[rise]
    frac = -y[last_neg] / (y[last_neg + 1] - y[last_neg])
    tc = (last_neg + frac) * ts
    return float((len(tc) - 1) / (tc[-1] - tc[0]))


def _tail_fit_offset(x, ts, f0, n_harmonics, mask):
    """Constant of a least-squares fit of ``c + sum_h (a_h + a'_h t) cos + (b_h + b'_h t) sin``
    (harmonics of f0, each with a linear envelope: it absorbs a slowly changing amplitude and a
    small frequency error) over ``x``; rows where ``mask`` is True are left out."""
    n = len(x)
    t = np.arange(n) * ts
    tc = np.linspace(-1.0, 1.0, n)
    cols = [np.ones(n)]
    for h in range(1, n_harmonics + 1):
        if h * f0 >= 0.45 / ts:
            break
        c, s = np.cos(2 * np.pi * h * f0 * t), np.sin(2 * np.pi * h * f0 * t)
        cols += [c, s, tc * c, tc * s]
    A = np.column_stack(cols)
    keep = ~mask if mask is not None else np.ones(n, bool)
    if int(np.count_nonzero(keep)) <= A.shape[1]:
        raise ValueError(f"estimate_offsets: {int(np.count_nonzero(keep))} unmasked samples in the tail, "
                         f"too few for its fit's {A.shape[1]} coefficients")
    coef = np.linalg.lstsq(A[keep], x[keep], rcond=None)[0]
    return float(coef[0]), x[keep] - A[keep] @ coef


def long_run_std(e: np.ndarray, n_blocks: int = 20) -> float:
    """Square root of the long-run variance of noise ``e`` (``sigma^2 g(0)``, what sets the
    spread of a mean: ``std(mean of N) = long_run_std / sqrt(N)``), by batch means: the
    variance of the means of ``n_blocks`` consecutive blocks times the block length. Unlike an
    AR(1) fit it does not need the noise's spectrum to have one pole: a probe's slowly drifting
    zero under white noise has a small lag-one correlation and a long-run variance a hundred
    times its white part."""
    e = np.asarray(e, float)
    e = e - np.mean(e)
    L = len(e) // n_blocks
    if L < 1:
        return math.inf
    means = e[:n_blocks * L].reshape(n_blocks, L).mean(axis=1)
    return float(max(math.sqrt(L * np.var(means, ddof=1)), np.std(e)))


#: A speed's rest offset below this (rad/s) is the rounding of a speed that reads zero at rest.
SPEED_OFFSET_ROUNDING = 1e-9


def speed_offset_note(offset: float) -> str:
    """The report's line for the speed's rest offset (rad/s) removed: a speed at rest whose mean is
    rounding (below :data:`SPEED_OFFSET_ROUNDING`) has none to speak of."""
    if abs(offset) < SPEED_OFFSET_ROUNDING:
        return "speed at rest before switch-on reads zero: no offset"
    return f"speed offset {offset:+.4g} rad/s (rest before switch-on) removed"


def estimate_offsets(x, ts: float, pretrigger_end: int | None, f0: float | None, *,
                     tail_s: float | None = None, n_harmonics: int = 7, guard: int = PRETRIGGER_GUARD,
                     mask=None, f0_from=None) -> tuple[float, str, float]:
    """DC offset of one channel (units of ``x``), how it was found, and its standard error:
    :func:`long_run_std` over the square root of the samples averaged, the long-run spread
    taken from the steady tail's residual where there is one (a pre-trigger of a few ms is too
    short to show a slow drift, which it cannot tell from an offset) and from the segment itself.

    * pre-trigger (``pretrigger_end - guard >= MIN_PRETRIGGER`` samples, 50): their mean. The channel is truly
      zero there (motor at rest, supply off); accuracy ``long_run_std / sqrt(N)`` (0.02 V for
      0.5 V white noise and 500 samples). A drift between pre-trigger and run is not seen.
    * else the steady tail (last ``tail_s`` s, default the last third, trimmed to a whole
      number of periods of f0): the constant of a least-squares fit of the harmonics of f0
      with linear envelopes (a grid or inverter supply, and the currents of a machine at steady
      speed, have no DC over whole periods; the envelope terms absorb the last of a
      start-up's decay and a frequency error of a few 1e-3). Same accuracy with N the tail
      length (0.007 V for 5000 samples of white noise); a non-periodic remnant (an unfinished start,
      interharmonics) leaks in. ``f0`` (Hz) is estimated from the zero crossings of
      ``f0_from`` (default ``x``) when None.

    ``mask`` : samples to leave out (clipped samples).
    """
    x = np.asarray(x, dtype=float).ravel()
    mask = None if mask is None else np.asarray(mask, bool)
    seg = pretrigger_segment(x, pretrigger_end, guard)
    if seg is not None:
        if mask is not None:
            seg = seg[~mask[:pretrigger_end - guard]]
        spread = long_run_std(seg)
        try:
            spread = max(spread, long_run_std(_tail(x, ts, f0, tail_s, n_harmonics, mask, f0_from)[2]))
        except (ValueError, np.linalg.LinAlgError):
            pass
        return float(np.mean(seg)), f"pre-trigger mean over {len(seg)} samples", spread / math.sqrt(len(seg))
    off, n_per, e, f0 = _tail(x, ts, f0, tail_s, n_harmonics, mask, f0_from)
    return off, f"steady-tail fit over {n_per} periods of {f0:.2f} Hz", long_run_std(e) / math.sqrt(len(e))


def _tail(x, ts, f0, tail_s, n_harmonics, mask, f0_from):
    """The steady tail's offset fit: (offset, whole periods used, residual, f0)."""
    n = len(x) // 3 if tail_s is None else min(len(x), int(round(tail_s / ts)))
    if f0 is None:
        f0 = estimate_frequency(x if f0_from is None else f0_from, ts, n * ts)
    n_per = math.floor(n * ts * f0)
    if n_per < 2:
        raise ValueError(f"estimate_offsets: the tail of {n * ts:.3g} s holds fewer than two periods of {f0:.4g} Hz")
    n = min(len(x), int(round(n_per / (f0 * ts))))
    off, e = _tail_fit_offset(x[len(x) - n:], ts, f0, n_harmonics, None if mask is None else mask[len(x) - n:])
    return off, n_per, e, f0


@dataclass(frozen=True)
class SpeedCheck:
    """Plausibility of the speed channel at the end of an unloaded start.

    end_speed : mean speed over the tail, pre-trigger offset removed (rad/s).
    synchronous : ``2 pi f0 / p`` (rad/s).  ratio : end_speed / synchronous.
    offset : speed reading at rest (rad/s), nan when there is no rest segment.
    still_accelerating, gain_suspected, offset_suspected : flags.  verdict : plain English.
    tail_s : the tail's length (s) whose mean ``end_speed`` is.
    """

    end_speed: float
    synchronous: float
    ratio: float
    offset: float
    still_accelerating: bool
    gain_suspected: bool
    offset_suspected: bool
    verdict: str
    tail_s: float = 0.1

    def line(self) -> str:
        rpm = self.end_speed * 30 / math.pi
        return (f"speed over the last {self.tail_s:.3g} s {rpm:.1f} rpm on average = {self.ratio:.4f} of synchronous: "
                f"{self.verdict}")


def check_speed_gain(speed, ts: float, f0: float, p: int, tail_s: float = 0.1, *, rest_end: int | None = None,
                     max_slip: float = 0.03, tol: float = 0.002, offset_tol: float = 0.005) -> SpeedCheck:
    """Check a speed channel (rad/s) against synchronous speed ``2 pi f0 / p``.

    At the end of an unloaded start the rotor sits just below synchronous speed (slip 0 to
    ``max_slip``). A ratio above ``1 + tol`` is impossible for a motor: a gain error (or a
    wrong ``p``/``f0``); below ``1 - max_slip`` with the speed no longer rising: a gain error,
    an offset or a load. ``rest_end``: samples before switch-on (rotor at rest): their mean is
    the tachometer offset (suspected when above ``offset_tol`` of synchronous) and is removed
    before the ratio. The tail is the last ``tail_s`` s; "still accelerating" when the speed
    rises by more than 0.5 % of synchronous over it. The gain implied by a slip in
    ``[0, max_slip]`` is ``ratio`` to ``ratio / (1 - max_slip)``.
    """
    w = np.asarray(speed, dtype=float).ravel()
    sync = 2 * np.pi * f0 / p
    offset = float(np.mean(w[:rest_end])) if rest_end is not None and rest_end >= 10 else math.nan
    n = max(2, min(len(w), int(round(tail_s / ts))))
    tail = w[-n:] - (offset if np.isfinite(offset) else 0.0)
    end = float(np.mean(tail))
    rise = float(np.polyfit(np.arange(n) * ts, tail, 1)[0]) * n * ts / sync
    ratio = end / sync
    accel = rise > 0.005
    off_s = bool(np.isfinite(offset) and abs(offset) > offset_tol * sync)
    gain = False
    implied = f"implied gain {ratio:.4f} to {ratio / (1 - max_slip):.4f}"
    if ratio < 0:
        verdict, gain = "negative: sign or phase sequence reversed", True
    elif ratio > 1 + tol:
        verdict, gain = f"above synchronous, impossible for a motor: gain error ({implied}) or wrong p/f0", True
    elif ratio >= 1 - max_slip:
        verdict = "plausible"
    elif accel:
        verdict = "still accelerating: the start is not finished, the gain cannot be checked"
    else:
        verdict, gain = f"slip above {100 * max_slip:.0f} %: gain error ({implied}), offset or load", True
    for q in (0.5, 2.0, 3.0, 1 / 3):
        if abs(ratio / q - 1) < max_slip + tol:
            verdict += f" (ratio near {q:.3g}: check the pole-pair number p = {p})"
    if off_s:
        verdict += f"; tachometer offset {offset:+.3g} rad/s at rest"
    return SpeedCheck(end, sync, ratio, offset, accel, gain, off_s, verdict, n * ts)


@dataclass(frozen=True, eq=False)  # holds arrays: compare fields explicitly
class ConditionedRecord:
    """Conditioned record: ``v`` (3, m) V and ``i`` (2, m) A offsets removed, ``speed`` (m,)
    rad/s or None, ``weight`` (2, m) bool (False = clipped current sample, leave it out of the
    residual; ``i_t = -i_r - i_s`` is untrustworthy where either is False), ``first``: index of
    the first kept sample in the input record, ``ts``: sample time (s)."""

    v: np.ndarray
    i: np.ndarray
    speed: np.ndarray | None
    weight: np.ndarray
    first: int
    ts: float


@dataclass(frozen=True)
class ConditioningReport:
    """What :func:`condition_record` did (all numbers in SI units unless named)."""

    ts: float
    f0: float
    f0_source: str
    switch_on: int | None
    n_trimmed: int
    n_kept_before: int
    offsets: tuple  # ((channel, value, unit, method, standard_error), ...)
    n_clipped: tuple  # hard-clipped samples per current channel
    clip_levels: tuple  # ((low, high) or None per current channel), raw units
    n_saturated: tuple  # further samples of soft-saturated peaks per current channel
    speed_offset: float
    speed_check: SpeedCheck | None
    notes: tuple = ()

    def lines(self) -> list[str]:
        """Plain-English report lines."""
        out = [f"supply frequency {self.f0:.3f} Hz ({self.f0_source})"]
        if self.switch_on is None:
            out.append("no switch-on found: the record starts energised, nothing trimmed")
        else:
            out.append(f"switch-on at t = {self.switch_on * self.ts:.4f} s: {self.n_trimmed} pre-trigger samples "
                       f"trimmed ({self.n_kept_before} kept before it, bounce kept)")
        parts = [f"{c} {val:+.{2 if u == 'V' else 3}f} {u} ({m.split(' over ')[0]})"
                 for c, val, u, m, _ in self.offsets]
        out.append("offsets removed: " + ", ".join(parts))
        total = sum(self.n_clipped)
        if total:
            lv = [abs(x) for lev in self.clip_levels if lev for x in lev if np.isfinite(x)]
            per = ", ".join(f"i_{c} {k}" for c, k in zip("rs", self.n_clipped, strict=True))
            out.append(f"{total} current samples clipped at +-{max(lv):.1f} A masked ({per})")
        else:
            out.append("no clipped current samples")
        if sum(self.n_saturated):
            per = ", ".join(f"i_{c} {k}" for c, k in zip("rs", self.n_saturated, strict=True))
            out.append(f"{sum(self.n_saturated)} current samples of soft-saturated (flattened) peaks masked ({per})")
        if np.isfinite(self.speed_offset):
            out.append(speed_offset_note(self.speed_offset))
        if self.speed_check is not None:
            out.append(self.speed_check.line())
        return out + list(self.notes)


def condition_record(v, i, ts: float, speed=None, *, f0: float | None = None, p: int | None = None,
                     keep_before: int = 10, tail_s: float | None = None, clip_rel_tol: float = 1e-3,
                     soft: bool = True, speed_tail_s: float = 0.1) -> tuple[ConditionedRecord, ConditioningReport]:
    """Condition a measured start record for identification.

    Steps: supply frequency (``f0`` Hz, or :func:`estimate_frequency` on ``v_r``); switch-on
    (:func:`detect_switch_on`); clipped current samples (:func:`detect_clipping` on the raw
    currents, soft saturation too when ``soft``); offsets of every voltage and current channel
    (:func:`estimate_offsets`, clipped samples left out) removed; the pre-trigger trimmed but
    ``keep_before`` samples (the simulation starts from rest at zero voltage); the speed's
    rest offset removed and :func:`check_speed_gain` run when ``p`` is given. The speed's gain
    is reported, never corrected.

    Parameters
    ----------
    v : (3, n) phase voltages in V.  i : (2, n) currents ``i_r, i_s`` in A.  ts : sample time (s).
    speed : (n,) mechanical speed in rad/s, or None.  p : pole pairs.

    Returns
    -------
    (ConditionedRecord, ConditioningReport)
    """
    v = np.asarray(v, dtype=float)
    i = np.asarray(i, dtype=float)
    if v.ndim != 2 or v.shape[0] != 3 or i.ndim != 2 or i.shape[0] != 2 or i.shape[1] != v.shape[1]:
        raise ValueError(f"need v (3, n) and i (2, n), got {v.shape} and {i.shape}")
    n = v.shape[1]
    notes = []
    if f0 is None:
        f0, f0_source = estimate_frequency(v[0], ts, tail_s), "from zero crossings of v_r"
    else:
        f0_source = "given"
    k_on, said = find_pretrigger(v, i, ts)
    notes.extend(said)
    hard = [detect_clipping(x, clip_rel_tol) for x in i]
    masks = [detect_clipping(x, clip_rel_tol, ts=ts, f0=f0, start=k_on or 0) if soft else h
             for x, h in zip(i, hard, strict=True)]
    offsets, vc, ic = [], np.empty_like(v), np.empty_like(i)
    for name, x, out in zip(("v_r", "v_s", "v_t"), v, vc, strict=True):
        off, how, se = estimate_offsets(x, ts, k_on, f0, tail_s=tail_s)
        out[:] = x - off
        offsets.append((name, off, "V", how, se))
    levels = []
    for name, x, m, h, out in zip(("i_r", "i_s"), i, masks, hard, ic, strict=True):
        off, how, se = estimate_offsets(x, ts, k_on, f0, tail_s=tail_s, mask=m)
        out[:] = x - off
        offsets.append((name, off, "A", how, se))
        levels.append((float(x[h].min()), float(x[h].max())) if h.any() else None)
    sp, sp_off, check = None, math.nan, None
    if speed is not None:
        sp = np.asarray(speed, dtype=float).ravel().copy()
        rest = k_on if k_on is not None and k_on >= 10 else None
        if rest is not None:
            sp_off = float(np.mean(sp[:rest]))
            sp -= sp_off
        if p is not None:
            check = check_speed_gain(speed, ts, f0, p, speed_tail_s, rest_end=rest)
        else:
            notes.append("speed check skipped: no pole-pair number p")
    first = 0 if k_on is None else max(k_on - keep_before, 0)
    kept = 0 if k_on is None else k_on - first
    rec = ConditionedRecord(vc[:, first:], ic[:, first:], None if sp is None else sp[first:],
                            ~np.vstack(masks)[:, first:], first, ts)
    if n - first < 2:
        notes.append("warning: almost nothing left after trimming")
    report = ConditioningReport(ts, float(f0), f0_source, k_on, first, kept, tuple(offsets),
                                tuple(int(h.sum()) for h in hard), tuple(levels),
                                tuple(int((m & ~h).sum()) for m, h in zip(masks, hard, strict=True)),
                                sp_off, check, tuple(notes))
    return rec, report

