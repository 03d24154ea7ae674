"""The coloured speed noise study's draws and sets (its diagnoses are the user's command)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from benchmark.studies.coloured_speed_noise import draw, make, recorded_noise


def test_the_draws_are_seeded_and_within_their_ranges():
    rows = draw(472, 8)
    assert rows == draw(472, 8) and rows != draw(473, 8)
    for r in rows:
        nz = r["noise"]
        assert 1e-3 <= nz["speed_filter"] <= 5e-3 and 0.05 <= nz["speed_std"] <= 0.2
        assert 0.5 <= nz["speed_coloured_std"] / nz["speed_std"] <= 2.0
    assert {(r["motor"], r["scenario"]) for r in rows[:4]} == {("motulator_2p2kw", "dol"), ("alonge_1kw", "dol"),
                                                               ("motulator_2p2kw", "six_step"),
                                                               ("alonge_1kw", "six_step")}


def test_a_set_and_its_quiet_twin_differ_by_the_speed_noise_alone(tmp_path, monkeypatch):
    pytest.importorskip("motulator")
    import benchmark.studies.coloured_speed_noise as study

    monkeypatch.setattr(study, "DURATION", 0.3)
    d = draw(1, 1)[0]
    make(d, tmp_path)
    for name in ("set", "clean"):
        assert yaml.safe_load((tmp_path / name / "meta.yaml").read_text())["speed_filter"] == d["noise"]["speed_filter"]
    from benchmark.problems.timedomain.data import load_startup_dataset

    noisy, quiet = (load_startup_dataset(tmp_path / name).startups[0] for name in ("set", "clean"))
    np.testing.assert_array_equal(noisy.i_alpha, quiet.i_alpha)
    assert not np.array_equal(noisy.speed, quiet.speed)
    speed, stop = recorded_noise(tmp_path)
    total = float(np.hypot(d["noise"]["speed_std"], d["noise"]["speed_coloured_std"]))
    assert stop == pytest.approx(total, rel=0.05)  # the stop's 10 s hold many independent samples
    assert 0.5 * total < speed < 1.5 * total
