"""The noise of a start-up record: each measured channel's level, with its own uncertainty, that
holds for coloured and quantised noise. This is the one noise estimate of the time-domain
problem: the identification's fit quality (:meth:`benchmark.problems.timedomain.problem.
TimeDomainProblem.channel_noise`, judged by :func:`benchmark.core.uncertainty.misfit_ratio`) and
the diagnosis (:mod:`benchmark.problems.timedomain.diagnosis.fit`) both call
:func:`startup_noise`; change it here and both change.

Where the record has a pre-trigger (samples before the supply is switched on: voltage and
current at rest, :func:`quiet_pre_trigger_length`), every channel's noise is the spread of that
quiet segment (:func:`benchmark.core.noise_estimates.noise_from_quiet`, unbiased for AR(1)
noise). The conditioning trims a pre-trigger to a few samples on load, so only records read with
``conditioning: false`` keep one. Otherwise:

* currents: the end of the start-up, least-squares fitted by the supply's harmonics, each
  with an amplitude that may still drift as a quadratic in time
  (:func:`noise_from_modulated_periodic`, the same degrees-of-freedom correction for
  coloured noise as :func:`benchmark.core.noise_estimates.noise_from_periodic`); what is left,
  coloured noise included, is the noise. A record that ends before its steady state (the
  speed still moving at its end) has a current falling faster than a quadratic follows, and
  the quadratic fit's residual holds the signal (five times the noise on an independent-plant
  start of a motor with a coupled load): there the envelopes are piecewise linear with a knot
  every two periods, with at least a 20 % relative uncertainty;
* speed: over the steady state, the smaller of a Savitzky-Golay fit's residual
  (:func:`noise_from_smooth`) and the same drifting-harmonics fit as the currents at the orders
  where this record's supply makes the torque pulsate (:func:`supplied_torque_orders`: the
  measured voltage's harmonics; see :func:`steady_speed_noise`: each fit leaves some signal
  in, in different records);
* stop record: a smooth fit over the free motion.

Segments too short for these fall back to a fourth-difference estimate (white noise only),
with a 20 % relative uncertainty. A quantised channel's noise is at least ``q / sqrt(12)``,
``q`` the grid step found on the whole channel (:func:`quantum`), and a noise-free channel's
is 1e-4 of its peak for a current, 1e-5 for a speed (:data:`NOISE_FREE_FLOOR`,
:data:`SPEED_NOISE_FREE_FLOOR`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from benchmark.core.noise_estimates import (
    NoiseEstimate,
    ar1_coefficient,
    ar1_gain,
    estimate_noise,
    harmonic_design,
    least_squares_solve,
    noise_from_quiet,
    noise_from_smooth,
    refine_frequency,
)
from benchmark.problems.timedomain.frames import inverse_clarke, phasor_speed
from benchmark.problems.timedomain.speed_filter import filter_pole
from benchmark.problems.timedomain.switch_on import find_pretrigger, pretrigger_segment

#: Fallback relative uncertainty of the fourth-difference estimate.
FALLBACK_REL_UNCERTAINTY = 0.2
#: The noise of a current is at least this share of its peak (a noise-free synthetic record:
#: a 14-bit converter's resolution; below it no record is measured).
NOISE_FREE_FLOOR = 1e-4
#: ... and a speed's at least this share of its peak: an encoder or tachometer resolves finer (the
#: independent plant's 0.02 rad/s on a 3000 rpm motor is 6e-5 of it, which 1e-4 raised by a quarter).
SPEED_NOISE_FREE_FLOOR = 1e-5


def fourth_difference(x: np.ndarray) -> float:
    """White-noise std from fourth differences (robust through the median)."""
    d4 = np.diff(np.asarray(x, float), 4)
    return 1.4826 * float(np.median(np.abs(d4 - np.median(d4)))) / math.sqrt(70.0)


def quantum(x: np.ndarray) -> float:
    """The quantisation step of a channel whose values sit on a grid, else 0."""
    x = np.asarray(x, float)
    steps = np.abs(np.diff(x))
    steps = steps[steps > 0]
    if len(steps) <= 10:
        return 0.0
    q = float(np.min(steps))
    if q <= 0:
        return 0.0
    on_grid = np.abs(x / q - np.round(x / q)) < 1e-6
    return q if np.mean(on_grid) > 0.99 else 0.0


def quantisation_cells(x: np.ndarray, q: float) -> float:
    """Effective number of independent quantisation errors in ``x`` (a channel on a grid of step
    ``q``): the record cut into stretches that stay within one step of their first value (a
    signal that sits still, or flickers between two levels, keeps one error for the whole
    stretch), ``1 / sum w_j^2`` with ``w_j`` each stretch's share of the samples."""
    x = np.asarray(x, float)
    starts, ref = [0], x[0]
    for k in np.flatnonzero(np.abs(np.diff(x)) > 0) + 1:  # only where the value changes
        if abs(x[k] - ref) > 1.5 * q:
            starts.append(int(k))
            ref = x[k]
    w = np.diff(np.append(starts, len(x))) / len(x)
    return float(1.0 / np.sum(w**2))


