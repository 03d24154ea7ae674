"""The speed channel's filter, a fact of the instrument (``speed_filter`` in ``meta.yaml``, s).

A tachogenerator's output is smoothed by an RC filter, an encoder's speed is the angle turned
in a gate time over that time: milliseconds, documented by the data sheet or set in the drive.
Where ``meta.yaml`` states it, every model of the diagnosis reads its simulated speed through
a first-order filter of that time constant (:func:`first_order_lag`; an encoder's mean over a
gate time lags by half of it: state half the gate time), on the start-up and on the free stop
alike, and so does the identification's model (``python -m benchmark``: its cost, its
residuals and its figures, :func:`speed_read_through`); where nothing is stated the speed is
read unfiltered. A 5 ms filter on a motor accelerating at 1000 rad/s^2 reads 5 rad/s below the
shaft, fifty times a tachometer's noise.
The filter is not fitted: searched as the tachometer's fourth error (0-10 ms on every record),
it took what a foreign form left in the speed (a slip clutch read as a tachometer with its
lag at that bound, blind plant seed 452 set 12; a coupling and a saturation read as a
tachometer and a double cage where a filter was stated and free up to it, seed 471 set 6).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import signal

from benchmark.core.errors import DataError
from benchmark.core.meta_file import check_meta_type
from benchmark.core.tables import _short_repr

#: The longest speed filter meta.yaml may state (s): a tachogenerator's RC filter or an
#: encoder's gate time are milliseconds; a tenth of a second would be a filter on the
#: dynamics the record is there to show.
MAX_SPEED_FILTER = 0.1


def parse_speed_filter(meta_path: Path, value) -> float:
    """``speed_filter`` of meta.yaml: seconds, 0 to :data:`MAX_SPEED_FILTER`."""
    tau = check_meta_type(meta_path, "speed_filter", value, float)
    if not 0.0 <= tau <= MAX_SPEED_FILTER:
        raise DataError(meta_path, f"key 'speed_filter' must be in seconds, 0 to {MAX_SPEED_FILTER:g} (the speed "
                                   f"channel's filter time constant, half an encoder's gate time), got "
                                   f"{_short_repr(value)}")
    return float(tau)


def stated_speed_filter(facts: dict | None) -> float:
    """The speed filter's time constant (s) ``facts`` state (``speed_filter``), 0 when none."""
    return float((facts or {}).get("speed_filter") or 0.0)


def filter_pole(speed_filter: float | None, dt: float) -> float:
    """The per-sample pole ``exp(-dt / tau)`` that the speed channel's stated filter (``tau`` =
    ``speed_filter``, s; 0 or None: none) gives noise entering before it, at the sample time
    ``dt`` (s); 0 when there is none. A tachogenerator's own noise (brushes, commutation) passes
    its RC filter: the recorded noise is then coloured, mostly slower than a smoothing window,
    which took it for signal and put an effect-free record's gap at 1.5 (motulator, a 5 ms
    filter: 0.018 rad/s estimated where 0.044 was recorded)."""
    tau = float(speed_filter or 0.0)
    return math.exp(-dt / tau) if tau > 0.0 and dt > 0.0 else 0.0


def first_order_lag(w: np.ndarray, tau: np.ndarray | float, dt: float) -> np.ndarray:
    """Rows of ``w`` (n, N) through first-order filters of time constants ``tau`` (n,) s (or one
    for all), sampled every ``dt`` s, each starting settled at its first value; a row with
    ``tau = 0`` passes unchanged. Exact for an input linear between samples (ramp-invariant:
    the simulated speed is continuous)."""
    out = np.array(w, float, copy=True)
    taus = np.broadcast_to(np.ravel(tau), (out.shape[0],)) if np.ndim(tau) else np.full(out.shape[0], float(tau))
    for k, tk in enumerate(taus):
        if tk > 0.0 and dt > 0.0:
            r = tk / dt
            a = math.exp(-1.0 / r)
            b = [1.0 - r * (1.0 - a), r * (1.0 - a) - a]
            out[k] = signal.lfilter(b, [1.0, -a], out[k], zi=signal.lfilter_zi(b, [1.0, -a]) * out[k, 0])[0]
    return out


