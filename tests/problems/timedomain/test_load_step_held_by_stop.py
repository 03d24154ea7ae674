"""A load step that stays on through the coast-down, on motulator (blind seed 51, set 22).

The stop record's pre-identification reads the step's torque as Coulomb friction (0.78 N m
against the motor's 0.04), so the base model carries it through the whole start-up, before the
step too. The load effect's starts put the step on top of that friction, where it only adds
torque the start-up before the step does not have: it removed a sixth of the gap and a double
cage, soaking up the pre-step misfit, was named instead (``partly_explained``, 3.36 -> 2.55;
own seed 49 set 38 and motulator seed 48 set 15 had the same cause). The load effect now also
starts with the base's friction above a motor's own moved into the step
(:meth:`LoadTorque.starts_from_base`)."""

from __future__ import annotations

import pytest

from tests.conftest import diagnose_with, stored_set

# motulator blind seed 51, set 22 (the draw as rows.jsonl records it): the preset 1 kW motor
# spread by the draw, a six-step start, a 0.73 N m step at 0.164 s, on through the stop. The
# record is stored (tests/data/motulator_blind51_set22, see its README.md): motulator takes
# minutes to make it; it was made by
# make_motulator_dataset(MOTOR, "six_step", {"load_torque": STEP}, NOISE, 53869196, folder, 0.5, 12000.0, True)
MOTOR = {"parameters": {"Rs": 4.3353680867925775, "Ls": 0.10725417825304943, "Le": 0.009536544054008817,
                        "Rr": 1.7334943513101373, "J": 0.006661245244928131, "fv": 0.000297854834552906,
                        "fc": 0.04297},
         "pole_pairs": 1, "frequency": 50.0, "dc_link_voltage": 300.0, "rated_power": 1000.0}
STEP = {"form": "step", "size": 0.22265934081024757, "time": 0.16353909029873182}
NOISE = {"current_std": 0.05701416926622967, "current_colored_std": 0.03231564667975357,
         "speed_std": 0.16112351838501565, "speed_quantum": 0.5}


@pytest.mark.slow  # a full diagnosis of a remade record (README: the reproductions)
def test_a_load_step_the_stop_reads_as_friction_is_named_not_a_double_cage(tmp_path):
    folder = stored_set("motulator_blind51_set22", tmp_path / "set")
    doc = diagnose_with(folder, tmp_path / "out", ["load_torque", "double_cage", "iron_loss", "speed_sensor_gain"])
    gap = (doc["gap_before"]["heldout_rms_over_noise"], doc["gap_after"]["heldout_rms_over_noise"])
    base = doc["base"]["estimate"]
    print(doc["status"], doc["verdict"], gap, base["fc"], doc["per_effect"])
    assert gap[0] > 3.0  # the step leaves a clear gap
    assert doc["base"]["identification"]["fc"] > 0.5  # the stop read the step as friction
    assert doc["verdict"] == "load_torque", (doc["verdict"], doc["status"], gap)
    # what the step leaves sits on the noise band's upper edge (held-out RMS 1.0996 against the
    # band's 1.0994, 'partly_explained'; 1.0990, 'explained', before the load's fits took a weak
    # prior toward no load and their Coulomb friction went from 0.026 to 0.030 N m, the motor's
    # 0.043): the status turns on 0.05 % of the fit, the share it explains does not
    assert doc["explained_share"] > 0.98, doc["explained_share"]
    assert gap[1] < 1.15
    step = {k: v["value"] for k, v in doc["per_effect"][0]["parameters"].items()}
    assert abs(step["load_step_time"] * 0.5 - STEP["time"]) < 0.01, step
    assert base["fc"] < 0.2, base["fc"]  # the friction went back to the motor's (0.04 N m)
