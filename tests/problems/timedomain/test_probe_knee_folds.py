"""A probe that compresses the start's first peaks: each held-out fold must see them.

Independent plant (``synthetic.independent``): a 7.5 kW direct-on-line start (blind set 7 of
``python -m benchmark.blind source=plant seed=21``, remade from its truth file) whose current
probes compress above 2.3 times the rated current (a knee). With fold blocks of two supply
periods the first and largest peaks all fell into fold A: fold B's fit could not see the knee,
its prediction of fold A stayed at 200 times the noise, and the tachometer tried next, with a gain
error of 1e-4, took the credit when its own fit happened to restart near the knee (verdict
``current_sensor_saturation+speed_sensor_gain``). The folds are now cut by segment of the
experiment (:mod:`~benchmark.problems.timedomain.diagnosis.folds`): the electrical start's three
periods in four blocks, so both folds hold its peaks. Two more things kept the held-out misfit up:
fold A's fit had stopped in a worse basin than fold B's point, on fold A's own samples
(``Selector.cross_start`` now refits a fold from the other fold's point where that fits it
better), and the probe saturation then is the whole story.
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from benchmark.problems.timedomain.data import load_startup_dataset
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData
from benchmark.problems.timedomain.diagnosis.folds import segment_folds
from tests.conftest import diagnose_with, remade_blind_set

BLIND_PROBE_KNEE = yaml.safe_load("""
effects:
- {form: knee, name: current_sensor_saturation, size: 2.2643717386937743, unit: x rated current amplitude}
machine: {J: 0.026448813708970686, Llr: 0.003982285569184413, Lls: 0.003166236353257535, Lm: 0.1275707351702683,
          Rr: 0.7874064269961294, Rs: 0.6299659829178379, fc: 0.23486477429034047, fv: 0.002137657259971353}
meta: {dc_resistance: false, nameplate: false}
motor: simulink_7k5
noise: {current_colored: 0.034300914840435896, current_pole: 0.9358735481629212, current_quantum: 0.009558559582417575,
        current_white: 0.16780037944690251, ripple_order: 10, speed_quantum: 0.10327950709134792, speed_ripple: 0.0,
        speed_white: 0.019928759989939565, voltage_quantum: 0.0, voltage_white: 0.22765002263968276}
oversampling: 10
sample_rate: 12000.0
scenario:
  V: 400.0
  arc_voltage: 37.48491974590188
  bounce: [0.0007646259839874858, 0.0008265236438087074, 0.0006892321107536916]
  dip: 0.04982508003364171
  duration: 0.8121618820447685
  f: 50.0
  h5: 0.0234507431336739
  h7: 0.02549210454907807
  kind: dol
  phase0: 3.2361374401814222
  phase5: 0.3375305821856971
  phase7: 2.341018271637265
  pre_trigger: 0.008884118100243739
  stagger: [0.0005134898376576446, 0.0, 0.00010493124960183565]
  unbalance: [-0.007954714157784737, -0.0004832533618981128, 0.002934594820413601]
  x_over_r: 2.397301549331628
seed: 2118027269
sensors: {has_speed: true, has_torque: false}
stop: {duration: 9.186613811178079, sample_time: 0.001}
""")


def remade(tmp_path):
    return remade_blind_set(BLIND_PROBE_KNEE, tmp_path / "set")[1]


def test_each_fold_holds_large_peaks_of_the_start(tmp_path):
    """The probe's knee is at 43.9 A. With two-period blocks fold B's largest current was 35 A
    (every sample above 60 A in fold A); now each fold holds over a hundred samples above 60 A."""
    data = DiagnosisData.from_dataset(load_startup_dataset(remade(tmp_path)))
    fold_a, _ = segment_folds(data)
    n = data.n_startup
    in_a, used = fold_a[:n], data.used()[:n]  # the i_alpha part; every channel has the same blocks
    t = data.t - data.t[0]
    i_mag = np.hypot(data.meas[0], data.meas[1])
    assert np.sum(i_mag[in_a & used] > 60.0) > 100 and np.sum(i_mag[~in_a & used] > 60.0) > 100
    two_period_a = (np.floor(t * data.supply_frequency / 2.0).astype(int) % 2) == 0
    assert np.max(i_mag[~two_period_a & used]) < 43.9  # what the old blocks gave fold B


@pytest.mark.slow
def test_a_probe_knee_is_named_alone(tmp_path):
    doc = diagnose_with(remade(tmp_path), tmp_path / "out", ["current_sensor_saturation", "speed_sensor_gain"])
    assert doc["verdict"] == "current_sensor_saturation", doc["selection"]
    assert doc["status"] == "explained"
    assert doc["gap_before"]["heldout_rms_over_noise"] > 5.0
    assert doc["gap_after"]["heldout_rms_over_noise"] < doc["gap_after"]["noise_band"][1]
