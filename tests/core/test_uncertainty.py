"""benchmark.core.uncertainty and noise_estimates: HAC standard errors, noise estimates for coloured noise, warnings."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from benchmark.core.noise_estimates import (
    NoiseEstimate,
    noise_from_periodic,
    noise_from_quiet,
    noise_from_smooth,
    noise_std,
    variance_sample_fraction,
)
from benchmark.core.uncertainty import (
    FitQuality,
    correlation,
    hac_covariance,
    misfit_ratio,
    standard_errors,
    stated_noise_covariance,
    uncertainty_warnings,
    white_covariance,
)


def ar1(rng, n, phi, std=1.0, burn=1000):
    """AR(1) noise of marginal standard deviation ``std``."""
    e = lfilter([1.0], [1.0, -phi], rng.standard_normal(n + burn))[burn:]
    return e * std * np.sqrt(1 - phi**2)


def regressors(n):
    t = np.linspace(0, 1, n)
    return np.column_stack([np.ones(n), np.sin(2 * np.pi * 1.5 * t), t - 0.5])


def coverage(phi, n=2000, draws=250, seed=0):
    rng = np.random.default_rng(seed)
    X, b = regressors(n), np.array([1.0, 2.0, -1.0])
    hit_white, hit_hac = np.zeros(3), np.zeros(3)
    for _ in range(draws):
        y = X @ b + ar1(rng, n, phi)
        bh = np.linalg.lstsq(X, y, rcond=None)[0]
        r = y - X @ bh
        hit_white += np.abs(bh - b) <= 1.96 * standard_errors(white_covariance(X, r))
        hit_hac += np.abs(bh - b) <= 1.96 * standard_errors(hac_covariance(X, r))
    return hit_white / draws, hit_hac / draws


def test_coloured_noise_white_se_undercovers_hac_covers():
    white, hac = coverage(0.9)
    print("AR(1) phi=0.9 coverage white", white, "HAC", hac)
    assert np.all(white < 0.70)
    assert np.all((hac >= 0.88) & (hac <= 0.98))


def test_white_noise_both_cover():
    white, hac = coverage(0.0, n=1000)
    print("white-noise coverage white", white, "HAC", hac)
    assert np.all((white >= 0.91) & (white <= 0.98))
    assert np.all((hac >= 0.91) & (hac <= 0.98))


def test_aligned_channels_include_cross_covariance():
    # two channels with the SAME AR(1) noise (fully cross-correlated) and the same parameter:
    # only the cross-channel terms make the standard error honest
    rng = np.random.default_rng(3)
    n, draws = 1000, 200
    t = np.linspace(0, 1, n)
    X = np.concatenate([np.column_stack([np.ones(n), t])] * 2)
    groups = np.repeat([0, 1], n)
    hit = {True: 0, False: 0}
    for _ in range(draws):
        e = ar1(rng, n, 0.8)
        y = X @ np.array([1.0, 2.0]) + np.concatenate([e, e])
        bh = np.linalg.lstsq(X, y, rcond=None)[0]
        r = y - X @ bh
        for aligned in (True, False):
            se = standard_errors(hac_covariance(X, r, groups, aligned=aligned))
            hit[aligned] += abs(bh[0] - 1.0) <= 1.96 * se[0]
    print("shared-noise coverage aligned", hit[True] / draws, "per channel", hit[False] / draws)
    assert 0.88 <= hit[True] / draws <= 0.98
    assert hit[False] / draws < 0.87  # SE too small by sqrt(2): about 83 %


def test_no_lags_is_hc0_sandwich_and_info():
    rng = np.random.default_rng(1)
    X = regressors(300)
    r = rng.standard_normal(300)
    cov, info = hac_covariance(X, r, bandwidth=1, prewhiten=False, return_info=True)
    bread = np.linalg.inv(X.T @ X)
    expect = bread @ (X * r[:, None]).T @ (X * r[:, None]) @ bread * 300 / 297
    assert np.allclose(cov, expect)
    assert info.n_lags == 0 and info.rank == 3 and info.null_space.shape == (3, 0)
    with pytest.raises(ValueError, match="contiguous"):
        hac_covariance(X, r, groups=np.tile([0, 1, 0], 100))


def test_collinear_pair_flagged():
    rng = np.random.default_rng(2)
    n = 500
    t = np.linspace(0, 1, n)
    J = np.column_stack([np.ones(n), t, 2.0 * t])  # Ls and Lr enter only as their sum
    r = 0.1 * rng.standard_normal(n)
    with pytest.warns(RuntimeWarning, match="rank 2 of 3"):
        cov, info = hac_covariance(J, r, return_info=True)
    assert info.rank == 2
    R = correlation(cov)
    assert abs(R[1, 2]) > 0.999
    msgs = uncertainty_warnings(["Rs", "Ls", "Lr"], [5.0, 0.1, 0.05], standard_errors(cov), R,
                                [0, 0, 0], [10, 1, 1])
    assert any("Ls and Lr are not separately identifiable" in m for m in msgs), msgs
    assert not any(m.startswith("Rs") for m in msgs)


def test_bound_and_large_se_messages():
    R = np.eye(2)
    msgs = uncertainty_warnings(["Rs", "J"], [9.0, 0.006], [0.1, 0.01], R, [0.1, 1e-4], [9.0, 1.0],
                                units={"Rs": "ohm"})
    assert "Rs = 9 ohm sits at its upper bound 9: widen it (on the command line ++problem.bounds.Rs=[low,high])" in msgs
    assert any(m.startswith("J is not identifiable") and "167 %" in m for m in msgs), msgs
    assert len(msgs) == 2


def test_a_parameter_at_zero_is_told_it_is_at_its_physical_limit_not_to_widen_a_bound():
    """A Coulomb friction fitted at 7e-33 N m on its lower bound 0 was told "widen bounds.fc": a
    friction below zero is no widening a user can do."""
    msgs = uncertainty_warnings(["fv", "fc"], [0.05, 7e-33], [0.01, 0.01], np.eye(2), [0.0, 0.0], [1.0, 1.0],
                                units={"fc": "N m"}, bounds_key="bounds")
    assert msgs == ["fc = 7e-33 N m sits at zero, its physical lower limit: the data show none of it (or another "
                    "parameter takes its part)", "fc is not identifiable from these data: standard error 0.01 N m is "
                    "more than 1000 times its value 7e-33 N m (limit 50 %)"]


def test_standard_errors_and_correlation_nan_safe():
    cov = np.array([[4.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    se = standard_errors(cov)
    assert np.allclose(se, [2.0, 1.0, 0.0])
    R = correlation(cov)
    assert R[0, 1] == pytest.approx(0.5) and R[0, 0] == 1.0
    assert np.all(np.isnan(R[2])) and np.all(np.isnan(R[:, 2]))
    assert np.isnan(standard_errors(np.array([[-1.0]])))[0]


FS, F0 = 10_000.0, 50.0


def supply(rng, n, f=50.03):
    t = np.arange(n) / FS
    return (325 * np.sin(2 * np.pi * f * t + 0.3) + 10 * np.sin(2 * np.pi * 5 * f * t + 1.0)
            + 4 * np.sin(2 * np.pi * 7 * f * t) + 2.0)


def test_periodic_noise_recovered_and_uncertainty_honest():
    rng = np.random.default_rng(4)
    # one long record (1 s): within 5 %; the supply is 50.03 Hz, the nominal 50 Hz is passed
    one = noise_from_periodic(supply(rng, 10_000) + ar1(rng, 10_000, 0.8, 0.7), FS, F0, n_harmonics=8)
    print("periodic 1 s:", one)
    assert abs(one.std / 0.7 - 1) < 0.05
    z, est = [], []
    for _ in range(200):
        ne = noise_from_periodic(supply(rng, 2000) + ar1(rng, 2000, 0.8, 0.7), FS, F0, n_harmonics=8)
        est.append(ne.std)
        z.append((ne.std - 0.7) / (0.7 * ne.rel_uncertainty))
    print("periodic 0.2 s: mean ratio", np.mean(est) / 0.7, "z std", np.std(z), "rel", ne.rel_uncertainty)
    assert abs(np.mean(est) / 0.7 - 1) < 0.02
    assert 0.7 <= np.std(z) <= 1.4


@pytest.mark.parametrize("phi", [0.0, 0.9])
def test_quiet_noise_recovered_and_uncertainty_honest(phi):
    rng = np.random.default_rng(5)
    one = noise_from_quiet(1.7 + ar1(rng, 20_000, phi, 0.3))
    assert abs(one.std / 0.3 - 1) < 0.05
    z, est = [], []
    for _ in range(300):
        ne = noise_from_quiet(1.7 + ar1(rng, 1000, phi, 0.3))
        est.append(ne.std)
        z.append((ne.std - 0.3) / (0.3 * ne.rel_uncertainty))
    print(f"quiet phi={phi}: mean ratio", np.mean(est) / 0.3, "z std", np.std(z), "n_eff", ne.n_effective)
    assert abs(np.mean(est) / 0.3 - 1) < 0.02
    assert 0.7 <= np.std(z) <= 1.4


def test_uncertainty_honest_for_white_plus_slow_coloured_noise():
    """A sensor's white noise beside a slowly coloured interference (the validation plant's
    current noise: white 0.02 + AR(1) 0.037 with pole 0.982): the lag-1 correlation is
    small (0.76) but the tail is long. The AR(1) ``N_eff`` alone makes the stated uncertainty
    three times too small; the summed autocorrelation keeps the z-spread near 1."""
    rng = np.random.default_rng(11)
    z, z_ar1 = [], []
    for _ in range(200):
        x = 0.02 * rng.standard_normal(6000) + ar1(rng, 6000, 0.982, 0.037)
        ne = noise_from_quiet(x)
        true = np.hypot(0.02, 0.037)
        z.append((ne.std - true) / (true * ne.rel_uncertainty))
        phi = 0.982 * 0.037**2 / true**2  # the mixture's lag-1 autocorrelation
        z_ar1.append((ne.std - true) / (true / np.sqrt(2 * 6000 * (1 - phi**2) / (1 + phi**2))))
    print("white + slow AR(1): z std", np.std(z), "with the AR(1) N_eff", np.std(z_ar1))
    assert np.std(z_ar1) > 2.5  # the old N_eff: far too confident
    assert 0.7 <= np.std(z) <= 1.4
    # white and AR(1) noise: the summed autocorrelation agrees with Bartlett's AR(1) value
    assert variance_sample_fraction(rng.standard_normal(20_000)) == pytest.approx(1.0, abs=0.02)
    phi = 0.9
    assert variance_sample_fraction(ar1(rng, 20_000, phi)) == pytest.approx((1 - phi**2) / (1 + phi**2), rel=0.15)


def test_smooth_noise_white_and_coloured_bias():
    rng = np.random.default_rng(6)
    t = np.arange(3000) / 1000.0
    speed = 150 * (1 - np.exp(-t / 0.4))
    white = noise_from_smooth(speed + 0.2 * rng.standard_normal(3000), 31)
    assert abs(white.std / 0.2 - 1) < 0.05
    coloured = noise_from_smooth(speed + ar1(rng, 3000, 0.9, 0.2), 31)
    assert coloured.std < 0.8 * 0.2  # documented: biased low for low-pass noise
    assert noise_std(speed + 0.2 * rng.standard_normal(3000), window=31).method.startswith("smooth")
    assert noise_std(supply(rng, 2000), FS, f0=F0).method.startswith("periodic")


def test_misfit_ratio_band():
    rng = np.random.default_rng(7)
    noise = NoiseEstimate(std=1.0, rel_uncertainty=0.02, n_effective=1250, method="test")
    fq = misfit_ratio(rng.standard_normal(5000), noise)
    assert isinstance(fq, FitQuality) and fq.at_noise_level
    # band: 1 + 2 * hypot(0.02, 1/sqrt(10000)) + 0.05 = 1.0947
    assert fq.threshold == pytest.approx(1 + 2 * np.hypot(0.02, 0.01) + 0.05, rel=0.01)
    assert not misfit_ratio(1.2 * rng.standard_normal(5000), noise).at_noise_level
    assert not misfit_ratio(0.5 * rng.standard_normal(5000), noise).at_noise_level


def test_a_standard_error_on_a_value_near_zero_is_not_a_huge_percentage():
    """A parameter identified at (numerically) zero gets 'more than 1000 times its value', not
    '6e35 % of its value'; an ordinary one keeps its percentage."""
    w = uncertainty_warnings(["a", "b"], [1e-36, 2.0], [0.05, 1.5], np.eye(2), [-1.0, 0.0], [1.0, 10.0],
                             units={"a": "ohm"})
    assert w == ["a is not identifiable from these data: standard error 0.05 ohm is more than 1000 times its"
                 " value 1e-36 ohm (limit 50 %)",
                 "b is not identifiable from these data: standard error 1.5 is 75 % of its value 2 (limit 50 %)"]


def report_design(rng, sigma):
    """A test report's shape: 16 readings that share two parameters and one reading that alone fixes a
    third (a locked-rotor test), each residual over its reading's stated standard error ``sigma``."""
    X = np.zeros((17, 3))
    X[:16, 0] = 1.0
    X[:16, 1] = np.linspace(-1, 1, 16)
    X[16, 2] = 1.0
    b = np.array([1.0, 0.5, 2.0])
    y = X @ b + sigma * rng.standard_normal(17)
    bh = np.linalg.lstsq(X, y, rcond=None)[0]
    return X, b, bh, y - X @ bh