def floored(est: NoiseEstimate, x: np.ndarray, floor: float) -> NoiseEstimate:
    """``est`` raised to ``floor`` and to the quantisation noise ``q / sqrt(12)`` of the whole
    channel ``x``: the grid is found on the whole record, not on the stretch the noise came
    from. A coarse speed step with little dither sits on one or two levels at standstill and at
    steady state (the estimate sees almost nothing), while the run-up crosses every level and
    leaves its full quantisation error in the residual (independent plant, a 0.186 rad/s step
    with 0.016 rad/s of white noise: the steady state gave only the 1e-4 floor, 0.013 rad/s,
    the run-up's residual holds q/sqrt(12) = 0.054, and an effect-free start was called
    ``unexplained``).

    Where the quantisation sets the level, ``q / sqrt(12)`` is the RMS of a uniform error only
    over many independent errors; a signal that sits still keeps one error, anywhere within
    ``+-q/2``, for as long as it sits (a steady state: up to ``sqrt(3)`` times ``q / sqrt(12)``).
    So the level's relative uncertainty is ``1 / sqrt(5 n)``, ``n`` the
    :func:`quantisation_cells` (the spread of the RMS of ``n`` uniform errors; the paper motor's
    start with a 0.5 rad/s step and no other noise: n = 3.2, 25 %, where the exact model's
    residual is 1.15 times ``q / sqrt(12)``)."""
    q = quantum(x)
    std = max(est.std, q / math.sqrt(12.0), floor)
    if std == est.std:
        return est
    if std == q / math.sqrt(12.0):
        u = math.hypot(est.rel_uncertainty, 1.0 / math.sqrt(5.0 * quantisation_cells(x, q)))
        return NoiseEstimate(std, u, est.n_effective, est.method + f" (floored: quantisation step {q:.3g})")
    return NoiseEstimate(std, est.rel_uncertainty, est.n_effective, est.method + " (floored)")


def fallback(x: np.ndarray, floor: float, why: str) -> NoiseEstimate:
    n = max(len(x) - 4, 1)
    return floored(NoiseEstimate(fourth_difference(x), FALLBACK_REL_UNCERTAINTY, float(n),
                                  f"fourth differences ({why})"), x, floor)