def speed_read_through(sim: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """Simulated outputs ``sim`` (n, 3, N): i_alpha, i_beta, speed at samples ``dt`` s apart,
    with the speed read through the stated filter ``tau`` (s); ``sim`` itself when ``tau`` is 0
    (a copy otherwise: a cached simulation stays as it is); ``tau`` may be one per row (n,)."""
    if not np.any(np.asarray(tau) > 0.0):
        return sim
    out = np.array(sim, copy=True)
    out[:, 2] = first_order_lag(out[:, 2], tau, dt)
    return out


#: :func:`unstated_filter` looks for a filter where the speed's misfit (RMS over its noise)
#: exceeds this, and names one that takes at least :data:`HINT_SHARE` of that misfit away. A
#: warning's thresholds, not a verdict's: the user is asked to check the instrument.
HINT_MISFIT = 1.5
HINT_SHARE = 0.5
#: The evaluations of the hint's fit (the model's parameters and the filter together, by least squares).
HINT_EVALUATIONS = 300


def speed_misfit(problem, X: np.ndarray, lags) -> float:
    """The first start-up's speed misfit (RMS over its noise estimate) of ``problem``'s model at
    ``X`` (one row), its speed read through a filter of ``lags`` (s)."""
    noise = problem.channel_noise()[0][2]
    w = problem.simulate(X, np.asarray(lags, float))[0][0, 2]
    return float(np.sqrt(np.mean((np.asarray(problem.dataset.startups[0].speed, float) - w) ** 2))) / noise.std


@dataclass(frozen=True)
class UnstatedFilter:
    """A speed filter a record does not state but its speed reads through (:func:`unstated_filter`)."""

    time_constant: float  #: s, fitted with the model's parameters
    misfit_before: float  #: the speed's misfit (RMS over its noise) at the parameters given
    misfit_with: float  #: ... at the refit's parameters, read through the filter

    @property
    def warning(self) -> str:
        """The warning in words, with the line for meta.yaml."""
        return (f"the measured speed reads like the model's through a first-order filter of "
                f"{1e3 * self.time_constant:.2g} ms (fitted with the model's parameters: the speed's misfit "
                f"{self.misfit_before:.3g} times its noise, {self.misfit_with:.3g} with it): if the speed channel has "
                f"a filter (a tachogenerator's RC filter; half an encoder's gate time), state it in meta.yaml, "
                f"`speed_filter: {self.time_constant:.2g}` (s), and the models read their speed through it")


def unstated_filter(problem, x: np.ndarray) -> UnstatedFilter | None:
    """A filter the record does not state but its speed reads through, or None: the time-domain
    ``problem``'s parameters and a first-order filter's time constant fitted together by least
    squares from the estimate ``x`` (:data:`HINT_EVALUATIONS`); named when the speed's misfit
    exceeds :data:`HINT_MISFIT` times its noise and the fit, with a filter of 0 to
    :data:`MAX_SPEED_FILTER` s, leaves at most :data:`HINT_SHARE` of it and of the misfit of its
    own parameters without the filter (a refit that mends the parameters, an Rs 30 % off, is no
    filter's doing: it found one of 7 microseconds), which must themselves still miss the speed by
    :data:`HINT_MISFIT` (a search stopped short, mended by the refit, was told of a filter of 1.2e-5 ms
    on noise-free data where the refit alone was at 0.0013 times the noise).
    The identification's result is not changed: a filter is a fact the user states (a 3 ms
    filter read raw on a motulator start left the speed 21 times its noise with biased
    resistances: from those, the filter alone, the parameters held, explained a third)."""
    from benchmark.core.polish import least_squares_batch

    before = speed_misfit(problem, x[None, :], [0.0])
    if not before > HINT_MISFIT:
        return None
    z0 = np.append(x, 1e-3)
    lower, upper = np.append(problem.lower, 0.0), np.append(problem.upper, MAX_SPEED_FILTER)
    with np.errstate(all="ignore"):
        z, _ = least_squares_batch(lambda Z: problem.residuals_batch(Z[:, :-1], Z[:, -1]), z0, lower, upper,
                                   HINT_EVALUATIONS)
    tau = float(z[-1])
    after = speed_misfit(problem, z[None, :-1], [tau])
    unfiltered = speed_misfit(problem, z[None, :-1], [0.0])  # the refit's parameters alone (x off its minimum)
    mends = unfiltered > HINT_MISFIT and after <= HINT_SHARE * min(before, unfiltered)
    if not (0.0 < tau <= MAX_SPEED_FILTER and mends):
        return None
    return UnstatedFilter(tau, before, after)
