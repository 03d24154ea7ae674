"""The fit-quality verdict on a quantised speed (:mod:`benchmark.problems.timedomain.noise`, the one
noise estimate of the identification and the diagnosis).

Independent plant (``synthetic.independent``, no code shared with the model): the paper's 1 kW
motor started by a six-step inverter, every channel clean except the speed, quantised in steps of
0.5 rad/s (an encoder or a digitised tachometer). Without a quantisation floor the speed's noise
came from the steady state, where the reading sits on one level, and an exact fit read "the model
misses the data: speed 97 times the noise". With it the effect-free record's speed is at the
noise level (its level ``q / sqrt(12)``, whose uncertainty counts how few independent errors a
reading that sits still holds) and the same record with a double cage, which the model lacks, is
still called a miss, on the speed too.
"""

from __future__ import annotations

import pytest

from synthetic.independent import make_dataset, make_spec, write_dataset
from tests.conftest import identify_folder

#: Every channel clean but the speed, quantised in 0.5 rad/s steps.
QUANTISED_SPEED_ONLY = {"current_white": 0.0, "current_colored": 0.0, "current_pole": 0.97, "current_quantum": 0.0,
                        "voltage_white": 0.0, "voltage_quantum": 0.0, "speed_white": 0.0, "speed_quantum": 0.5}


def _identified(tmp_path, effects):
    spec = make_spec("paper_1kw", "six_step", effects, seed=1, duration=0.6, stop=2.0, noise=QUANTISED_SPEED_ONLY,
                     ideal_supply=True)
    name = "_".join(effects) or "exact"
    return identify_folder(write_dataset(make_dataset(spec), tmp_path / name), tmp_path / f"run_{name}")


def _misses(rec) -> bool:
    return any(w.startswith("the model misses the data") for w in rec["warnings"])


def test_a_quantised_speed_fitted_exactly_is_at_the_noise_level(tmp_path):
    rec = _identified(tmp_path, [])
    for k in ("Rs", "Ls", "Le", "Rr", "J"):
        assert abs(rec["rel_error"][k]) < 1e-3, (k, rec["rel_error"])
    speed = rec["fit_quality"]["speed"]
    assert "quantisation step 0.5" in speed["noise_method"], speed
    assert speed["noise"] == pytest.approx(0.5 / 12**0.5)
    assert 1.0 < speed["ratio"] <= speed["threshold"], speed  # the reading's error is not dithered: above 1
    assert not _misses(rec), rec["warnings"]


def test_the_same_record_with_an_unmodelled_double_cage_misses_the_data(tmp_path):
    rec = _identified(tmp_path, ["double_cage"])
    assert _misses(rec), rec["warnings"]
    speed = rec["fit_quality"]["speed"]
    assert speed["ratio"] > 2 * speed["threshold"], speed