def modulated_periodic_residual(x, fs: float, f0: float, order: int = 2, n_harmonics: int | None = None,
                                rel_line: float = 1e-3, knot_periods: float | None = None,
                                harmonics: str | Sequence[int] = "all") -> tuple[np.ndarray, np.ndarray, int]:
    """What is left of ``x`` after least squares on the supply's harmonics, each modulated by
    an envelope (and an envelope trend): a polynomial in time of ``order``, or, with
    ``knot_periods``, a piecewise-linear curve with a knot every ``knot_periods`` supply periods
    (it follows a start-up's current as it falls within a few periods). The harmonics kept are
    those whose amplitude in a plain periodic fit exceeds ``rel_line`` of the largest, among
    every order (``harmonics="all"``), with ``harmonics="torque"`` only the orders at which
    a three-phase supply makes the torque pulsate (:func:`torque_harmonic_orders`), or among
    the orders given (those up to the Nyquist order). Returns the
    residual, each column's normalised frequency (rad per sample) and the harmonics kept."""
    x = np.asarray(x, float).ravel()
    n = len(x)
    t = np.arange(n) / fs
    tau = np.linspace(-1.0, 1.0, n)
    h_max = int(n_harmonics or 0.48 * fs / f0)
    w = 2 * np.pi * f0 * t
    if isinstance(harmonics, str):
        if harmonics not in ("all", "torque"):
            raise ValueError(f"harmonics must be 'all', 'torque' or a list of orders, got {harmonics!r}")
        orders = np.arange(1, h_max + 1) if harmonics == "all" else torque_harmonic_orders(h_max)
    else:
        orders = np.array([h for h in harmonics if 1 <= h <= h_max], dtype=int)
    plain = [np.ones(n)]
    for h in orders:
        plain += [np.cos(h * w), np.sin(h * w)]
    A = np.column_stack(plain)
    c = least_squares_solve(A, x)
    amp = np.hypot(c[1::2], c[2::2])
    keep = orders[amp > rel_line * amp.max()] if len(orders) else orders
    if knot_periods is None:
        env = [tau**k for k in range(order + 1)]
    else:
        n_knots = max(int(math.ceil((n - 1) / (knot_periods * fs / f0))), 1) + 1
        knots, step = np.linspace(0.0, n - 1.0, n_knots, retstep=True)
        k = np.arange(n)
        env = [np.clip(1.0 - np.abs(k - c) / step, 0.0, None) for c in knots]
    cols, om = list(env), [0.0] * len(env)
    for h in keep:
        for e in env:
            cols += [e * np.cos(h * w), e * np.sin(h * w)]
            om += [2 * np.pi * h * f0 / fs] * 2
    A = np.column_stack(cols)
    return x - A @ least_squares_solve(A, x), np.asarray(om), len(keep)


def torque_harmonic_orders(h_max: int) -> np.ndarray:
    """The supply harmonics (orders up to ``h_max``) at which a three-phase machine's torque, and
    so its speed, pulsates: 2 (a negative-sequence voltage, the supply's unbalance) and the
    multiples of 6 (the 5th and 7th, 11th and 13th, ... voltage harmonics of a grid or an
    inverter). A speed line at any other order is no supply's: a tachometer's commutator or an
    encoder's ripple at a multiple of the rotation frequency, which the model cannot make."""
    return np.array([h for h in range(2, h_max + 1) if h == 2 or h % 6 == 0], dtype=int)


#: :func:`supplied_torque_orders` reads the voltage's lines over at most this many supply periods
#: (memory only: the records so far have at most 40 periods of steady state).
SUPPLY_LINE_PERIODS = 100


def supplied_torque_orders(v_alpha, v_beta, fs: float, f0: float, rel_line: float = 1e-3) -> np.ndarray:
    """The :func:`torque_harmonic_orders` at which this supply makes the torque pulsate: an order
    ``m`` where the measured voltage (``v_alpha``, ``v_beta``, V, sampled at ``fs`` Hz) holds a
    line at a signed order ``h`` of ``f0`` (Hz) with ``|h - 1| = m`` (its negative sequence at
    ``-1`` for 2, the 5th at ``-5`` and the 7th at ``+7`` for 6, ...) larger than ``rel_line``
    of the fundamental. A grid's voltage has a 5th and a 7th and no 11th or 13th, so its motor's
    torque has no 12th: a speed line there is the sensor's (a 4-pole motor's tachometer with 24
    segments near synchronous speed, ~599 Hz), noise to a model the supply cannot make pulsate
    there; a six-step inverter's voltage holds every ``6k +- 1`` and keeps every multiple of 6.
    The lines are read over the last :data:`SUPPLY_LINE_PERIODS` periods at most (the fit's
    matrix grows with the samples times the orders: a long record at a high rate would take
    gigabytes; a steady supply's lines are there in any stretch of it)."""
    n_max = int(SUPPLY_LINE_PERIODS * fs / f0)
    v = (np.asarray(v_alpha, float) + 1j * np.asarray(v_beta, float))[-n_max:]
    h_max = int(0.48 * fs / f0)
    A, _ = harmonic_design(len(v), fs, f0, h_max, trend=False)
    c = least_squares_solve(A, v)  # the alpha and beta fits at once: cos, sin coefficients of each order
    k = len(c) // 2
    c_cos, c_sin = c[1::2][:k], c[2::2][:k]
    amp = {0: abs(c[0])}  # the signed lines e^{jhw}: (c_cos -+ j c_sin) / 2 at +-h
    for h in range(1, k + 1):
        amp[h] = abs(c_cos[h - 1] - 1j * c_sin[h - 1]) / 2
        amp[-h] = abs(c_cos[h - 1] + 1j * c_sin[h - 1]) / 2
    present = {abs(h - 1) for h, a in amp.items() if h != 1 and a > rel_line * amp[1]}
    return np.array([m for m in torque_harmonic_orders(h_max) if m in present], dtype=int)


