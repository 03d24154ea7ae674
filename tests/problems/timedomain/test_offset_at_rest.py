"""Offsets the conditioning measured on a pre-trigger are checked by the rule at rest.

Beside a large gap (a coupling the base model lacks, 120 times the noise left) a real offset
takes almost nothing of the whole record's excess, so the whole-record check left the worked
example's offsets unnamed. At rest the model is exact (zero current, zero voltage): the rule
compares the pre-trigger with its offset held out (each half less the other half's mean) against
the samples themselves, each channel whitened by its own spread there."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from benchmark.problems.timedomain.conditioning import restored
from benchmark.problems.timedomain.data import StartupDataset, StartupRecord, load_startup_dataset
from benchmark.problems.timedomain.diagnosis.conditioning_check import at_rest_row
from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings
from benchmark.problems.timedomain.diagnosis.rule import Rule
from synthetic.independent.dataset import make_dataset, make_spec, write_dataset

SELECTOR = SimpleNamespace(settings=DiagnosisSettings(), rule=Rule(0.3))  # what at_rest_row reads of a selector


def _record_at_rest(samples: dict) -> StartupDataset:
    """A data set whose one record says its offsets were removed, measured on ``samples``."""
    t = np.arange(10) * 1e-4
    rec = StartupRecord(t=t, v_alpha=t, v_beta=t, i_alpha=t, i_beta=t, speed=t,
                        removed={"sensor_offset": (0.0, 0.0, 0.1, 0.0), "sensor_offset_at_rest": samples})
    return StartupDataset(pole_pairs=2, sample_time=1e-4, startups=[rec], conditioning_removed=["sensor_offset"])


@pytest.mark.parametrize("offset_over_sigma, n, earns", [(2.0, 130, True), (1.0, 130, True), (0.25, 170, False),
                                                         (0.0, 270, False)])
def test_an_offset_at_rest_earns_its_place_when_it_shows_per_sample(offset_over_sigma, n, earns):
    rng = np.random.default_rng(3)
    sigma = 0.09  # A
    ds = _record_at_rest({"i_r": offset_over_sigma * sigma + rng.normal(0, sigma, n),
                          "i_s": rng.normal(0, sigma, n)})
    row = at_rest_row(ds, SELECTOR)
    assert row["earns"] is earns, row
    # the samples themselves: 1 + (offset / sigma)^2 on one channel of two (sigma estimated from
    # n samples: 12 % one-sigma on its square at n = 130, hence the relative tolerance)
    assert row["heldout_chi2_put_back"] - 1 == pytest.approx(offset_over_sigma**2 / 2, rel=0.3, abs=0.1)
    assert row["heldout_chi2"] == pytest.approx(1.0, abs=0.15)  # the offset held out: the noise
    assert 1.1 < row["band"] < 1.25  # a few hundred samples: a wide band
    if earns:
        assert row["excess_reduction"] > 0.85
    assert "i_r 130 samples" in row["where"] or not earns


def test_no_check_at_rest_where_an_offset_came_from_the_steady_tail():
    ds = _record_at_rest({"i_r": np.ones(100)})
    rec = ds.startups[0]
    tail = replace(ds, startups=[replace(rec, removed={"sensor_offset": (0.0, 0.0, 0.1, 0.0)})])
    assert at_rest_row(tail, SELECTOR) is None


def test_a_grid_start_with_offsets_keeps_its_pre_trigger_for_the_check(tmp_path):
    """The independent plant's grid start (pre-trigger, offsets on every channel): the
    conditioning removes the offsets from the pre-trigger's means and keeps those samples; the
    rule names them at rest; put back, they are gone from the record's removals."""
    spec = make_spec("motulator_2k2", "dol", ["sensor_offset"], seed=5, duration=0.3, sample_rate=5000.0,
                     forms={"sensor_offset": "both"})
    ds = load_startup_dataset(write_dataset(make_dataset(spec), tmp_path / "set"))  # conditioned on load
    assert "sensor_offset" in ds.conditioning_removed
    at_rest = ds.startups[0].removed["sensor_offset_at_rest"]
    assert set(at_rest) <= {"v_r", "v_s", "v_t", "i_r", "i_s"} and len(at_rest) >= 2
    assert all(len(x) >= 50 for x in at_rest.values())
    row = at_rest_row(ds, SELECTOR)
    assert row["earns"] and row["excess_reduction"] > 0.9, row
    put_back = restored(ds, "sensor_offset")
    assert put_back.startups[0].removed is None or "sensor_offset_at_rest" not in put_back.startups[0].removed
