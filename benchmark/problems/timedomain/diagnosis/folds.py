"""The experiment's segments and the two held-out folds of the diagnosis's score.

A start-up record has three segments, the free stop a fourth:

* ``electrical_start``: the first :data:`ELECTRICAL_START_PERIODS` supply periods (the current's
  largest peaks, the flux build-up);
* ``acceleration``: from there until the measured speed first reaches 98 % of its final value
  (without a speed sensor, until 60 % of the record);
* ``steady_state``: the rest of the start-up record;
* ``free_stop``: the coast-down of the stop record.

The held-out score needs two folds, each fitted and predicting the other. They are cut by
segment: every segment is split into :data:`BLOCKS_PER_SEGMENT` contiguous blocks of equal
duration, the blocks alternate between fold A and fold B. So each fold holds part of every
segment (each fold's fit sees the physics of every regime: the start's large currents, the
acceleration, the loaded or unloaded steady state, the coast), and each held-out block is a
stretch of its segment as long as a quarter of it. A model error that is smooth in time (an
augmentation's form that misses the plant's) is no longer held out in blocks of half a period
between blocks the fit has seen, where any flexible effect fitted to it on one fold predicted it
on the other: it must be predicted a quarter of a segment away.

Masked samples (the conditioning's, :meth:`DiagnosisData.used`) belong to no fold.
"""

from __future__ import annotations

import numpy as np

from benchmark.problems.timedomain.conditioning import ELECTRICAL_START_PERIODS

SEGMENTS = ("electrical_start", "acceleration", "steady_state", "free_stop")
#: Contiguous blocks each segment is cut into; they alternate between the two folds.
BLOCKS_PER_SEGMENT = 4


def acceleration_end(data) -> float:
    """Time (s, on the record's clock) the start-up reaches 98 % of its final measured speed
    (the mean over the last tenth); without a speed sensor 60 % into the record."""
    n = data.n_startup
    if not data.has_speed:
        return float(data.t[int(0.6 * n)])
    w = data.meas[2]
    final = float(np.mean(w[int(0.9 * n):]))
    reached = np.flatnonzero(w >= 0.98 * final)
    return float(data.t[reached[0]] if len(reached) else data.t[-1])


def startup_segments(data) -> np.ndarray:
    """(N,) segment index (0 electrical start, 1 acceleration, 2 steady state) of each start-up sample."""
    t_acc = acceleration_end(data)
    t_el = min(data.t[0] + ELECTRICAL_START_PERIODS / data.supply_frequency, t_acc)
    return np.where(data.t < t_el, 0, np.where(data.t < t_acc, 1, 2))


def segment_masks(data) -> dict[str, np.ndarray]:
    """Masks over the residual vector (:class:`DiagnosisData` layout) for the four segments."""
    seg = startup_segments(data)
    parts = [seg] * len(data.startup_channels())
    if data.stop_t is not None:
        parts.append(np.full(len(data.stop_t), 3))
    seg_all = np.concatenate(parts)
    return {name: seg_all == k for k, name in enumerate(SEGMENTS)}


def _alternate(t: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """True where a sample falls into an even block of its segment: each segment (``labels``)
    cut into :data:`BLOCKS_PER_SEGMENT` blocks of equal duration over its span in ``t``."""
    in_a = np.zeros(len(t), bool)
    for k in np.unique(labels):
        m = labels == k
        t0, t1 = float(t[m][0]), float(t[m][-1])
        span = max(t1 - t0, 1e-12)
        block = np.minimum(np.floor((t[m] - t0) / span * BLOCKS_PER_SEGMENT), BLOCKS_PER_SEGMENT - 1)
        in_a[m] = block.astype(int) % 2 == 0
    return in_a


def segment_folds(data) -> tuple[np.ndarray, np.ndarray]:
    """The two folds (masks over the residual vector): every segment's blocks alternate
    between A and B (module docstring); masked samples are in neither."""
    a_start = _alternate(data.t, startup_segments(data))
    parts = [a_start] * len(data.startup_channels())
    if data.stop_t is not None:
        parts.append(_alternate(data.stop_t, np.zeros(len(data.stop_t), int)))
    a = np.concatenate(parts)
    used = data.used()
    return a & used, ~a & used