@pytest.mark.parametrize("actual", [1.0, 3.0])
def test_stated_errors_cover_the_reading_that_alone_fixes_a_parameter(actual):
    """Residuals over stated errors of 1, the actual noise 1 or 3 times them: (J'J)^-1, widened by the
    reduced chi^2 (of the shared readings' scatter), covers every parameter; the sandwich gives the lone
    reading's parameter a standard error of zero (its residual is zero), and the stated rule does not."""
    rng = np.random.default_rng(4)
    hits, hits_hac = np.zeros(3), np.zeros(3)
    for _ in range(400):
        X, b, bh, r = report_design(rng, actual)
        cov, info = stated_noise_covariance(X, r)
        assert info.rank == 3
        if float(r @ r) / 14 <= 1.0:
            assert np.allclose(cov, np.linalg.inv(X.T @ X))  # the stated errors as they are, never narrowed
        hits += np.abs(bh - b) <= 1.96 * standard_errors(cov)
        hits_hac += np.abs(bh - b) <= 1.96 * standard_errors(hac_covariance(X, r, bandwidth=1.0))
    cover = hits / 400
    print("coverage of the 95 % intervals", cover, "sandwich", hits_hac / 400)
    # 1.96 standard errors cover 95 % when the stated errors hold, 93 % (Student's t, 14 degrees of freedom)
    # when the scatter sets them; three standard errors of a share of 400 draws below that
    lowest = 0.95 - 0.033 if actual == 1.0 else 0.93 - 0.038
    assert np.all((cover >= lowest) & (cover <= 0.99)), cover
    assert hits_hac[2] / 400 < 0.05  # the sandwich: zero
