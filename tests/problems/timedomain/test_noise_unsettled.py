"""The noise estimate of a record that ends before its steady state
(:func:`benchmark.problems.timedomain.noise.startup_noise`).

Independent plant (``synthetic.independent``): a 1 kW grid-fed start with a load machine of 1.3
times the motor's inertia on a flexible coupling, recorded for 1 s, which ends while the speed
still creeps towards synchronism; coloured current noise (AR(1), pole 0.97). The same record
made again with the current noise switched off gives the noise that was really added. A
quadratic envelope cannot follow the start-up current as it falls in its last periods, so the
steady-state fit leaves signal in its residual: 1.4-1.9 times the true noise, which would hide
a gap of that size as "no gap". Piecewise-linear envelopes must come within 20 %.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

import benchmark.problems.timedomain.noise as noise
from benchmark.problems.timedomain.conditioning import condition_dataset
from benchmark.problems.timedomain.data import load_startup_dataset
from synthetic.independent import make_dataset, make_spec, write_dataset


def _record(spec, folder):
    return condition_dataset(load_startup_dataset(write_dataset(make_dataset(spec), folder))).startups[0]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_start_that_has_not_settled_gets_its_noise_right(tmp_path, seed, monkeypatch):
    spec = make_spec("paper_1kw", "dol", ["two_mass"], seed=seed, duration=1.0, forms={"two_mass": "spring"})
    spec["effects"][0].update({"size": 145.0, "inertia_ratio": 1.3, "damping_ratio": 0.037})
    spec["noise"].update({"voltage_white": 0.0, "voltage_quantum": 0.0})
    clean_spec = copy.deepcopy(spec)
    for k in ("current_white", "current_colored", "current_quantum"):
        clean_spec["noise"][k] = 0.0
    rec, clean = _record(spec, tmp_path / "noisy"), _record(clean_spec, tmp_path / "clean")
    n = len(rec.speed)
    last, before = np.mean(rec.speed[-n // 20:]), np.mean(rec.speed[-3 * n // 20:-2 * n // 20])
    assert last > 1.001 * before  # still accelerating in the record's last tenth

    def estimate():
        return noise.startup_noise(rec.t, rec.v_alpha, rec.v_beta, rec.i_alpha, rec.i_beta, rec.speed, 50.0, True)

    new = estimate()
    monkeypatch.setattr(noise, "UNSETTLED_RATIO", 0.0)  # the quadratic envelope kept, as before
    old = estimate()
    for ch in ("i_alpha", "i_beta"):
        true = float(np.std(getattr(rec, ch) - getattr(clean, ch)))
        assert old[ch].std > 1.35 * true, (ch, old[ch].std, true)
        assert 0.85 < new[ch].std / true < 1.2, (ch, new[ch].std, true)
        assert "piecewise linear" in new[ch].method and new[ch].rel_uncertainty >= noise.UNSETTLED_REL_UNCERTAINTY


def test_a_low_live_voltage_with_moving_currents_is_no_quiet_pre_trigger():
    """An inverter's V/f boost is below 5 % of the final voltage, so the voltage alone takes it
    for a pre-trigger; the current it drives is signal, not noise. Noise only (white plus
    AR(1), pole 0.91) is quiet; the same noise on a 2 A current at 1 Hz rising from zero is not,
    and the whole-record estimate then uses the steady state instead."""
    from scipy.signal import lfilter

    rng = np.random.default_rng(3)
    n = 600
    coloured = lfilter([np.sqrt(1 - 0.91**2)], [1, -0.91], 0.016 * rng.standard_normal(n))
    noise_only = 0.026 * rng.standard_normal(n) + coloured
    t = np.arange(n) / 12000.0
    boost = 2.0 * (t / t[-1]) * np.sin(2 * np.pi * 1.0 * t + 0.3)
    assert noise.quiet(noise_only, noise_only[::-1])
    assert not noise.quiet(noise_only + boost, noise_only)
