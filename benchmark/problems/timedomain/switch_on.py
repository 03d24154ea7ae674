"""The switch-on of a start record: where it is, and what sampling a switching transient loses.

* :func:`detect_switch_on`: the first contact of the first sustained energisation;
  :func:`current_departure`: whether the currents are at rest before it (else the voltage
  was live, if low, from the start: no pre-trigger); :func:`find_pretrigger`: the two together,
  the one pre-trigger of a record that the conditioning and the noise estimate both read
  (:func:`pretrigger_segment`: its samples, at least :data:`MIN_PRETRIGGER` of them).

* :func:`switching_steps`: voltage steps between two samples (contactor poles closing, arcs
  ending) put volt-seconds the model's interpolation between samples gets wrong; they are
  estimated from the current's response and corrected, and the switching window's current
  samples are masked.
* :func:`sampled_volt_seconds`: a sampled continuous (sine) voltage, interpolated linearly
  between samples, loses about ``(w Ts)^2 / 12`` of its volt-seconds; the samples are corrected
  by their second difference / 12.

Used by :mod:`benchmark.problems.timedomain.conditioning` after
:func:`benchmark.problems.timedomain.record_conditioning.condition_record`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def _magnitude(v: np.ndarray) -> np.ndarray:
    """Space-vector magnitude ``sqrt(2/3 sum v_k^2)`` of three phase voltages (V): the phase
    peak voltage for a balanced sine supply, without the zero crossings of a single phase."""
    v = np.asarray(v, dtype=float)
    if v.ndim != 2 or v.shape[0] != 3:
        raise ValueError(f"phase voltages must have shape (3, n), got {v.shape}")
    return np.sqrt(2.0 / 3.0 * np.sum(v**2, axis=0))


#: A voltage magnitude above this fraction of the energised level is a closed contact (the
#: first contact of a switch-on is looked for back to where the voltage rose above it).
CONTACT_LEVEL = 0.05
#: Dips below that level shorter than this (s) are bridged: the zero crossings of the single-phase
#: voltage of two closed poles.
CONTACT_GAP_S = 1e-3


def detect_switch_on(v_phases, ts: float, *, rel_threshold: float = 0.3, hold_s: float = 0.02,
                     min_on_fraction: float = 0.5) -> int | None:
    """Index of the switch-on: the first contact of the first sustained energisation.

    The voltage magnitude (:func:`_magnitude`) is compared with ``rel_threshold`` times its
    energised level (its 90th percentile: the supply must be on for at least about 15 % of
    the record; a switch-off later in the record does no harm). Offsets of a few volts and
    noise sit far below the threshold (30 % of 325 V). The switch-on is the first sample above the
    threshold from which the voltage is above it for at least ``min_on_fraction`` of the next
    ``hold_s`` seconds: an isolated spike does not count, contact bounce (about 1 ms of
    open/closed chatter) does not delay it. From there it goes back to the first contact: the
    first of the samples just before it whose magnitude is above :data:`CONTACT_LEVEL` of the
    energised level, with dips shorter than :data:`CONTACT_GAP_S` bridged (contactor poles
    closing one after another first put a line-line voltage on two phases, about 0.3 of the
    level, and the current flows from then on). The record is kept
    from the first contact, bounce included, since the model is fed the measured voltages.

    Parameters
    ----------
    v_phases : (3, n) phase voltages in V.  ts : sample time in s.

    Returns
    -------
    int or None : sample index; None when the record starts already energised (above the
        threshold for most of its first millisecond) or is never energised.
    """
    m = _magnitude(v_phases)
    n = len(m)
    steady = float(np.percentile(m, 90)) if n else 0.0
    if n < 3 or steady <= 0:
        return None
    above = m > rel_threshold * steady
    n0 = min(n, max(3, int(round(1e-3 / ts))))
    if above[:n0].mean() >= 0.5:
        return None
    hold = max(1, min(int(round(hold_s / ts)), n))
    cs = np.concatenate([[0], np.cumsum(above)])
    end = np.minimum(np.arange(n) + hold, n)
    frac = (cs[end] - cs[:n]) / np.maximum(end - np.arange(n), 1)
    ok = np.flatnonzero(above & (frac >= min_on_fraction))
    if not len(ok):
        return None
    k = int(ok[0])
    # back to the first contact: poles closing one after the other first put a line-line voltage
    # on two phases (an alpha-beta magnitude near 0.3 of the energised level, below the
    # threshold), and the current flows from then on
    # (a single-phase voltage crosses zero: gaps shorter than CONTACT_GAP_S are bridged)
    live = np.flatnonzero(m[:k] > CONTACT_LEVEL * steady)
    gap = max(2, int(round(CONTACT_GAP_S / ts)))
    for j in live[::-1]:
        if k - j > gap:
            break
        k = int(j)
    return k


#: Currents departing from their rest level by more than this fraction of the record's peak
#: (or :data:`REST_NOISE_K` times their sample noise, whichever is larger) are no longer at rest.
REST_LEVEL = 0.02
REST_NOISE_K = 8.0
#: Currents moving more than this (s) before the voltage's switch-on (smoothing and the first
#: pole's contact allow for less) mean the voltage was live from the start: no pre-trigger.
REST_GUARD_S = 2e-3


def difference_noise(x) -> float:
    """Sample noise (one standard deviation) of ``x`` from its first differences: the robust
    spread (1.4826 median absolute deviation) of ``diff(x)`` over sqrt(2); a smooth trend or a
    slow ramp adds almost nothing to it."""
    d = np.diff(np.asarray(x, dtype=float))
    return 1.4826 * float(np.median(np.abs(d - np.median(d)))) / math.sqrt(2.0)


def current_departure(i, ts: float, k_on: int | None, *, smooth_s: float = 1e-3) -> int | None:
    """First sample before ``k_on`` at which a phase current leaves its rest level, or None
    when the currents are at rest up to ``k_on`` (a true pre-trigger: supply off, only offsets
    and noise).

    A voltage that is live but low (an inverter's V/f start with a boost voltage at near-zero
    frequency: a few volts, nearly DC) sits below the switch-on's contact level, yet drives a
    current from the first sample: that stretch is no pre-trigger, and its current is no
    sensor offset. Each current, smoothed over ``smooth_s``, is compared with its rest level,
    its median over the first ``smooth_s`` (over the first five, a current rising from the first
    sample lifted the level with it: the independent plant's 7.5 kW PWM start from a 3.4 % boost,
    3.5 A at the contact 22 samples in, was taken for a pre-trigger); the threshold is
    ``max(REST_NOISE_K sigma, REST_LEVEL peak)``, ``sigma`` the sample noise from the median
    absolute first difference.

    ``i`` : (2, n) currents in A.  ``ts`` : sample time in s.  ``k_on`` : the voltage's switch-on.
    """
    if k_on is None or k_on < 3:
        return None
    i = np.atleast_2d(np.asarray(i, dtype=float))
    peak = float(np.max(np.abs(i))) if i.size else 0.0
    w = max(1, int(round(smooth_s / ts)))
    first = None
    for x in i:
        seg = x[:k_on]
        sigma = difference_noise(x[: max(k_on, 3)])
        ref = float(np.median(seg[: max(3, min(len(seg), w))]))
        sm = np.convolve(seg - ref, np.ones(w) / w, mode="same")
        out = np.flatnonzero(np.abs(sm) > max(REST_NOISE_K * sigma, REST_LEVEL * peak))
        if len(out):
            first = int(out[0]) if first is None else min(first, int(out[0]))
    return first


#: A pre-trigger whose voltage magnitude rises, from its first quarter to its last, by more than
#: this fraction of the energised level (and :data:`LIVE_NOISE_K` standard errors) is live.
LIVE_RISE_LEVEL = 0.01
LIVE_NOISE_K = 8.0


def voltage_rises_before(v_phases, k_on: int | None) -> bool:
    """Whether the voltage before ``k_on`` is live: its magnitude rises through the stretch.

    A pre-trigger holds the sensors' offsets and noise, constant until the first contact; an
    inverter's V/f ramp that starts at a low boost voltage climbs steadily up to the contact
    level instead (a 1 kW start: 3.9 V at the first sample, 7.8 V at the 5 % contact level
    8.5 ms later), and its current is no sensor offset. The magnitude's mean over the last
    quarter of ``[0, k_on)`` is compared with that over the first quarter; the noise's standard
    error comes from :func:`difference_noise` (``v_phases`` (3, n) V)."""
    if k_on is None or k_on < 8:
        return False
    m = _magnitude(np.asarray(v_phases, dtype=float))
    n = len(m)
    level = float(np.percentile(m, 90)) if n else 0.0
    seg = m[:k_on]
    q = max(2, k_on // 4)
    rise = float(np.mean(seg[-q:]) - np.mean(seg[:q]))
    se = difference_noise(seg) * math.sqrt(2.0 / q)
    return rise > max(LIVE_NOISE_K * se, LIVE_RISE_LEVEL * level)


#: A stretch before the switch-on whose voltage magnitude (median) is at least this share of the
#: magnitude at the switch-on, while the currents already move, is live (:func:`voltage_live_from_start`).
LIVE_SHARE_OF_CONTACT = 0.5


def voltage_live_from_start(v_phases, k_on: int | None, k_rest: int | None) -> bool:
    """Whether the record is energised from its first sample although the switch-on was found
    later: the voltage magnitude before ``k_on`` is already :data:`LIVE_SHARE_OF_CONTACT` of
    the magnitude at ``k_on``, and the currents leave their rest level (``k_rest``, from
    :func:`current_departure`) more than three samples before it.

    An inverter's V/f start whose boost sits just under the contact level (the independent
    plant's 3.7 kW PWM start, blind seed 50, set 4: 14.4 V at the first sample, 15.2 V at the 5 %
    contact level 24 samples later) neither rises by 1 % of the level through the stretch
    (:func:`voltage_rises_before`) nor drives its current away more than 2 ms before the contact
    (the current leaves rest at the 6th sample); trimmed as a pre-trigger, the record lost its
    first 14 samples and 1.3 A of current, and the model, started from rest, missed the data by
    0.3 A rms over the first 50 ms at the true parameters. A contactor's pre-trigger holds
    offsets of a few volts (far under the first contact's magnitude) and no current.

    ``v_phases`` (3, n) V."""
    if k_on is None or k_on < 8:
        return False
    m = _magnitude(np.asarray(v_phases, dtype=float))
    if not float(np.median(m[:k_on])) >= LIVE_SHARE_OF_CONTACT * float(m[k_on]):
        return False
    return k_rest is not None and k_rest < k_on - 3


#: Samples a pre-trigger needs, less its guard, to be one: the stretch whose mean is a channel's
#: offset (:mod:`.record_conditioning`) and whose spread is its noise (:mod:`.noise`).
MIN_PRETRIGGER = 50
#: Samples left out before the switch-on when a pre-trigger is used (the contactor's first arcs).
PRETRIGGER_GUARD = 3


def find_pretrigger(v_phases, i, ts: float) -> tuple[int | None, list[str]]:
    """The switch-on that ends a record's pre-trigger (:func:`detect_switch_on`), or None where
    the record starts energised, with a note for each reason a found switch-on is no pre-trigger's
    end: the currents leave their rest level well before it (:func:`current_departure`), the
    voltage rises through the stretch (:func:`voltage_rises_before`) or is live from the first
    sample (:func:`voltage_live_from_start`); each is a live low voltage, e.g. an inverter's V/f
    boost. The one switch-on of a record: the conditioning trims by it and takes its offsets
    there, the noise estimate its quiet segment.

    ``v_phases`` (3, n) V.  ``i`` (2, n) currents in A (two phases or alpha-beta).  ``ts`` s."""
    notes: list[str] = []
    k_on = detect_switch_on(v_phases, ts)
    k_rest = current_departure(i, ts, k_on)
    if k_rest is not None and k_rest < k_on - max(3, round(REST_GUARD_S / ts)):
        # current flows well before the voltage's switch-on: the voltage was live (if low) from the start
        notes.append(f"currents leave their rest level at t = {k_rest * ts:.4f} s, before the voltage's "
                     f"switch-on at {k_on * ts:.4f} s (a live low voltage, e.g. a V/f boost): no pre-trigger")
        k_on = None
    elif voltage_rises_before(v_phases, k_on):
        notes.append(f"the voltage's magnitude rises steadily before its switch-on at {k_on * ts:.4f} s (a live "
                     f"low voltage, e.g. a V/f ramp from a boost voltage): no pre-trigger")
        k_on = None
    elif voltage_live_from_start(v_phases, k_on, k_rest):
        notes.append(f"the voltage before its switch-on at {k_on * ts:.4f} s is already near its magnitude there "
                     f"and the currents move before it (a live low voltage from the first sample, e.g. a V/f "
                     f"boost just under the contact level): no pre-trigger")
        k_on = None
    return k_on, notes


def has_pretrigger(pretrigger_end: int | None, guard: int = PRETRIGGER_GUARD) -> bool:
    """Whether a switch-on at sample ``pretrigger_end`` leaves at least :data:`MIN_PRETRIGGER`
    samples before it less ``guard``: a pre-trigger."""
    return pretrigger_end is not None and pretrigger_end - guard >= MIN_PRETRIGGER


def pretrigger_segment(x, pretrigger_end: int | None, guard: int = PRETRIGGER_GUARD) -> np.ndarray | None:
    """The samples of ``x`` before a switch-on at ``pretrigger_end`` less ``guard``, when there
    are at least :data:`MIN_PRETRIGGER` of them (the pre-trigger), else None."""
    if not has_pretrigger(pretrigger_end, guard):
        return None
    return np.asarray(x)[..., :pretrigger_end - guard]


#: A change of the voltage space vector between two samples that departs from the smooth change
#: of its neighbours by more than this fraction of the energised level is a switching step.
STEP_LEVEL = 0.05
#: Switching steps are looked for this long (s) after the switch-on (pole scatter, bounce).
STEP_WINDOW_S = 0.02
#: Sample intervals after the last step used to estimate the current's response (with fewer, the
#: baseline and the transient inductance are nearly collinear and noise moves the fractions).
STEP_FIT_AFTER = 30


@dataclass(frozen=True, eq=False)
class SwitchingSteps:
    """What :func:`switching_steps` found: the corrected voltages ``v_a, v_b`` (V), the sample
    intervals ``steps`` holding a step (interval ``k`` runs from sample ``k`` to ``k+1``), the
    estimated fraction of each interval after its step, the transient inductance the estimate
    used (H, None when it could not be estimated: then nothing was corrected), and the current
    samples to mask, ``mask`` (bool, True = masked)."""

    v_a: np.ndarray
    v_b: np.ndarray
    steps: tuple
    fractions: tuple
    inductance: float | None
    mask: np.ndarray


def switching_steps(v_a, v_b, i_a, i_b, start: int, ts: float, *, window_s: float = STEP_WINDOW_S,
                    rel_step: float = STEP_LEVEL, after: int = STEP_FIT_AFTER) -> SwitchingSteps:
    """Volt-seconds of the switching steps of a sampled switch-on, from the current's response.

    A contactor's poles close (and their arcs end) between two samples. The model interpolates the
    sampled voltage linearly between samples, so it puts ``dV (1/2 - f) Ts`` volt-seconds too many
    into a sample interval with a step ``dV`` that closes a fraction ``f`` of the interval before its
    end; the flux error this leaves decays only with the machine's time constants (tens to hundreds
    of milliseconds of misfit). The current tells ``f``: over one sample interval the current moves
    by ``Ts/L' x`` (mean voltage over the interval) plus a smooth term (resistive drop, back-EMF),
    ``L'`` the transient inductance. A linear least-squares fit over the switching window of the
    current increments on the interpolated voltage (``Ts/L'``), on each step's ``dV`` (its
    ``f - 1/2``, times ``Ts/L'``), and on a smooth baseline (constant and slope per axis, the
    current) gives every ``f``; the voltage sample before each step is then corrected by
    ``dV (f - 1/2)`` so that the interpolated volt-seconds over the step are the measured ones.
    The current samples of the window (from the sample before the first step, whose voltage may
    be corrected, to two samples after the last), which the interpolation cannot follow within a
    sample, are to be masked.

    ``v_a, v_b, i_a, i_b``: alpha-beta voltages (V) and currents (A); ``start``: the switch-on
    sample. Steps: intervals whose voltage change departs from the mean of the changes two
    intervals before and after by more than ``rel_step`` of the energised level (90th percentile
    of the magnitude), and by at least as much as the intervals within two on either side,
    within ``window_s`` after the switch-on.
    """
    V = np.asarray(v_a, float) + 1j * np.asarray(v_b, float)
    Cur = np.asarray(i_a, float) + 1j * np.asarray(i_b, float)
    n = len(V)
    mask = np.zeros(n, bool)
    none = SwitchingSteps(np.asarray(v_a, float), np.asarray(v_b, float), (), (), None, mask)
    if n < 16:
        return none
    level = float(np.percentile(np.abs(V), 90))
    dV = np.diff(V)
    pred = np.zeros(n - 1, complex)
    pred[2:-2] = 0.5 * (dV[:-4] + dV[4:])
    lo, hi = max(start - 3, 2), min(n - 3, start + max(int(round(window_s / ts)), 10))
    dev = np.abs(dV - pred)
    # a step also lifts the deviation two intervals on either side (to half): keep local maxima
    steps = [j for j in range(lo, hi) if dev[j] > rel_step * level and dev[j] >= dev[max(j - 2, 0):j + 3].max()]
    if not steps:
        return none
    k1, k2 = steps[0], steps[-1]
    mask[k1:min(n, k2 + 3)] = True
    js = np.arange(k1, min(n - 1, k2 + 1 + after))
    d = Cur[js + 1] - Cur[js]
    t = (js - k1) / len(js)
    cols = [0.5 * (V[js] + V[js + 1])] + [np.where(js == s, dV[s], 0.0) for s in steps]
    one = np.ones(len(js))
    imid = 0.5 * (Cur[js] + Cur[js + 1])
    cols += [one, 1j * one, t, 1j * t, imid, 1j * imid]
    A = np.column_stack(cols)
    if 2 * len(js) < A.shape[1] + 4:
        return SwitchingSteps(none.v_a, none.v_b, tuple(steps), (), None, mask)
    coef = np.linalg.lstsq(np.vstack([A.real, A.imag]), np.concatenate([d.real, d.imag]), rcond=None)[0]
    g = float(coef[0])
    if not (np.isfinite(g) and g > 0):
        return SwitchingSteps(none.v_a, none.v_b, tuple(steps), (), None, mask)
    out = V.copy()
    fractions = []
    for q, s in enumerate(steps):
        excess = float(np.clip(coef[1 + q] / g, -0.5, 0.5))  # f - 1/2
        fractions.append(excess + 0.5)
        out[s] += excess * dV[s]
    return SwitchingSteps(out.real.copy(), out.imag.copy(), tuple(steps), tuple(fractions), ts / g, mask)


def sampled_volt_seconds(v, start: int) -> np.ndarray:
    """Samples of a continuous voltage for the model's linear interpolation from ``start`` on:
    ``v[k] - (v[k-1] - 2 v[k] + v[k+1]) / 12``.

    The model integrates the input over a sample interval as the mean of its end samples (RK4 on
    a linearly interpolated input is Simpson's rule on the chord). A continuous voltage bends
    between its samples: a sine of ``w`` loses ``(w Ts)^2 / 12`` of its volt-seconds to the chord
    (3e-4 at 60 Hz sampled at 6 kHz, some ten times the statistical uncertainty of a start-up's
    parameters; every impedance comes out that much low). With the second difference subtracted
    the interpolated volt-seconds match those of the continuous voltage to fourth order in
    ``w Ts``, and the sum over the record changes only by its end terms (the second differences
    telescope): the volt-seconds of a step are not moved."""
    v = np.asarray(v, float)
    out = v.copy()
    a = max(int(start), 1)
    if a < len(v) - 1:
        out[a:-1] -= (v[a - 1:-2] - 2.0 * v[a:-1] + v[a + 1:]) / 12.0
    return out
