"""Data conditioning of Alonge et al. section 3.2.

Speed carries quantisation noise; it is smoothed by a zero-phase ("anticausal") filter: a
5th-order Chebyshev type-I low-pass, 0.5 dB ripple, 50 Hz cut-off, run forward and backward
(order 10 overall). The electrical part of the free stop (braking by the trapped rotor flux) is
detected from the speed record and dropped before the mechanical pre-identification.
"""

from __future__ import annotations

import numpy as np
from scipy import signal


def zero_phase_lowpass(x: np.ndarray, sample_time: float, cutoff_hz: float = 50.0, order: int = 5,
                       ripple_db: float = 0.5) -> np.ndarray:
    """Chebyshev-I low-pass run forward and backward (no phase lag). ``sample_time`` in s."""
    fs = 1.0 / sample_time
    if cutoff_hz >= 0.5 * fs:
        return np.asarray(x, dtype=float).copy()
    sos = signal.cheby1(order, ripple_db, cutoff_hz, btype="low", fs=fs, output="sos")
    return signal.sosfiltfilt(sos, np.asarray(x, dtype=float))


def free_motion_start(t: np.ndarray, speed: np.ndarray) -> int:
    """Index where the purely mechanical free motion of a stop record begins.

    During the electrical part the trapped rotor flux brakes the rotor far harder than
    friction does. The deceleration of free motion is affine in speed (``w/tau_m + fc/J``), so
    it is fitted on the later half of the moving record and the electrical part is taken to
    last until the measured deceleration last exceeds that fit by a clear margin, plus the
    same time again as a safety margin (the electrical transient decays exponentially).
    """
    t = np.asarray(t, float)
    w = np.asarray(speed, float)
    moving = np.flatnonzero(w > 0.05 * w[0])
    end = moving[-1] + 1 if len(moving) else len(w)
    if end < 20:
        return 0
    dt = float(np.median(np.diff(t)))
    ws = zero_phase_lowpass(w[:end], dt, cutoff_hz=min(50.0, 0.2 / dt))
    decel = -np.gradient(ws, dt)
    half = end // 2
    A = np.column_stack([ws[half:end], np.ones(end - half)])
    coef, *_ = np.linalg.lstsq(A, decel[half:end], rcond=None)
    excess = decel[:end] - (coef[0] * ws + coef[1])
    scale = np.median(np.abs(excess[half:end])) * 1.4826 + 1e-3 * abs(coef[1]) + 1e-9
    # the fit's own level: the electrical braking is a large multiple of the free deceleration
    threshold = max(10.0 * scale, 0.5 * float(np.median(decel[half:end])))
    above = np.flatnonzero(excess[:half] > threshold)
    if len(above) == 0:
        return 0
    k = int(above[-1])
    return min(end - 10, 2 * k + 1)
