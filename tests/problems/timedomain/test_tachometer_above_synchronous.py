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

from tests.conftest import diagnose_with, remade_blind_set

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


@pytest.mark.slow  # a full diagnosis of a remade record (README: the reproductions)
def test_zero_friction_in_the_base_does_not_make_a_load_torque_rider(tmp_path):
    made, folder = remade_blind_set(BLIND_TACHOMETER, tmp_path / "set")
    doc = diagnose_with(folder, tmp_path / "out", ["speed_sensor_gain", "load_torque"])
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


#: Blind set 4 of ``python -m benchmark.blind source=plant seed=16``: a 7.5 kW 6-pole direct-on-line
#: start and free stop, the tachometer 1.6 % high with a 0.33 rad/s offset and a ripple once per turn.
BLIND_TACHOMETER_STOP = yaml.safe_load("""
motor: fitzgerald_6pole
machine: {Rs: 0.3191873820232418, Rr: 0.15136103579394047, Lm: 0.037212048167751755, Lls: 0.0013757412364180969,
          Llr: 0.0007023844652857846, J: 0.08190202334216208, fv: 0.003764645590056543, fc: 0.7536397594724589}
scenario:
  kind: dol
  V: 220.0
  f: 60.0
  duration: 0.8113078711014267
  h5: 0.003683975380455076
  h7: 0.013752399801959553
  phase5: 4.211730909779699
  phase7: 0.6671679818606655
  unbalance: [-0.005635798582474815, -0.001117575643878203, 0.0039683415499089545]
  phase0: 3.725368836960268
  pre_trigger: 0.019008320438821655
  stagger: [0.0004518667578353721, 0.0014533637202602248, 0.0]
  bounce: [0.0003801790325738759, 0.0006653160624721714, 0.0006758412306910906]
  arc_voltage: 38.9645861676465
  dip: 0.027798322407776695
  x_over_r: 5.713390195685033
sample_rate: 10800.0
oversampling: 10
effects:
- {name: speed_sensor_gain, form: gain_ripple, unit: fraction, size: 0.01605685386924963, offset: 0.32985088583314703,
   ripple: 0.006437128169194685, ripple_phase: 2.464669229648574}
noise: {current_white: 0.08602516321354034, current_colored: 0.11146549903560451, current_pole: 0.9063753294901739,
        current_quantum: 0.0, voltage_white: 0.3811719138098164, voltage_quantum: 0.008222774405094897,
        speed_white: 0.04405146633482962, speed_quantum: 0.14539277950912513, speed_ripple: 0.0, ripple_order: 20}
sensors: {has_speed: true, has_torque: true}
stop: {duration: 8.83342560466085, sample_time: 0.001}
meta: {nameplate: true, dc_resistance: true}
seed: 1052562428
""")


def test_the_stop_record_is_seen_through_the_same_tachometer(tmp_path):
    """The free stop is recorded by the start-up's tachometer: its rest offset (removed from the
    start-up by the conditioning) and its gain and ripple sit on the stop too, and the first
    tenth of a second of the stop still holds the trapped flux's braking. At the plant's true
    parameters and tachometer the augmented model's stop residual was 16 times the noise (the
    ripple and offset not applied, the coast started from the filtered measured speed); a load
    torque was then chosen to bend the coast (verdict ``speed_sensor_gain+load_torque``). Now
    the conditioning takes the offset off the stop too, the tachometer acts on the stop (ripple
    phase profiled out) and the coast's starting speed is fitted: the truth is at the noise."""
    import numpy as np

    from benchmark.core.effects import load_effects
    from benchmark.problems.timedomain.data import load_startup_dataset
    from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
    from benchmark.problems.timedomain.diagnosis.pipeline import base_context, friction_scale

    made, folder = remade_blind_set(BLIND_TACHOMETER_STOP, tmp_path / "set")
    ds = load_startup_dataset(folder)
    assert any(line.startswith("stop record: the start-up's speed offset +0.3") for line in ds.conditioning)
    data = DiagnosisData.from_dataset(ds)
    p = made.truth["parameters"]
    ctx = base_context(data, p, ds.dc_link_voltage)
    model = JointModel(data, 2, [load_effects("timedomain", ["speed_sensor_gain"])["speed_sensor_gain"]], ctx, p,
                       friction_scale(p, ctx), 5.0)
    tach = BLIND_TACHOMETER_STOP["effects"][0]
    a, phase = tach["ripple"], tach["ripple_phase"]
    x = np.r_[[p[n] for n in model.base_names], tach["size"], 0.0, a * np.cos(phase), a * np.sin(phase), 0.0]
    r = model.residuals(x[None, :])[0]
    used = data.used()
    rms = {ch: float(np.sqrt(np.mean(r[s][used[s]] ** 2))) for ch, s in data.channel_slices().items()}
    assert rms["stop_speed"] < 1.1, rms  # was 16.2
    assert rms["speed"] < 1.1, rms
