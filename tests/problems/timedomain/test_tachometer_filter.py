"""A tachometer behind an output filter (the catalogue's ``speed_sensor_gain``, ``tach_lag``).

Independent plant, blind set 29 of ``python -m benchmark.blind source=plant forms=heldout
seed=402`` (remade from its truth file): a 7.5 kW 6-pole six-step start whose tachometer reads
3.7 % high through a first-order RC filter of 3.17 ms (the plant's ``tacho_filter`` form, held
out then). An accelerating shaft reads low by about ``tau dw/dt``; the catalogue's tachometer
had a gain, an offset and a once-per-revolution ripple, and the verdict was
``speed_sensor_gain`` ``partly_explained`` with 14.6 times the noise left (92.7 before). With
the filter's time constant among its parameters (0-10 ms: an RC filter on a tachogenerator,
an encoder's gate time), the gain alone explains the record. The plant's form is retired from
its held-out forms since (an encoder's gate-time mean is held out in its place).

The filter is a fact of the instrument: ``meta.yaml`` states it (``speed_filter``, as the blind
draws state an injected one) and the fit searches it up to that; where nothing is stated it is
held at none, and the same record is then not explained by the tachometer alone.
"""

from __future__ import annotations

import pytest
import yaml

from benchmark.analysis.blind_sources import state_filter
from tests.conftest import diagnose_with, remade_blind_set

TACHOMETER_FILTER = yaml.safe_load("""
motor: fitzgerald_6pole
machine: {Rs: 0.3152868183304746, Rr: 0.16800472941416913, Lm: 0.03357072195978715, Lls: 0.0010330437351524883,
  Llr: 0.00046986910392404844, J: 0.08659861731269436, fv: 0.0036375741900381443, fc: 0.529376501910328}
scenario: {kind: six_step, Ed: 282.2, Nc: 30, cycles: 77}
sample_rate: 10800.0
oversampling: 10
effects:
- {name: speed_sensor_gain, form: tacho_filter, unit: fraction, size: 0.03705586323495129, offset: 0.4818461703410942,
  ripple: 0.0, ripple_phase: 3.414457305540055, time_constant: 0.0031687424960925247}
noise: {current_white: 0.12915820733366973, current_colored: 0.07779409575315059, current_pole: 0.902033982424311,
  current_quantum: 0.007965768769822077, voltage_white: 0.1274430853523926, voltage_quantum: 0.0,
  speed_white: 0.031026041271989997, speed_quantum: 0.0, speed_ripple: 0.0, ripple_order: 16}
sensors: {has_speed: true, has_torque: false}
stop: null
meta: {nameplate: true, dc_resistance: false}
seed: 1085214444
""")


@pytest.mark.slow
def test_a_filtered_tachometer_is_explained_by_its_gain_and_lag(tmp_path):
    _, folder = remade_blind_set(TACHOMETER_FILTER, tmp_path / "set")
    state_filter(folder, TACHOMETER_FILTER["effects"][0]["time_constant"])
    doc = diagnose_with(folder, tmp_path / "out", ["speed_sensor_gain", "two_mass", "load_torque"])
    assert doc["verdict"] == "speed_sensor_gain", doc["selection"]
    assert doc["status"] == "explained"
    assert doc["gap_before"]["heldout_rms_over_noise"] > 50.0
    assert doc["gap_after"]["heldout_rms_over_noise"] < doc["gap_after"]["noise_band"][1]
    fitted = doc["per_effect"][0]["parameters"]
    lag, gain = fitted["tach_lag"], fitted["tach_gain_error"]
    assert lag["value"] == pytest.approx(0.0031687, abs=3 * lag["standard_error"] + 1e-4)
    assert gain["value"] == pytest.approx(0.0370559, abs=3 * gain["standard_error"] + 2e-4)


@pytest.mark.slow
def test_an_unstated_filter_is_not_searched(tmp_path):
    """The same record without ``speed_filter``: the tachometer's lag is held at none, and its
    gain and offset alone leave the shaft's lag (``tau dw/dt``) in the speed."""
    _, folder = remade_blind_set(TACHOMETER_FILTER, tmp_path / "set")
    doc = diagnose_with(folder, tmp_path / "out", ["speed_sensor_gain"])
    assert doc["facts"]["speed_filter"] is None
    tach = [p for p in doc["per_effect"] if p["effect"] == "speed_sensor_gain"]
    if tach:
        assert tach[0]["parameters"]["tach_lag"]["value"] == 0.0
    assert doc["gap_after"]["heldout_rms_over_noise"] > 2.0 * doc["gap_after"]["noise_band"][1]
