"""The sweep diagnosis's noise estimate when the noise grows with the reading (an instrument's error as a
share of its reading): its shape and level from the residual alone, no false gap on an exact circuit, and a
magnetising-branch effect still named.

The textbook sweep is written here with numpy and the circuit's closed form, as a user would: 40 slips
log-spaced from 0.001 to 1 at one voltage, one table (the diagnosis's former single noise level, a typical
reading's, called such a sweep ``unexplained`` on 30 of 30 draws of 1 % of each reading).
"""

import numpy as np
import pytest

from benchmark.core.effects import load_effects
from benchmark.problems.admittance.circuit import input_admittance
from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.diagnosis.pipeline import AdmittanceDiagnosisSettings, diagnose_sweep
from benchmark.problems.admittance.diagnosis.sweep_model import SweepData, noise_estimate
from synthetic.admittance import make_dataset
from tests.conftest import compose_config

EFFECTS = load_effects("admittance")
SLIP = np.logspace(-3, 0, 40)
# R1t, X1, R2, X2, R0, X0 (ohm): a 400 V, 4-pole textbook motor, its magnetising branch in series form
Y_EXACT = input_admittance(SLIP, 0.5, 1.2, 0.45, 1.2, 1.2, 29.9)


def textbook_sweep(seed: int, constant: float, share: float) -> AdmittanceData:
    """Noise of standard deviation ``sqrt(constant^2 + (share |Y|)^2)`` (S) on G and on B."""
    rng = np.random.default_rng(seed)
    sd = np.hypot(constant, share * np.abs(Y_EXACT))
    return AdmittanceData(
        frequency=50.0,
        pole_pairs=2,
        slip=SLIP,
        G=Y_EXACT.real + sd * rng.standard_normal(SLIP.size),
        B=Y_EXACT.imag + sd * rng.standard_normal(SLIP.size),
        voltage=np.full(SLIP.size, 230.9),
        stator_dc_resistance=(0.5, 0.5),
    )


@pytest.mark.parametrize(
    ("constant", "share", "expect_share"),
    [(0.0, 0.01, (0.9, 1.0)), (2e-3, 0.0, (0.0, 0.1)), (1e-3, 5e-3, (0.3, 0.7))],
    ids=["reading", "constant", "mixed"],
)
def test_shape_and_level_of_the_noise_from_the_residual_alone(constant, share, expect_share):
    """Over 40 draws: no bias, each reading's noise within about 20 % (the median of 37 third differences of
    each of G and B; the diagnosis states 1.17/sqrt(40) = 18.5 % for its level), the share's median right.
    On 300 draws the log error's RMS was 0.20 (reading), 0.20 (constant), 0.22 (mixed) at a typical reading."""
    truth = np.hypot(constant, share * np.abs(Y_EXACT))
    log_error, shares = [], []
    for seed in range(40):
        data = SweepData.from_data(textbook_sweep(seed, constant, share))
        noise = noise_estimate(data, data.Y - Y_EXACT, floor=1e-5)
        log_error.append(np.log(noise.per_reading / truth))
        shares.append(noise.proportional_share)
    log_error = np.array(log_error)
    rms = np.sqrt(np.mean(log_error**2, axis=0))  # per reading, over the draws
    assert abs(np.mean(log_error)) < 0.06
    assert np.median(rms) < 0.26 and np.max(rms) < 0.35, (np.median(rms), np.max(rms))
    assert expect_share[0] <= np.median(shares) <= expect_share[1], np.median(shares)


def test_one_level_is_the_former_estimate_when_the_noise_is_constant():
    """Where the share is 0 (on most draws of constant noise), every reading's noise is the former estimate:
    the median of |third difference| / sqrt(20), G's and B's pooled."""
    constant = 0
    for seed in range(10):
        data = SweepData.from_data(textbook_sweep(seed, 2e-3, 0.0))
        r = data.Y - Y_EXACT
        noise = noise_estimate(data, r, floor=1e-5)
        if noise.proportional_share > 0.0:
            continue
        constant += 1
        d = np.diff(r, 3)
        level = [1.4826 * np.median(np.abs(c)) / np.sqrt(20.0) for c in (d.real, d.imag)]
        assert np.all(noise.per_reading == np.sqrt(0.5 * (level[0] ** 2 + level[1] ** 2)))
        assert noise.reading_fraction == 0.0 and noise.constant_S == noise.per_reading[0]
    assert constant >= 5, constant


