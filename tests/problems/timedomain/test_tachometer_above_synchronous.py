"""A tachometer that reads above synchronous speed must not lock the friction at zero.

Independent plant (``synthetic.independent``): a 1 kW direct-on-line start (blind set 10 of
``python -m benchmark.blind source=plant seed=17``, remade from its truth file) whose tachometer
reads 1.1 % high with a once-per-revolution ripple. The identification, which has no tachometer
gain, gets as close to a speed above synchronous as it can: its viscous and Coulomb friction
end at zero (1e-26 N m s, 1e-19 N m). The diagnosis searched the friction in ``[0, 5 x fc]``
about that base, so every augmented model kept zero friction, and a quadratic load torque was
chosen as a second effect to stand in for the motor's own friction (verdict
``speed_sensor_gain+load_torque``). With the friction's search range floored at 3 % of the
estimated rated torque, the tachometer alone explains the gap.
"""

from __future__ import annotations

import pytest
import yaml

from benchmark.core.harness import run_diagnosis
from synthetic.independent import make_dataset, write_dataset
from tests.conftest import compose_config

BLIND_TACHOMETER = yaml.safe_load("""
motor: paper_1kw
machine: {Rs: 4.1506923915062055, Rr: 1.4143470741409472, Lm: 0.09601121220695355, Lls: 0.0064502042147439,
          Llr: 0.004853968812310599, J: 0.006420233824894451, fv: 0.00029859091130241146, fc: 0.01656173832682414}
scenario:
  kind: dol
  V: 230.0
  f: 50.0
  duration: 1.2591544696885615
  h5: 0.022125687130566167
  h7: 0.0036516840638182576
  phase5: 0.9268145288148639
  phase7: 0.9217466872154931
  unbalance: [-0.009635374674118034, -0.004770476407105322, -0.004460989883295507]
  phase0: 3.43143445666134
  pre_trigger: 0.03907274804691053
  stagger: [0.0, 0.000669936280216244, 0.0002511757632077025]
  bounce: [0.0006828520417946866, 0.0003829193586345074, 0.0002506837970337852]
  arc_voltage: 37.703354688524804
  dip: 0.03614424529104448
  x_over_r: 3.0148821593218766
sample_rate: 12000.0
oversampling: 10
effects:
- {name: speed_sensor_gain, form: gain_ripple, unit: fraction, size: 0.011201107380885143, offset: -0.499993120990139,
   ripple: 0.009291519520217062, ripple_phase: 1.0302543199513035}
noise: {current_white: 0.060757111956899826, current_colored: 0.03388812357737023, current_pole: 0.9251570700404806,
        current_quantum: 0.0, voltage_white: 0.9969114045025587, voltage_quantum: 0.0, speed_white: 0.01470398289638106,
        speed_quantum: 0.16966319313490838, speed_ripple: 0.014833114759444078, ripple_order: 10}
sensors: {has_speed: true, has_torque: true}
stop: null
meta: {nameplate: true, dc_resistance: false}
seed: 1679352321
""")


def test_zero_friction_in_the_base_does_not_make_a_load_torque_rider(tmp_path):
    made = make_dataset(BLIND_TACHOMETER)
    folder = write_dataset(made, tmp_path / "set")
    (folder / "truth.yaml").unlink(missing_ok=True)
    cfg = compose_config([f"data.path={folder}", "candidates=[speed_sensor_gain,load_torque]", "figures=false"],
                         name="diagnose")
    doc = run_diagnosis(cfg, tmp_path / "out")
    ident = doc["base"]["identification"]
    assert ident["fv"] < 1e-9 and ident["fc"] < 1e-9  # what the identification gives: no friction at all
    assert doc["verdict"] == "speed_sensor_gain", doc["selection"]
    assert doc["status"] == "explained"
    assert doc["gap_before"]["heldout_rms_over_noise"] > 20.0
    assert doc["gap_after"]["heldout_rms_over_noise"] < doc["gap_after"]["noise_band"][1]
    gain = doc["per_effect"][0]["parameters"]["tach_gain_error"]
    assert gain["value"] == pytest.approx(0.011201, abs=3 * gain["standard_error"] + 2e-4)
    truth = made.truth["parameters"]
    final = doc["base"]["estimate"]
    assert 0.5 * truth["fv"] < final["fv"] < 2.0 * truth["fv"]
    assert 0.3 * truth["fc"] < final["fc"] < 3.0 * truth["fc"]
