"""Masked current peaks are checked by the rule on the masked samples themselves.

The conditioning masks current peaks that a saturating probe flattened. Judged on the whole
record beside a large gap (the worked example: a coupling the base lacks, 120 times the noise
left), real compressed peaks took 1 % of the excess and went unnamed. On the masked samples the
final model's held-out prediction, put through a probe's compression fitted on the other fold,
either takes the residual away (a probe compressed them) or not (the peaks are the machine's)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.problems.timedomain.data import StartupDataset, StartupRecord, StopRecord
from benchmark.problems.timedomain.diagnosis.named import named_effects
from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings, diagnose
from benchmark.problems.timedomain.frames import clarke, inverse_clarke
from tests.conftest import PAPER_MOTOR

NOISE_A = 0.05  # current noise, A


def _dataset(records, compress: bool, harmonic_a: float = 0.0) -> StartupDataset:
    """The paper motor's start with noise, its phase probes compressing as ``L tanh(i / L)``
    (``L`` 0.7 of the largest phase current) when ``compress``, a fifth harmonic of
    ``harmonic_a`` A the base model cannot follow on both currents, and the conditioning's mask
    over the samples where a phase current is above 0.6 of its largest (said to be removed)."""
    s, st = records["startup"], records["stop"]
    rng = np.random.default_rng(11)
    n = len(s["t"])
    w = 2 * np.pi * 50.0 * 5
    i_a = s["i_alpha"] + harmonic_a * np.cos(w * s["t"])
    i_b = s["i_beta"] + harmonic_a * np.sin(w * s["t"])
    i_r, i_s, _ = inverse_clarke(i_a, i_b)
    peak = max(np.max(np.abs(i_r)), np.max(np.abs(i_s)))
    mask = (np.abs(i_r) > 0.6 * peak) | (np.abs(i_s) > 0.6 * peak)
    if compress:
        limit = 0.7 * peak
        i_r, i_s = limit * np.tanh(i_r / limit), limit * np.tanh(i_s / limit)
    i_a, i_b = clarke(i_r, i_s, -i_r - i_s)
    rec = StartupRecord(
        t=s["t"], v_alpha=s["v_alpha"], v_beta=s["v_beta"],
        i_alpha=i_a + rng.normal(0, NOISE_A, n), i_beta=i_b + rng.normal(0, NOISE_A, n),
        speed=s["speed"] + rng.normal(0, 0.2, n), weight=~mask, removed={"current_sensor_saturation": mask})
    stop = StopRecord(t=st["t"], speed=st["speed"] + rng.normal(0, 0.2, len(st["t"])))
    return StartupDataset(pole_pairs=1, sample_time=1 / 12000, startups=[rec], stops=[stop], input_hold="zoh",
                          conditioning_removed=["current_sensor_saturation"])


def _truth() -> dict[str, float]:
    return {k: getattr(PAPER_MOTOR, k) for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")}


@pytest.mark.parametrize("compress, harmonic_a, named", [(True, 0.0, True), (False, 0.0, False), (True, 0.6, True),
                                                         (False, 0.6, False)])
def test_masked_peaks_are_named_only_where_a_probe_compressed_them(paper_records, compress, harmonic_a, named):
    ds = _dataset(paper_records, compress, harmonic_a)
    doc = diagnose(ds, _truth(), {}, DiagnosisSettings())
    row = doc["conditioning_check"][0]
    assert row["effect"] == "current_sensor_saturation" and "masked samples" in row["where"], row
    print(compress, harmonic_a, {k: row[k] for k in ("heldout_chi2_put_back", "heldout_chi2", "band",
                                                      "excess_reduction", "compression_limit_a")})
    assert row["earns"] is named, row
    if harmonic_a:  # a gap the base cannot close, on every sample
        assert doc["gap_before"]["heldout_rms_over_noise"] > 3.0, doc["gap_before"]
    if named:
        assert row["excess_reduction"] > 0.5, row
        assert named_effects(doc) == ["current_sensor_saturation"]
    else:
        assert row["excess_reduction"] < 0.3 or row["heldout_chi2_put_back"] < row["band"] ** 2, row
        assert "current_sensor_saturation" not in named_effects(doc)
