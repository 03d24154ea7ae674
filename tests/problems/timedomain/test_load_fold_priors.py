"""A load torque fitted on one fold: what the fold cannot see goes to no load, what the base
reads as friction moves into the load, and the step's instant is judged at its best size.

Two held-out blind sets where ``load_torque``'s fold fits did worse on the other fold than the
base model without it, so a real load could never earn its place:

- the independent plant, effect-free (blind seed 395, set 1): fold A's fit put a switched load of
  its start's size at an instant only fold B has samples of (nothing pulled it back), held-out
  chi^2 196.8 against the base's 1.19. Every fit now minimises, beside the residuals, a weak prior
  of each load torque toward none (:meth:`LoadTorque.prior_residuals`, width the largest realistic
  load): an extra the fold cannot see goes to its absence.
- motulator, a DC generator (held-out form: brush drop, armature inductance) switched onto its
  resistor at 0.208 s of a six-step start and left on through the free stop (blind seed 399,
  set 18). The stop's pre-identification reads its torque, which follows speed, as viscous
  friction (``fv w_sync`` 1.9 N m against the motor's 0.1), every start of the load then added
  torque on top, and the grid judged each instant at the start's size: held-out chi^2 101.6 against
  the base's 62.1, and ``speed_sensor_gain`` was named instead. The load now also starts with the
  base's viscous friction above a motor's own moved into a switched load that follows speed
  (:meth:`LoadTorque.starts_from_base`), and the grid judges each instant with the size at its
  best too (``Selector.profiled``). Once the speed's noise estimate came closer to the noise
  really added (0.1006 rad/s against 0.0966, was 0.1025: the harmonic fit at the torque orders
  only), the tachometer took 36 % of what the generator's form leaves beside the load (held-out
  1.303 -> 1.195) with a gain error of 0.026 % and an offset of 0.03 % on all data: nothing a
  tachometer has. An effect fitted below a tenth of its smallest realistic size is not named
  (``Selector.negligible``).
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from tests.conftest import diagnose_with, remade_blind_set, stored_set

# the held-out blind draw `python -m benchmark.blind source=plant forms=heldout n=34 seed=395`, set 1
EFFECT_FREE = yaml.safe_load("""
motor: simulink_5hp
machine: {Rs: 1.247349383561329, Rr: 1.1711160383796386, Lm: 0.21222845304189394, Lls: 0.00581713365223583,
          Llr: 0.008113060222996448, J: 0.02081034847362243, fv: 0.0008242111625050757, fc: 0.2364590463446796}
scenario: {kind: six_step, Ed: 590.0, Nc: 30, cycles: 69}
sample_rate: 10800.0
oversampling: 10
effects: []
noise: {current_white: 0.07071889553035617, current_colored: 0.005559225016493691, current_pole: 0.9436230712856504,
        current_quantum: 0.020486440903726432, voltage_white: 0.9536725344622893, voltage_quantum: 0.034386147512215026,
        speed_white: 0.06585796871123362, speed_quantum: 0.0, speed_ripple: 0.07421863709119624, ripple_order: 12}
sensors: {has_speed: true, has_torque: true}
stop: null
meta: {nameplate: true, dc_resistance: true}
seed: 1905265776
""")

# motulator blind seed 399 (held-out forms), set 18, stored in tests/data (see its README.md):
# the generator's torque at synchronous speed and its switch-on instant, from the set's truth file
GENERATOR_TORQUE, GENERATOR_ON = 1.899001455679868, 0.20807049759441773


def round_one(doc: dict) -> dict:
    """Held-out chi^2 of the base and of each candidate in the first selection round."""
    first = doc["selection"][0]
    return {"base": first["heldout_chi2_from"]} | {r["effect"]: r["heldout_chi2"] for r in first["candidates"]}


@pytest.mark.slow
def test_a_load_the_fold_cannot_see_goes_to_none(tmp_path):
    _, folder = remade_blind_set(EFFECT_FREE, tmp_path / "set")
    doc = diagnose_with(folder, tmp_path / "out", ["load_torque"])
    chi2 = round_one(doc)
    print(chi2)
    assert chi2["base"] > 1.1  # the base leaves a gap a load could try to fill (1.19)
    # without the prior 196.8: the load's fold fits now do no worse than the base's
    assert chi2["load_torque"] <= 1.005 * chi2["base"], chi2
    assert doc["effects"] == []


@pytest.fixture(scope="module")
def generator(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("generator")
    folder = stored_set("motulator_blind399_set18", tmp / "set")
    return diagnose_with(folder, tmp / "out", ["load_torque", "speed_sensor_gain", "double_cage", "iron_loss"])


@pytest.mark.slow
def test_a_dc_generator_the_base_reads_as_viscous_friction_is_named(generator):
    doc = generator
    gap = (doc["gap_before"]["heldout_rms_over_noise"], doc["gap_after"]["heldout_rms_over_noise"])
    print(doc["verdict"], doc["status"], gap, round_one(doc))
    assert gap[0] > 5.0  # the generator leaves a large gap (7.9 x the noise)
    assert doc["base"]["identification"]["fv"] * 2 * np.pi * 50 > 1.5  # the stop read it as viscous friction
    assert round_one(doc)["load_torque"] < 0.05 * round_one(doc)["base"]  # 1.4 against 62.1 (was 101.6)
    assert doc["effects"] == ["load_torque"], doc["effects"]
    assert doc["explained_share"] > 0.95 and gap[1] < 1.3, (doc["explained_share"], gap)


@pytest.mark.slow
def test_the_generator_s_instant_and_torque_are_found(generator):
    load = next(e for e in generator["per_effect"] if e["effect"] == "load_torque")["physical"]
    print(load)
    assert abs(load["switched_on_s"] - GENERATOR_ON) < 0.005, load
    assert load["switched_share_following_speed"] > 0.9, load
    assert abs(load["switched_Nm"] / GENERATOR_TORQUE - 1.0) < 0.1, load  # at synchronous speed
    assert generator["base"]["estimate"]["fv"] * 2 * np.pi * 50 < 0.5  # the friction went back to the motor
