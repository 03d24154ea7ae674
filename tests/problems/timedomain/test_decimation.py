"""A start-up sampled far faster than the model needs is read at a longer sample time
(``decimate`` in meta.yaml, :mod:`benchmark.problems.timedomain.decimation`): the loader says so
when it is not asked, the reading keeps the switch-on and the volt-seconds, and the motor is
identified from it as from the full record."""

from __future__ import annotations

import shutil
import warnings

import numpy as np
import pytest

from benchmark.core.errors import DataError, DataWarning
from benchmark.problems.timedomain.data import load_startup_dataset, write_startup_dataset
from benchmark.problems.timedomain.decimation import held_means, interval_means, suggested_factor
from synthetic.timedomain import make_dataset
from tests.conftest import compose_config, identify_folder, with_meta_key

RATE_24K = ("motor.test.sample_time=4.1666666666666665e-05", "motor.test.samples_per_state=80")


def _synthetic(folder, *overrides):
    ds, truth = make_dataset(compose_config(["noise=noisy", *overrides], name="synthetic"))
    return write_startup_dataset(folder, ds, truth=truth)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """Noisy 1 s starts of the paper's motor sampled at 24 kHz, direct-on-line and six-step."""
    root = tmp_path_factory.mktemp("rate24")
    return {w: _synthetic(root / w, *RATE_24K, f"motor.test.waveform={w}") for w in ("sinusoidal", "six_step")}


@pytest.fixture
def dol_24k(made, tmp_path):
    """The direct-on-line start (a test's own copy)."""
    return shutil.copytree(made["sinusoidal"], tmp_path / "dol24")


def test_the_means_are_centred_and_a_held_inputs_volt_seconds_are_kept():
    x = np.arange(10.0) ** 2
    # k = 2: samples 0, 2, 4, ... each the mean of its neighbours at half weight and itself
    assert np.allclose(interval_means(x, 2), [(0 / 2 + 0 + 1 / 2) / 2] + [(x[j - 1] / 2 + x[j] + x[j + 1] / 2) / 2
                                                                          for j in (2, 4, 6, 8)])
    assert np.allclose(interval_means(x, 3), [(0 + 0 + 1) / 3] + [x[j - 1:j + 2].mean() for j in (3, 6)]
                       + [(x[8] + 2 * x[9]) / 3])
    held = held_means(x, 4)  # intervals [0, 4), [4, 8), [8, 10)
    assert np.allclose(held, [x[:4].mean(), x[4:8].mean(), x[8:].mean()])
    assert np.isclose(np.sum(held * [4, 4, 2]), x.sum())
    assert suggested_factor(1 / 48e3, 50.0) == 4 and suggested_factor(1 / 12e3, 50.0) == 1
    assert suggested_factor(1 / 48e3, 400.0) == 1  # a 400 Hz supply: 200 samples per period are 80 kHz


def test_the_loader_reads_every_kth_sample_and_says_so(dol_24k, made):
    with pytest.warns(DataWarning, match=r"sampled at 24 kHz.*decimate: 2"):
        full = load_startup_dataset(dol_24k)
    ds = with_meta_key(dol_24k, "decimate", 2)
    rec, raw = ds.startups[0], full.startups[0]
    assert ds.sample_time == pytest.approx(2 * full.sample_time) and len(rec.t) == -(-len(raw.t) // 2)
    assert np.array_equal(rec.t, raw.t[::2])
    # the generator's chords, sampled every 2nd sample, are a continuous voltage's samples: their
    # volt-seconds restored by the conditioning (v - its second difference / 12), where the chords' were not
    v = raw.v_alpha[::2]
    assert np.allclose(rec.v_alpha[5:-1], v[5:-1] - (v[4:-2] - 2 * v[5:-1] + v[6:]) / 12, rtol=0, atol=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.array_equal(raw.v_alpha, load_startup_dataset(made["sinusoidal"]).startups[0].v_alpha)
    assert any("one sample in 2" in line for line in ds.conditioning)
    assert len(ds.stops[0].t) == len(full.stops[0].t)  # the stop keeps its own sample time
    assert with_meta_key(dol_24k, "channel_skew", 0.8).channel_skew == pytest.approx(0.4)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)  # asked: no suggestion
        with_meta_key(dol_24k, "channel_skew", None)


@pytest.mark.parametrize("bad, words", [(0, "1 (none) or more"), (2.5, "whole number"), ("four", "whole number"),
                                        (True, "whole number"), (10**9, "leaves one sample")])
def test_a_bad_factor_names_the_key(dol_24k, bad, words):
    with pytest.raises(DataError) as err:
        with_meta_key(dol_24k, "decimate", bad)
    assert "meta.yaml" in str(err.value) and "decimate" in str(err.value) and words in str(err.value)


def test_a_whole_number_written_as_a_float_is_read_and_a_rate_too_low_is_told(dol_24k):
    assert with_meta_key(dol_24k, "decimate", 2.0).sample_time == pytest.approx(2 / 24e3)
    with pytest.warns(DataWarning, match="6 kHz, meta.yaml decimate.*below the 10 kHz"):
        ds = with_meta_key(dol_24k, "decimate", 4)
    assert any("below the 10 kHz" in line for line in ds.conditioning)


@pytest.mark.parametrize("waveform, se_ratio", [("sinusoidal", (0.8, 1.25)), ("six_step", (1.05, 1.8))])
def test_a_start_read_at_half_its_rate_is_identified_as_from_all_its_samples(made, tmp_path, waveform, se_ratio):
    """Read at 12 kHz, a 24 kHz start fits to its noise (a reading whose model is not the data's,
    as when the means were taken over each interval from its start, or about the bends of a held
    voltage's current, fitted at 1.18-1.27 times the noise), every estimate within three combined
    standard errors of the full record's (the two share most of their noise, so they lie closer
    still: 2.1 at most measured), and the standard errors those of all the samples under a sampled
    supply (0.95-1.00 of them measured), of half of them under a held one (1.15-1.53)."""
    folder = shutil.copytree(made[waveform], tmp_path / waveform)
    full = identify_folder(folder, tmp_path / "full")
    with_meta_key(folder, "decimate", 2)
    read = identify_folder(folder, tmp_path / "read")
    assert all(q["at_noise_level"] for q in read["fit_quality"].values()), read["fit_quality"]
    assert not any("misses the data" in w for w in read["warnings"]), read["warnings"]
    for name in ("Rs", "Ls", "Le", "Rr", "J"):
        se_full, se_read = full["standard_error"][name], read["standard_error"][name]
        assert abs(read["estimate"][name] - full["estimate"][name]) <= 3 * np.hypot(se_full, se_read), name
        assert se_ratio[0] <= se_read / se_full <= se_ratio[1], (name, se_read / se_full)


def test_a_stop_sampled_finer_than_a_millisecond_is_read_at_one(tmp_path):
    """Its speed as means over the twelve samples about each kept one (a 12 kHz stop), the report told;
    a stop at 1 ms is read as it is (the loader test above)."""
    import pandas as pd

    folder = _synthetic(tmp_path / "fine_stop", "motor.test.cycles=5", "motor.test.stop_duration=2",
                        "motor.test.stop_sample_time=8.333333333333333e-05")
    raw = pd.read_csv(folder / "stop.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = load_startup_dataset(folder)
    stop = ds.stops[0]
    assert np.allclose(np.diff(stop.t), 1e-3) and len(stop.t) == -(-len(raw) // 12)
    assert np.allclose(stop.speed, interval_means(raw["speed"].to_numpy(), 12))
    assert any("stop.csv read at 1 kHz, its speed as means over 12 samples" in line for line in ds.conditioning)
