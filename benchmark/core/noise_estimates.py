"""Noise levels of one channel, each with its own relative uncertainty, that stay honest when
the noise is coloured: :func:`noise_from_quiet` (a pre-trigger), :func:`noise_from_periodic`
(a steady periodic segment), :func:`noise_from_smooth` (a slowly varying channel), dispatcher
:func:`noise_std`; :func:`estimate_noise` (a residual after any fit) and
:func:`variance_sample_fraction` (the effective sample count of a sample variance); the AR(1)
helpers they and :mod:`benchmark.core.uncertainty` share.

Pure numerics: numpy and scipy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize, signal

RHO_MAX = 0.97  #: AR(1) coefficients are clipped to +-RHO_MAX in plug-in formulas


def _ar1(x: np.ndarray) -> float:
    """Lag-1 autocorrelation of a (centred) series, 0 for degenerate input."""
    den = float(np.dot(x, x))
    return float(np.dot(x[1:], x[:-1]) / den) if den > 0 and len(x) > 2 else 0.0


@dataclass(frozen=True)
class NoiseEstimate:
    """Noise level of one channel.

    std : estimated noise standard deviation (units of the channel).
    rel_uncertainty : one-sigma relative uncertainty of ``std`` (Gaussian noise assumed:
        ``1 / sqrt(2 n_effective)``).
    n_effective : effective number of independent samples for a variance estimate.
    method : how it was obtained (plain English).
    """

    std: float
    rel_uncertainty: float
    n_effective: float
    method: str


def ar1_coefficient(e: np.ndarray) -> float:
    """AR(1) coefficient of a mean-removed residual, with Kendall's bias correction
    ``+(1 + 3 phi) / N``, clipped to +-0.97."""
    p = _ar1(e)
    return float(np.clip(p + (1 + 3 * p) / len(e), -RHO_MAX, RHO_MAX))


def ar1_gain(phi: float, omega) -> np.ndarray:
    """AR(1) spectrum relative to white noise of the same variance, at ``omega`` rad/sample."""
    return (1 - phi**2) / (1 - 2 * phi * np.cos(omega) + phi**2)


def variance_sample_fraction(e: np.ndarray) -> float:
    """``N_eff / N`` of a sample variance of the mean-removed series ``e``.

    Bartlett's ``1 / (1 + 2 sum_l r_l^2)``, ``r_l`` the sample autocorrelation summed up to the
    first lag where ``|r_l| < 2 / sqrt(N)`` (at most ``N / 4`` lags), and never more than the
    AR(1) value ``(1 - phi^2)/(1 + phi^2)``. A mixture of white and slowly coloured noise (a
    sensor's own noise beside a drifting interference) has a small lag-1 correlation and a long
    tail: the AR(1) value alone overstates ``N_eff`` (measured: three times the z-spread of the
    estimated std for white 0.02 + AR(1) 0.037 with pole 0.982, the validation plant's current
    noise); for white or AR(1) noise both agree.
    """
    x = np.asarray(e, dtype=float).ravel()
    n = len(x)
    if n < 8:
        return 1.0
    x = x - x.mean()
    phi = ar1_coefficient(x)
    ar = (1 - phi**2) / (1 + phi**2)
    lags = max(1, n // 4)
    spec = np.fft.rfft(x, 2 * n)
    acov = np.fft.irfft(spec.real**2 + spec.imag**2, 2 * n)[:lags + 1]
    if acov[0] <= 0:
        return ar
    r = acov[1:] / acov[0]
    small = np.flatnonzero(np.abs(r) < 2.0 / math.sqrt(n))
    m = int(small[0]) if len(small) else lags
    return float(min(ar, 1.0 / (1.0 + 2.0 * float(np.sum(r[:m] ** 2)))))


def estimate_noise(e: np.ndarray, p_eff: float, method: str) -> NoiseEstimate:
    """The noise of a residual ``e`` after a fit that absorbed ``p_eff`` noise degrees of freedom:
    variance ``e'e / (N - p_eff)`` and ``N_eff = (N - p_eff) f``, ``f`` of
    :func:`variance_sample_fraction` (Bartlett's formula for the variance of a sample variance;
    ``(1 - phi^2)/(1 + phi^2)`` for AR(1) noise)."""
    dof = max(len(e) - p_eff, 1.0)
    n_eff = dof * variance_sample_fraction(e)
    std = math.sqrt(float(e @ e) / dof)
    return NoiseEstimate(std, 1.0 / math.sqrt(2 * n_eff), n_eff, method)


def noise_from_quiet(x, *, detrend: bool = False) -> NoiseEstimate:
    """Noise of a segment that holds no signal (a pre-trigger): std about the mean.

    The mean removes ``g(0) = (1 + phi)/(1 - phi)`` degrees of freedom, not 1, for AR(1) noise
    (phi from the lag-1 autocorrelation); the variance is divided by ``N - g(0)``
    (``N - 2 g(0)`` with ``detrend``) so it is unbiased for AR(1) noise.
    """
    x = np.asarray(x, dtype=float).ravel()
    if len(x) < 8:
        raise ValueError(f"a quiet segment of {len(x)} samples is too short (>= 8 needed)")
    cols = [np.ones(len(x))] + ([np.linspace(-1, 1, len(x))] if detrend else [])
    A = np.column_stack(cols)
    e = x - A @ np.linalg.lstsq(A, x, rcond=None)[0]
    phi = ar1_coefficient(e)
    p_eff = min(len(cols) * (1 + phi) / (1 - phi), len(x) / 2)
    return estimate_noise(e, p_eff, "quiet segment" + (" (detrended)" if detrend else ""))


def harmonic_design(n: int, fs: float, f: float, n_harmonics: int, trend: bool):
    """Columns ``1`` (and a linear trend), then ``cos, sin`` of each harmonic of ``f`` (Hz) below
    Nyquist over ``n`` samples at ``fs`` Hz; and each column's frequency (rad per sample)."""
    t = np.arange(n) / fs
    cols, omegas = [np.ones(n)], [0.0]
    if trend:
        cols.append(np.linspace(-1, 1, n))
        omegas.append(0.0)
    for h in range(1, n_harmonics + 1):
        if h * f >= 0.499 * fs:
            break
        w = 2 * np.pi * h * f
        cols += [np.cos(w * t), np.sin(w * t)]
        omegas += [w / fs, w / fs]
    return np.column_stack(cols), np.asarray(omegas)


def least_squares_solve(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Least squares by normal equations summed in plain numpy (no multi-threaded BLAS: these
    designs are small and well conditioned); falls back to ``lstsq`` when ill-conditioned."""
    G = np.einsum("ij,ik->jk", A, A)
    if np.linalg.cond(G) > 1e10:
        return np.linalg.lstsq(A, x, rcond=None)[0]
    return np.linalg.solve(G, np.einsum("ij,i->j", A, x))


def _harmonic_residual(x, fs, f, n_harmonics, trend):
    A, om = harmonic_design(len(x), fs, f, n_harmonics, trend)
    return x - A @ least_squares_solve(A, x), om


def refine_frequency(x, fs: float, f0: float, n_harmonics: int = 10, f0_range: float = 0.005,
                     trend: bool = True) -> float:
    """Least-squares fundamental (Hz) of a constant (+ trend) + harmonics ``1..n_harmonics``
    fit, searched within ``f0 (1 +- f0_range)``: a grid of ``f0 / (4 n_harmonics n_periods)``
    steps (finer than the narrowest line's main lobe), then three Gauss-Newton steps on the
    frequency (variable projection)."""
    x = np.asarray(x, dtype=float).ravel()
    n = len(x)
    t = np.arange(n) / fs
    step = f0 / (4 * max(n_harmonics, 1) * n * f0 / fs)
    grid = np.arange(f0 * (1 - f0_range), f0 * (1 + f0_range) + step, step)
    f = float(grid[int(np.argmin([np.sum(_harmonic_residual(x, fs, g, n_harmonics, trend)[0] ** 2)
                                  for g in grid]))])
    for _ in range(3):
        A, om = harmonic_design(n, fs, f, n_harmonics, trend)
        c = least_squares_solve(A, x)
        m = 1 + trend
        h = (np.arange(len(om) - m) // 2 + 1)[::2]
        a, b = c[m::2], c[m + 1::2]
        jf = 2 * np.pi * t * (A[:, m + 1::2] @ (-a * h) + A[:, m::2] @ (b * h))
        df = float(least_squares_solve(np.column_stack([A, jf]), x)[-1])
        f += float(np.clip(df, -step, step))
        if abs(df) < 1e-9 * f:
            break
    return f


def noise_from_periodic(x, fs: float, f0: float, n_harmonics: int = 10, *, trend: bool = True,
                        refine_f0: bool = True, f0_range: float = 0.005) -> NoiseEstimate:
    """Noise of a steady-state periodic segment (a supply voltage, a steady current).

    Least-squares fit of a constant (+ a linear trend) + harmonics ``1..n_harmonics`` of
    ``f0`` over the largest whole number of periods; the noise is the std of what is left:
    lines go, coloured noise stays (except the little of it the fit absorbs, removed below).

    Parameters
    ----------
    x : samples of the channel; fs : sample rate in Hz; f0 : fundamental in Hz.
    n_harmonics : highest harmonic fitted (those at or above Nyquist are skipped).
    trend : fit a linear drift too.
    refine_f0 : refine f0 within ``+-f0_range`` (relative) by minimising the residual: a
        0.1 % error in f0 leaves a beat of the fundamental far above the noise.

    Notes
    -----
    Each fitted column at ``omega`` absorbs ``g(omega)`` noise degrees of freedom, ``g`` the
    AR(1) spectrum of the residual relative to white; the variance is divided by
    ``N - sum g``. ``N_eff = (N - sum g)(1 - phi^2)/(1 + phi^2)``. Non-periodic signal left
    in the segment (a drifting amplitude, interharmonics) counts as noise.
    """
    x = np.asarray(x, dtype=float).ravel()
    if len(x) * f0 / fs < 1:
        raise ValueError(f"segment of {len(x) / fs:.4g} s is shorter than one period of {f0} Hz")
    f = float(f0)
    if refine_f0:
        f = refine_frequency(x, fs, f0, n_harmonics, f0_range)
    n = int(round(math.floor(len(x) * f / fs) * fs / f))
    e, om = _harmonic_residual(x[:min(n, len(x))], fs, f, n_harmonics, trend)
    phi = ar1_coefficient(e)
    p_eff = min(float(np.sum(ar1_gain(phi, om))) + (1 if refine_f0 else 0), len(e) / 2)
    return estimate_noise(e, p_eff, f"periodic fit ({f:.4f} Hz, {(len(om) - 1 - trend) // 2} harmonics)")


def noise_from_smooth(x, window: int, polyorder: int = 2, pole: float = 0.0) -> NoiseEstimate:
    """Noise of a slowly varying channel (a speed): residual from a Savitzky-Golay fit.

    The residual ``e = (I - H) x`` of white noise has variance ``sigma^2 (1 - h_0)``, ``h_0``
    the centre tap of the filter (its own gain); it is divided out. Only interior samples
    (half a window from each end) are used. ``N_eff = N / (1 + 2 sum_l r_l^2)`` from the
    residual's sample autocorrelation over one window.

    Bias for coloured noise: the filter passes as "signal" every noise component below its
    cut-off (about ``(polyorder + 1) / (2 window)`` cycles per sample), so the estimate is the
    high-frequency part of the noise scaled as if the noise were white. For low-pass (AR(1),
    phi > 0) noise it is biased low; measured (order 2, 3000 samples): phi = 0.5: -13 % in std
    with a 21-sample window, -5 % with 51; phi = 0.9: -56 % and -37 %. So: make ``window`` as
    long as the signal's curvature allows (the signal must be a quadratic over one window,
    else it leaks in and biases high); fine for quantisation and ripple-type noise; prefer
    :func:`noise_from_quiet` when a rest segment exists. ``rel_uncertainty`` covers the
    random error only (measured: 10 % conservative for white noise), not this bias.

    Where the colour is known, ``pole`` > 0 (a sensor's first-order filter, ``exp(-dt/tau)``
    per sample), the noise is taken as white noise plus noise coloured by that pole (a
    tachogenerator's noise before its RC filter and an acquisition's after it), each of unknown
    level: :func:`smooth_two_colour`.
    """
    if pole > 0.0:
        return smooth_two_colour(x, window, polyorder, pole)
    window, e = smooth_residual(x, window, polyorder)
    h0 = float(signal.savgol_coeffs(window, polyorder)[window // 2])
    r = np.array([np.dot(e[lag:], e[:-lag]) for lag in range(1, window + 1)]) / float(e @ e)
    n_eff = len(e) / (1 + 2 * float(np.sum(r**2)))
    std = math.sqrt(float(e @ e) / (len(e) * (1.0 - h0)))
    return NoiseEstimate(std, 1.0 / math.sqrt(2 * n_eff), n_eff,
                         f"smooth (Savitzky-Golay window {window}, order {polyorder})")


def smooth_residual(x, window: int, polyorder: int) -> tuple[int, np.ndarray]:
    """(the odd window used, the interior residual of a Savitzky-Golay fit of ``x``: half a window
    from each end left out); ``x`` must hold three windows."""
    x, window = np.asarray(x, dtype=float).ravel(), int(window) | 1
    if window <= polyorder + 1:
        raise ValueError(f"a smoothing window of {window} samples needs an order below {window - 1}")
    if len(x) < 3 * window:
        raise ValueError(f"a steady part of {len(x)} samples, where a smooth fit over {window} needs {3 * window}")
    half = window // 2
    return window, (x - signal.savgol_filter(x, window, polyorder, mode="interp"))[half:len(x) - half]


#: Simulated records of the fitted noise behind :func:`smooth_two_colour`'s uncertainty.
TWO_COLOUR_REPLICATES = 32


def _residual_autocovariance(window: int, polyorder: int, pole: float, lags: int) -> np.ndarray:
    """(lags + 1, 2) the autocovariance at lags 0..``lags`` of the Savitzky-Golay residual of unit
    white noise (column 0) and of unit-variance AR(1) noise of ``pole`` (column 1)."""
    c = -signal.savgol_coeffs(window, polyorder)
    c[window // 2] += 1.0
    g = np.correlate(c, c, "full")  # the residual filter's own autocorrelation, lags -(W-1)..W-1
    m = np.arange(-(window - 1), window)
    d = np.abs(np.arange(lags + 1)[:, None] - m[None, :])
    return np.column_stack([np.sum(g * (d == 0), axis=1), np.sum(g * pole ** d.astype(float), axis=1)])


def _two_colour_levels(e: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """(white variance, coloured variance) fitted (non-negative least squares) to the
    autocovariance of a Savitzky-Golay residual ``e`` at the lags of ``kernel``."""
    n = len(e)
    gamma = np.array([np.dot(e[k:], e[:n - k]) / n for k in range(len(kernel))])
    return optimize.nnls(kernel, gamma)[0]


def smooth_two_colour(x, window: int, polyorder: int, pole: float) -> NoiseEstimate:
    """Noise of a slowly varying channel whose noise is white noise plus noise coloured by a
    known first-order ``pole`` (per sample), each of unknown level: both variances fitted to the
    Savitzky-Golay residual's autocovariance over one window of lags (the two colours leave it
    different shapes), the std that of their sum. A noise coloured below the smoothing's
    cut-off is mostly taken for signal by :func:`noise_from_smooth` (measured: a 5 ms filter at
    12 kHz, window 101: 0.37 of its std; 1 kHz, window 51: 0.78); this estimate came within 4 %
    (mean of 20 records each, white, coloured and both). Its relative uncertainty is the spread
    of the estimate over :data:`TWO_COLOUR_REPLICATES` simulated records of the fitted noise
    (fixed seed), at least the white estimate's ``1 / sqrt(2 N_eff)``: the coloured level is read
    through the small share of it the residual keeps."""
    x = np.asarray(x, dtype=float).ravel()
    window, e = smooth_residual(x, window, polyorder)
    if not 0.0 < pole < 1.0:
        raise ValueError(f"pole must be in (0, 1), got {pole}")
    kernel = _residual_autocovariance(window, polyorder, pole, window)
    levels = _two_colour_levels(e, kernel)
    std = math.sqrt(float(levels.sum()))
    white = noise_from_smooth(x, window, polyorder)
    rng = np.random.default_rng(0)
    sims = []
    for _ in range(TWO_COLOUR_REPLICATES):
        w = rng.standard_normal(len(x) + 1)
        w[0] /= math.sqrt(1.0 - pole**2)
        coloured = math.sqrt(1.0 - pole**2) * signal.lfilter([1.0], [1.0, -pole], w)[1:]
        sim = math.sqrt(levels[0]) * rng.standard_normal(len(x)) + math.sqrt(levels[1]) * coloured
        sims.append(math.sqrt(float(_two_colour_levels(smooth_residual(sim, window, polyorder)[1], kernel).sum())))
    u = max(float(np.std(sims)) / max(std, 1e-300), white.rel_uncertainty) if std > 0 else white.rel_uncertainty
    share = float(levels[1] / levels.sum()) if std > 0 else 0.0
    return NoiseEstimate(std, u, 1.0 / (2.0 * u * u), f"smooth (Savitzky-Golay window {window}, order {polyorder}), "
                                                      f"white and coloured by pole {pole:.4g} ({share:.0%} coloured)")


def noise_std(x, fs=None, *, f0=None, n_harmonics: int = 10, window=None, polyorder: int = 2) -> NoiseEstimate:
    """Dispatcher: :func:`noise_from_periodic` when ``f0`` (and ``fs``, Hz) are given,
    :func:`noise_from_smooth` when ``window`` (samples) is, else :func:`noise_from_quiet`."""
    if f0 is not None:
        if fs is None:
            raise ValueError("noise_std: f0 needs fs (sample rate in Hz)")
        return noise_from_periodic(x, fs, f0, n_harmonics)
    if window is not None:
        return noise_from_smooth(x, window, polyorder)
    return noise_from_quiet(x)