def noise_from_modulated_periodic(x, fs: float, f0: float, order: int = 2, n_harmonics: int | None = None,
                                  rel_line: float = 1e-3, knot_periods: float | None = None,
                                  harmonics: str | Sequence[int] = "all") -> NoiseEstimate:
    """Noise of a periodic segment whose amplitude still drifts (the end of a start-up): the
    spread of :func:`modulated_periodic_residual`. Each column at ``omega`` absorbs
    ``g(omega)`` noise degrees of freedom (``g`` the AR(1) spectrum of the residual relative to
    white), so the variance is divided by ``N - sum g`` and ``N_eff = (N - sum g)(1 - phi^2)/(1 + phi^2)``
    as in :func:`benchmark.core.noise_estimates.noise_from_periodic`."""
    return modulated_periodic_noise(x, fs, f0, order, n_harmonics, rel_line, knot_periods, harmonics)[0]


def modulated_periodic_noise(x, fs: float, f0: float, order: int = 2, n_harmonics: int | None = None,
                             rel_line: float = 1e-3, knot_periods: float | None = None,
                             harmonics: str | Sequence[int] = "all") -> tuple[NoiseEstimate, np.ndarray, np.ndarray]:
    """:func:`noise_from_modulated_periodic`, the residual it is the spread of (one fit), and the
    share of a white noise's power that residual keeps at each frequency of its FFT
    (:func:`residual_share`: the fit took out the bands about DC and each harmonic it kept)."""
    e, om, kept = modulated_periodic_residual(x, fs, f0, order, n_harmonics, rel_line, knot_periods, harmonics)
    phi = ar1_coefficient(e)
    p_eff = min(float(np.sum(ar1_gain(phi, om))), len(e) / 2)
    envelope = f"order {order}" if knot_periods is None else f"piecewise linear, knots every {knot_periods:g} periods"
    est = estimate_noise(e, p_eff, f"periodic fit, amplitudes drifting ({envelope}; {f0:.4f} Hz, {kept} harmonics)")
    share = residual_share(len(e), om, order) if knot_periods is None else np.ones(len(e) // 2 + 1)
    return est, e, share


#: Bins about a fitted frequency over which :func:`residual_share` counts its leverage.
SHARE_BINS = 24


def residual_share(n: int, om: np.ndarray, order: int) -> np.ndarray:
    """(n//2 + 1,) the expected share of a white noise's power that the residual of
    :func:`modulated_periodic_residual` (``n`` samples, polynomial envelopes of ``order``, its
    columns' frequencies ``om`` in rad per sample) keeps at each frequency of its real FFT:
    ``1 - leverage``, the leverage of the fit's columns at that frequency. The envelopes of one
    frequency span the polynomials of degree ``order``; their orthonormal basis's spectral window,
    shifted to each fitted frequency (and its mirror), is what that frequency's columns remove
    (columns at distinct frequencies are near orthogonal over a record of many periods)."""
    tau = np.linspace(-1.0, 1.0, n)
    q, _ = np.linalg.qr(np.column_stack([tau**k for k in range(order + 1)]))
    t = np.arange(n)
    bins = np.arange(n // 2 + 1)
    lev = np.zeros(len(bins))
    for w in np.unique(np.round(np.asarray(om, float), 12)):
        centre = w / (2 * np.pi) * n  # in bins of the FFT
        for c in (centre, -centre) if w > 0 else (centre,):
            near = bins[np.abs(bins - c) <= SHARE_BINS]  # the window's tail beyond: below 1e-3
            if not len(near):
                continue
            phase = np.exp(-2j * np.pi * np.outer(near - c, t) / n)  # the DTFT at the bins' offsets
            lev[near] += np.sum(np.abs(phase @ q) ** 2, axis=1) / n
    return np.clip(1.0 - lev, 0.0, 1.0)


#: A pre-trigger is quiet when no current's spread exceeds this many times its white part.
QUIET_SIGNAL_RATIO = 4.0


def quiet(*currents: np.ndarray) -> bool:
    """Whether a stretch of low voltage holds only noise: each current's spread within
    :data:`QUIET_SIGNAL_RATIO` of its fourth-difference (white) estimate. An inverter's V/f
    boost is a live voltage below 5 % of the final one, and the current it drives is signal:
    on an independent-plant PWM start it put i_alpha's 'noise' at ten times i_beta's."""
    for x in currents:
        x = np.asarray(x, float)
        white = fourth_difference(x)
        if white > 0 and np.std(x) > QUIET_SIGNAL_RATIO * white:
            return False
    return True


def quiet_pre_trigger_length(t, v_alpha, v_beta, i_alpha, i_beta) -> int:
    """Samples of the record's pre-trigger (:func:`~benchmark.problems.timedomain.switch_on.find_pretrigger`,
    the one the conditioning reads: at least :data:`~benchmark.problems.timedomain.switch_on.MIN_PRETRIGGER`
    before the switch-on less its guard) when that stretch is :func:`quiet`, else 0 (no pre-trigger
    to take the noise from). The conditioning trims a pre-trigger to a few samples before the
    noise is estimated: only a record read with ``conditioning: false`` keeps one."""
    ts = float(np.median(np.diff(t)))
    k_on, _ = find_pretrigger(np.vstack(inverse_clarke(v_alpha, v_beta)), np.vstack([i_alpha, i_beta]), ts)
    seg = pretrigger_segment(np.asarray(i_alpha), k_on)
    if seg is None or not quiet(seg, pretrigger_segment(np.asarray(i_beta), k_on)):
        return 0
    return len(seg)


def _departures(speed: np.ndarray, n: int, period: int) -> np.ndarray:
    """Samples (the last period left out) where the speed averaged over ``period`` samples is
    more than 0.5 % from its final value (the mean of the record's last tenth)."""
    ws = np.convolve(speed, np.ones(period) / period, mode="same") if period > 1 else speed
    final = float(np.mean(speed[int(0.9 * n):]))
    return np.flatnonzero(np.abs(ws[:n - period] - final) > 0.005 * max(abs(final), 1e-9))


def steady_start(speed: np.ndarray | None, n: int, period: int = 1) -> int:
    """First sample of the steady state: the speed (averaged over a supply period) within
    0.5 % of its final value for good, plus three periods, and not before 60 % of the record (nor after 80 %)."""
    if speed is None or not np.all(np.isfinite(speed)):
        return int(0.7 * n)
    off = _departures(speed, n, period)
    k = int(off[-1]) + 1 + 3 * period if len(off) else 0  # three periods more: the currents settle later
    return min(max(k, int(0.6 * n)), int(0.8 * n))


#: A record that ends before its steady state: the estimate with piecewise-linear envelopes
#: replaces the quadratic one when it is below this share of it (the envelope then changed
#: faster than a quadratic follows, and the quadratic fit's residual holds the signal).
UNSETTLED_RATIO = 0.8
#: Knot spacing (supply periods) of those envelopes: on independent-plant records with
#: coloured noise, 1 period absorbs the noise's slow part (half the true level), 4 let the
#: falling current leak in; 2 came within 10-40 % of the truth where the quadratic was 5 times it.
UNSETTLED_KNOT_PERIODS = 2.0
#: ... and its relative uncertainty is at least this (the errors seen there: -20 to +40 %).
UNSETTLED_REL_UNCERTAINTY = 0.2


def settled(speed: np.ndarray | None, n: int, k_ss: int, fs: float, f0: float) -> bool:
    """Whether the start-up reached its steady state before ``k_ss``: the speed (averaged over a
    supply period) stays within 0.5 % of its final value from there on. Unknown without a speed
    record (False: the window check then decides)."""
    if speed is None or not np.all(np.isfinite(speed)):
        return False
    period = max(int(fs / f0), 1)
    return bool(k_ss < n - period and not np.any(_departures(speed, n, period) >= k_ss))


def supply_frequency_of(t, v_alpha, v_beta) -> float:
    """Supply frequency (Hz) from the voltage phasor's phase over the last fifth of the record."""
    tail = slice(int(0.8 * len(t)), len(t))
    return abs(phasor_speed(np.asarray(v_alpha)[tail], np.asarray(v_beta)[tail], np.asarray(t)[tail])) / (2 * math.pi)


def record_noise(record, supply_frequency: float | None = None,
                 speed_filter: float | None = None) -> tuple[dict[str, NoiseEstimate], float]:
    """:func:`startup_noise` of a :class:`~benchmark.problems.timedomain.data.StartupRecord`
    (``speed`` left out when not measured) and the supply frequency it used (Hz): the one given
    (meta.yaml's ``supply_frequency``), else :func:`supply_frequency_of` the voltages;
    ``speed_filter`` (s) is meta.yaml's, the speed channel's filter (:func:`filter_pole`)."""
    r = record
    speed = np.asarray(r.speed, float)
    has_speed = bool(np.all(np.isfinite(speed)))
    f_supply = float(supply_frequency or supply_frequency_of(r.t, r.v_alpha, r.v_beta))
    noise = startup_noise(r.t, r.v_alpha, r.v_beta, r.i_alpha, r.i_beta, speed if has_speed else None, f_supply,
                          frequency_known=bool(supply_frequency), speed_filter=speed_filter)
    return noise, f_supply


def startup_noise(t, v_alpha, v_beta, i_alpha, i_beta, speed, supply_frequency: float,
                  frequency_known: bool = False, speed_filter: float | None = None) -> dict[str, NoiseEstimate]:
    """Noise of ``i_alpha``, ``i_beta`` and (when measured) ``speed`` of one start-up record
    (``speed_filter``, s: the speed channel's stated filter, :func:`filter_pole`)."""
    n = len(t)
    fs = 1.0 / float(np.median(np.diff(t)))
    has_speed = speed is not None and bool(np.all(np.isfinite(speed)))
    i_floor = NOISE_FREE_FLOOR * float(np.max(np.abs(np.concatenate([i_alpha, i_beta]))))
    out: dict[str, NoiseEstimate] = {}
    k_quiet = quiet_pre_trigger_length(t, v_alpha, v_beta, i_alpha, i_beta)
    chans = {"i_alpha": i_alpha, "i_beta": i_beta}
    if has_speed:
        chans["speed"] = speed
    if k_quiet:
        for ch, x in chans.items():
            floor = i_floor if ch != "speed" else SPEED_NOISE_FREE_FLOOR * float(np.max(np.abs(speed)))
            try:
                out[ch] = floored(noise_from_quiet(x[:k_quiet]), x, floor)
            except ValueError:
                out[ch] = fallback(x, floor, "pre-trigger too short")
        return out
    k_ss = steady_start(speed if has_speed else None, n, max(int(fs / supply_frequency), 1))
    f0 = float(supply_frequency)
    if not frequency_known and (n - k_ss) / fs * f0 >= 2:
        try:  # the supply frequency from the voltage (cheap: few harmonics), then every harmonic
            f0 = refine_frequency(v_alpha[k_ss:], fs, f0, n_harmonics=13)
        except (ValueError, np.linalg.LinAlgError):
            f0 = float(supply_frequency)
    for ch in ("i_alpha", "i_beta"):
        x = chans[ch][k_ss:]
        try:
            if (n - k_ss) / fs * f0 < 2:
                raise ValueError("steady state shorter than two periods")
            est = noise_from_modulated_periodic(x, fs, f0)
            if not settled(speed if has_speed else None, n, k_ss, fs, f0):
                local = noise_from_modulated_periodic(x, fs, f0, knot_periods=UNSETTLED_KNOT_PERIODS)
                if local.std < UNSETTLED_RATIO * est.std:
                    est = NoiseEstimate(local.std, max(local.rel_uncertainty, UNSETTLED_REL_UNCERTAINTY),
                                        local.n_effective,
                                        local.method + "; the record ends before a steady state")
            out[ch] = floored(est, chans[ch], i_floor)
        except (ValueError, np.linalg.LinAlgError) as exc:
            out[ch] = fallback(chans[ch], i_floor, str(exc))
    if has_speed:
        floor = SPEED_NOISE_FREE_FLOOR * float(np.max(np.abs(speed)))
        try:
            orders = supplied_torque_orders(v_alpha[k_ss:], v_beta[k_ss:], fs, f0)
            pole = filter_pole(speed_filter, 1.0 / fs)
            out["speed"] = floored(steady_speed_noise(speed[k_ss:], fs, f0, orders, pole), speed, floor)
        except ValueError as exc:
            out["speed"] = fallback(speed, floor, str(exc))
    return out


def steady_speed_noise(x: np.ndarray, fs: float, f0: float,
                       orders: str | Sequence[int] = "torque", pole: float = 0.0) -> NoiseEstimate:
    """Noise of the speed's steady state ``x`` (rad/s): the smaller of a Savitzky-Golay fit's
    residual (window up to 101 samples) and, over two supply periods or more, the drifting
    lines of the supply ``f0`` (Hz) at which the torque pulsates (:func:`torque_harmonic_orders`),
    fitted as for the currents. An inverter's torque ripple (six times the supply frequency) is
    faster than the smoothing window and stays in its residual (independent plant, six-step
    starts of 1 and 2.2 kW motors: 2.7 and 3.5 times the noise really added), the harmonic fit
    takes it out (1.00-1.01); a PWM inverter's ripple is no supply harmonic and the harmonic fit
    leaves it in (1.37-1.41), the smoothing takes it out (1.03-1.04). Both came within 5 % of it
    on direct-on-line starts. A tachometer's commutator ripple is noise to the model; fitted at
    every supply harmonic it was taken out wherever it fell beside one (a 6-pole motor's 18 per
    revolution at 357 Hz beside the 6th: 0.070 rad/s against 0.095 really added). ``orders``:
    the torque lines fitted, all of them (``"torque"``) or those the supply makes
    (:func:`supplied_torque_orders`, as :func:`startup_noise` calls it). ``pole``: the colour of
    the speed's stated filter (:func:`filter_pole`), allowed for in the smoothing's residual."""
    window = int(min(101, len(x) // 3)) | 1
    est = noise_from_smooth(x, window, pole=pole)
    if len(x) / fs * f0 >= 2:
        try:
            periodic = noise_from_modulated_periodic(x, fs, f0, harmonics=orders)
        except (ValueError, np.linalg.LinAlgError):
            return est
        if periodic.std < est.std:
            return periodic
    return est


def stop_noise(speed: np.ndarray, w0: float, pole: float = 0.0) -> NoiseEstimate:
    """Noise of a stop record's free motion ``speed`` (rad/s, from the speed ``w0``): a smooth
    fit's residual (``pole``: the colour of a stated filter, :func:`filter_pole`), floored as the
    start-up's channels."""
    floor = SPEED_NOISE_FREE_FLOOR * max(w0, 1e-9)
    window = int(min(51, len(speed) // 3)) | 1
    try:
        return floored(noise_from_smooth(speed, window, pole=pole), speed, floor)
    except ValueError as exc:
        return fallback(speed, floor, str(exc))


def combined(noise: dict[str, NoiseEstimate], counts: dict[str, int]) -> NoiseEstimate:
    """The noise of the stacked residual, each channel divided by its own noise (std 1): its
    relative uncertainty is the sample-weighted mean of the channels' (the channels' errors
    taken as fully correlated: conservative)."""
    total = sum(counts.values()) or 1
    u = sum(noise[c].rel_uncertainty * k for c, k in counts.items()) / total
    n_eff = sum(noise[c].n_effective for c in counts)
    return NoiseEstimate(1.0, float(u), float(n_eff), "channels normalised by their own noise")
