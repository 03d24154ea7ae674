"""The measured voltage's noise, carried through the model, is part of each channel's noise level
(:mod:`benchmark.problems.timedomain.diagnosis.input_noise`).

Checked on the independent plant (``synthetic.independent``, no code shared with the diagnosis):
the same grid-fed start of a 7.5 kW motor recorded twice, once with a noisy voltage probe
(1 V white per phase) and once with a clean one, every other noise draw identical. The model at
the plant's true parameters, driven by the noisy voltages, misses the currents by more than the
current sensor's noise; the difference of its two simulations is what the voltage noise really
does, and the estimate made from the noisy record alone must find it.
"""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.problems.timedomain.conditioning import condition_dataset
from benchmark.problems.timedomain.data import load_startup_dataset
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
from benchmark.problems.timedomain.diagnosis.input_noise import with_voltage_noise
from benchmark.problems.timedomain.diagnosis.pipeline import base_context, friction_scale
from synthetic.independent import make_dataset, make_spec, write_dataset


def _record(tmp_path, name, voltage_white, scenario="dol", seed=5, motor="simulink_7k5"):
    spec = make_spec(motor, scenario, [], seed=seed, duration=0.8)
    spec["noise"]["voltage_white"] = voltage_white
    made = make_dataset(spec)
    folder = write_dataset(made, tmp_path / name)
    data = DiagnosisData.from_dataset(condition_dataset(load_startup_dataset(folder)))
    truth = dict(made.truth["parameters"])
    ctx = base_context(data, truth, None)
    fc_scale = friction_scale(truth, ctx)

    def model_of(d):
        return JointModel(d, 2, [], ctx, truth, fc_scale, 5.0)

    model = model_of(data)
    return data, model, np.array([truth[n] for n in model.base_names]), model_of


def _rms_over_noise(data, model, x):
    r = model.residuals(x[None, :])[0]
    return {ch: float(np.sqrt(np.mean(r[s] ** 2))) for ch, s in data.channel_slices().items()
            if ch in ("i_alpha", "i_beta")}


@pytest.fixture(scope="module")
def grid_start(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("input_noise")
    return _record(tmp, "noisy", 1.0), _record(tmp, "clean", 0.0)


def test_the_voltage_noise_through_the_model_is_found_from_the_noisy_record_alone(grid_start):
    (data, model, x, _), (clean, clean_model, _, _) = grid_start
    y_noisy, y_clean = model.simulate(x[None, :])[0], clean_model.simulate(x[None, :])[0]
    updated, record = with_voltage_noise(data, model, x)
    assert record is not None
    # both currents together: the error is of low frequency, so one record holds few independent
    # samples of it and each channel alone scatters by 15-20 %
    s = np.r_[data.channel_slices()["i_alpha"], data.channel_slices()["i_beta"]]
    true = float(np.sqrt(np.mean((y_noisy[s] - y_clean[s]) ** 2)))
    estimate = float(np.sqrt(np.mean([record["propagated_std"][ch] ** 2 for ch in ("i_alpha", "i_beta")])))
    assert true > 0.8 * data.noise["i_alpha"].std  # large enough to matter on this record
    assert 0.8 < estimate / true < 1.25, (estimate, true)
    # the voltage noise itself, against the difference of the two conditioned records
    for ch in ("v_alpha", "v_beta"):
        true_v = float(np.std(getattr(data, ch) - getattr(clean, ch)))
        assert abs(record["voltage_std"][ch] / true_v - 1) < 0.1, (ch, record["voltage_std"][ch], true_v)


def test_with_it_the_true_parameters_sit_at_the_noise_level_and_without_it_above(grid_start):
    (data, model, x, model_of), (clean, clean_model, _, _) = grid_start
    before = _rms_over_noise(data, model, x)
    updated, _ = with_voltage_noise(data, model, x)
    after = _rms_over_noise(updated, model_of(updated), x)
    assert min(before.values()) > 1.2, before  # the record shows the problem (1.31 and 1.59)
    excess_before = np.mean([v**2 for v in before.values()]) - 1
    excess_after = np.mean([v**2 for v in after.values()]) - 1
    assert abs(excess_after) < 0.2 * excess_before, (before, after)
    # the clean record is at the noise level already, and adding its (tiny) voltage noise keeps it there
    clean_before = _rms_over_noise(clean, clean_model, x)
    clean_updated, rec = with_voltage_noise(clean, clean_model, x)
    assert all(0.9 < v < 1.1 for v in clean_before.values()), clean_before
    assert all(v < 0.05 * clean.noise[ch].std for ch, v in rec["propagated_std"].items() if ch != "speed")


def test_the_estimate_is_unbiased_over_records_whose_noise_comes_from_the_steady_states_fit(tmp_path):
    """Without a pre-trigger the voltage's noise is what the drifting-harmonics fit of the steady
    state leaves, and that fit takes out the bands about DC and the harmonics, which the machine
    turns into current error most. Realisations that repeated that residual came out low on
    average: over these eight records (two motors, four noise draws each) 0.95 and 0.89 of the
    true propagated noise in ``i_alpha`` and ``i_beta`` (each record scatters by 10-20 %: one
    realisation of a low-frequency error). Drawn from its smoothed spectrum, with what the fit
    took scaled back, the mean is 1.01 and 1.04."""
    ratios, claimed = [], []
    for motor in ("simulink_7k5", "simulink_5hp"):
        for seed in (5, 6, 7, 8):
            noisy, model, x, _ = _record(tmp_path, f"{motor}_{seed}_noisy", 1.0, seed=seed, motor=motor)
            clean, clean_model, _, _ = _record(tmp_path, f"{motor}_{seed}_clean", 0.0, seed=seed, motor=motor)
            y_noisy, y_clean = model.simulate(x[None, :])[0], clean_model.simulate(x[None, :])[0]
            _, record = with_voltage_noise(noisy, model, x)
            assert "periodic fit" in record["voltage_method"]  # no pre-trigger: the fit's residual
            for ch in ("i_alpha", "i_beta"):
                s = noisy.channel_slices()[ch]
                ratios.append(record["propagated_std"][ch] / float(np.sqrt(np.mean((y_noisy[s] - y_clean[s]) ** 2))))
                claimed.append(record["propagated_rel_uncertainty"][ch])
    assert 0.96 < np.mean(ratios) < 1.08, ratios
    # the uncertainty it states is that scatter: the record's own noise is one realisation (claimed as the
    # spread of the realisations' mean, a third of it, it put 9 of these 16 beyond two of its uncertainties)
    scatter = float(np.sqrt(np.mean(np.log(ratios) ** 2)))
    print("scatter of the estimate over the truth", scatter, "claimed", np.mean(claimed),
          "beyond two", int(np.sum(np.abs(np.log(ratios)) > 2 * np.asarray(claimed))))
    assert 0.6 < scatter / float(np.sqrt(np.mean(np.square(claimed)))) < 1.6, (scatter, claimed)
    assert np.mean(np.abs(np.log(ratios)) > 2 * np.asarray(claimed)) < 0.2, (ratios, claimed)


def test_inverter_records_are_left_alone(tmp_path):
    data, model, x, _ = _record(tmp_path, "six_step", 1.0, scenario="six_step")
    updated, record = with_voltage_noise(data, model, x)
    assert record is None and updated is data
