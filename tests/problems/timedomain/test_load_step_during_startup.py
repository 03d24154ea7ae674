"""A load step during the start-up, on motulator's 2.2 kW machine (motulator blind seed 45, set 32).

motulator's load step is an active torque that stays on through the coast-down, so the stop
record's pre-identification puts most of it into the base's Coulomb friction. The load effect's
starts then had their instant chosen on a grid judged with the step's torque at its start value:
the best grid instant was late in the record, where a step changes least, every start went there,
and the verdict was ``unexplained`` at 6.3 times the noise. The starts as they were are now tried
beside the grid's: ``load_torque``, explained (6.34 -> 0.98 on the blind set)."""

from __future__ import annotations

import pytest

from tests.conftest import diagnose_with, stored_set

# motulator blind seed 45, set 32: the 2.2 kW example machine spread by the draw, a six-step start.
# The record is stored (tests/data/motulator_blind45_set32, see its README.md): motulator takes
# four minutes to make it, its 23 s free stop most of that; it was made by
# make_motulator_dataset(MOTOR, "six_step", {"load_torque": STEP}, NOISE, 298262428, folder, 0.5, 12000.0, True)
MOTOR = {"name": "blind45_set32", "pole_pairs": 2, "voltage": 400.0, "frequency": 50.0, "rated_power": 2200.0,
         "parameters": {"Rs": 3.391149472101035, "Ls": 0.24755586049181844, "Le": 0.02434372911182061,
                        "Rr": 2.003895900226593, "J": 0.013672744908320794, "fv": 0.00043174359996410184,
                        "fc": 0.07219399480457109}}
STEP = {"form": "step", "torque": 5.438651442115841, "time": 0.16364176073554737}
NOISE = {"current_std": 0.09113198587807662, "current_colored_std": 0.045381846792444024,
         "speed_std": 0.1608633111790397}


@pytest.mark.slow  # a full diagnosis of a remade record (README: the reproductions)
def test_a_load_step_during_a_motulator_start_up_is_named(tmp_path):
    folder = stored_set("motulator_blind45_set32", tmp_path / "set")
    doc = diagnose_with(folder, tmp_path / "out", ["load_torque"])
    gap = (doc["gap_before"]["heldout_rms_over_noise"], doc["gap_after"]["heldout_rms_over_noise"])
    step = doc["per_effect"][0]["parameters"] if doc["effects"] else {}
    print(doc["status"], doc["verdict"], gap, {k: v["value"] for k, v in step.items()})
    assert gap[0] > 3.0  # the step leaves a clear gap
    assert doc["verdict"] == "load_torque" and doc["status"] == "explained", (doc["status"], gap)
    assert gap[1] < 1.2
    t_step = step["load_step_time"]["value"] * 0.5  # fraction of the record
    assert abs(t_step - STEP["time"]) < 0.01, t_step
