"""The smoothing's noise estimate where the noise's colour is known (a speed channel's stated
filter): white noise plus noise coloured by the filter's pole, each of unknown level
(:func:`benchmark.core.noise_estimates.smooth_two_colour`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from benchmark.core.noise_estimates import noise_from_smooth, smooth_two_colour

#: (sample rate Hz, filter time constant s, window samples, record samples): a start-up's steady
#: state at 12 kHz behind a 5 ms filter, a stop at 1 kHz behind the same filter, 5 kHz and 2 ms.
CASES = [(12000.0, 5e-3, 101, 3000), (1000.0, 5e-3, 51, 3000), (5000.0, 2e-3, 101, 2000)]
#: (white std, coloured std) rad/s: white only, coloured only, both.
LEVELS = [(0.02, 0.0), (0.0, 0.04), (0.02, 0.04), (0.02, 0.02)]


def noisy_ramp(rng, n: int, pole: float, white: float, coloured: float) -> np.ndarray:
    """A slowly rising speed (rad/s) with white noise and stationary AR(1) noise of ``pole``."""
    w = rng.standard_normal(n + 2000)
    ar = lfilter([1.0], [1.0, -pole], w)[2000:] * math.sqrt(1.0 - pole**2)
    return 100.0 + 0.001 * np.arange(n) + coloured * ar + white * rng.standard_normal(n)


@pytest.mark.parametrize("fs, tau, window, n", CASES)
def test_two_colours_are_read_within_a_few_percent_where_the_smoothing_alone_reads_less(fs, tau, window, n):
    """Mean over 12 records of each level: within 4 % of the total std (measured: -1.4 to +1.4 %
    over 40 records each), where the white reading of the same residual is 0.37-0.80 of it once
    the coloured part is the larger."""
    rng = np.random.default_rng(int(fs + 1e5 * tau))
    pole = math.exp(-1.0 / (fs * tau))
    for white, coloured in LEVELS:
        total = math.hypot(white, coloured)
        two, plain = [], []
        for _ in range(12):
            x = noisy_ramp(rng, n, pole, white, coloured)
            two.append(noise_from_smooth(x, window, pole=pole).std / total)
            plain.append(noise_from_smooth(x, window).std / total)
        assert abs(np.mean(two) - 1.0) < 0.04, (white, coloured, np.mean(two))
        if coloured > white:
            assert np.mean(plain) < 0.85, (white, coloured, np.mean(plain))


def test_its_uncertainty_covers_its_spread():
    """Over 24 records of each case and level, the estimate lies within two of its own relative
    uncertainties of the truth on at least 88 % of them (95 % expected; the uncertainty is the
    spread of the estimate over simulated records of the fitted noise)."""
    rng = np.random.default_rng(11)
    inside = total_count = 0
    for fs, tau, window, n in CASES:
        pole = math.exp(-1.0 / (fs * tau))
        for white, coloured in LEVELS:
            for _ in range(24):
                est = smooth_two_colour(noisy_ramp(rng, n, pole, white, coloured), window, 2, pole)
                inside += abs(est.std / math.hypot(white, coloured) - 1.0) <= 2.0 * est.rel_uncertainty
                total_count += 1
    assert inside / total_count >= 0.88, inside / total_count


def test_white_noise_alone_reads_as_the_white_estimate_and_the_same_input_the_same_number():
    rng = np.random.default_rng(3)
    x = noisy_ramp(rng, 3000, 0.0, 0.05, 0.0)
    pole = math.exp(-1.0 / (12000.0 * 5e-3))
    two = noise_from_smooth(x, 101, pole=pole)
    assert two.std == pytest.approx(noise_from_smooth(x, 101).std, rel=0.03)
    assert "white and coloured" in two.method
    assert noise_from_smooth(x, 101, pole=pole) == two  # its uncertainty's simulations have their own seed
    assert noise_from_smooth(x, 101, pole=0.0) == noise_from_smooth(x, 101)  # no colour stated: as before


def test_a_pole_outside_the_unit_interval_is_refused():
    x = noisy_ramp(np.random.default_rng(0), 600, 0.0, 0.05, 0.0)
    with pytest.raises(ValueError, match="pole"):
        smooth_two_colour(x, 51, 2, 1.0)