def test_an_exact_circuit_with_noise_in_proportion_to_each_reading_has_no_gap():
    fractions = []
    for seed in range(6):
        doc = diagnose_sweep(textbook_sweep(seed, 0.0, 0.01), EFFECTS, AdmittanceDiagnosisSettings())
        nl = doc["noise_level"]
        assert doc["status"] == "no_gap" and doc["effects"] == [], (seed, doc["gap_before"], doc["noise_band"])
        assert nl["proportional_share"] >= 0.8 and nl["source"] == "estimated", (seed, nl)
        fractions.append(nl["reading_fraction"])
    assert 0.85 < np.mean(fractions) / 0.01 < 1.15, fractions


def test_a_main_saturation_is_named_under_noise_in_proportion_to_the_reading():
    """Lindsay and Barton's bare machine at 20 and 50 V, up and down, a main saturation of 0.05 (its range
    0.01-0.08); noise 0.01 % of full scale plus 0.1 % of each reading. Weighted by each reading's noise, the
    magnetising readings' small noise shows it: held-out gap 2.2-4.5 on these six draws (the former single
    level: 1.6-2.5, two of them only partly explained). At 0.03 it is named on four of six, at the middle of
    its range on two of four: what the noise's shape leaves uncertain is not called a gap."""
    for seed in range(1, 7):
        cfg = compose_config(
            [
                "problem=admittance",
                "motor.test.voltages=[20.0,50.0]",
                "motor.test.down_sweep=true",
                "motor.test.full_scale_admittance=1.0",
                "effects=[main_saturation]",
                "effect_size={main_saturation:0.05}",
                "noise.admittance_fraction=0.0001",
                "noise.admittance_reading_fraction=0.001",
                f"noise.seed={seed}",
            ],
            name="synthetic",
        )
        data, _truth = make_dataset(cfg)
        doc = diagnose_sweep(data, EFFECTS, AdmittanceDiagnosisSettings())
        assert doc["status"] == "explained" and doc["effects"] == ["main_saturation"], (seed, doc["status"])
        assert doc["gap_before"]["heldout_chi2_per_residual"] > 2.0, seed


def test_no_gap_is_claimed_where_a_noise_shape_the_data_allow_leaves_none():
    """The blind run's effect-free set 5 (seed 2024, 0.01 % of full scale plus 0.1 % of each reading): few of
    its readings are small, the likelihood's best shape is all proportional (the constant part missed), and
    under it the base sits above the band (1.29 against 1.21), which the likelihood's best shape alone called
    `unexplained`. A shape within the 95 % interval puts it inside: `no_gap`."""
    from benchmark.analysis import blind
    from benchmark.blind_admittance import draw_sets, set_config
    from benchmark.problems.admittance.diagnosis.run import render_sweep_markdown

    cfg = compose_config(["n=60", "seed=2024", "noise.admittance_fraction=0.0001",
                          "noise.admittance_reading_fraction=0.001"], name="blind_admittance")
    settings = blind.BlindSettings.from_run(cfg)
    draw = draw_sets(settings)[5]
    assert draw["effects"] == []
    data, _truth = make_dataset(set_config(settings, draw))
    doc = diagnose_sweep(data, EFFECTS, AdmittanceDiagnosisSettings())
    upper = doc["noise_band"][1]
    assert doc["noise_level"]["proportional_share"] > 0.95
    assert doc["gap_before"]["heldout_rms_over_noise"] > upper > doc["lenient_heldout_rms_over_noise"]
    assert doc["status"] == "no_gap" and doc["effects"] == []
    doc.pop("_models")
    assert "No gap is claimed: under a noise shape the data allow" in render_sweep_markdown(doc | {"data": "set 5"})
