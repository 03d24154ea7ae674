"""Blind draws pooled (``python -m benchmark.analysis.blind_pool``): the scores of several draws as one
set of rows, and the diagnoses' wall times per source and kind of set."""

from __future__ import annotations

import json

import pytest

from benchmark.analysis import blind_pool
from tests.analysis.test_blind import _row


def _draws(tmp_path):
    a = [_row(0, [], "no_gap", [], gap=1.0), _row(1, ["double_cage"], "explained", ["double_cage"])]
    b = [_row(0, [], "explained", ["iron_loss"]), _row(1, ["iron_loss", "two_mass"], "explained", ["two_mass"])]
    for row, seconds in zip(a + b, (4.0, 30.0, 12.0, 250.0), strict=True):
        row["wall_time_s"] = seconds
    for name, rows in (("d1", a), ("d2", b)):
        (tmp_path / name / "plant").mkdir(parents=True)
        (tmp_path / name / "plant" / "blind.json").write_text(json.dumps({"sets": rows}))
    return [tmp_path / "d1", tmp_path / "d2"]


def test_pooled_draws_are_scored_as_one_set_of_rows(tmp_path, capsys):
    pooled = blind_pool.pooled(_draws(tmp_path))
    assert list(pooled) == ["plant"]
    s = pooled["plant"]
    assert (s["effect_sets_exact"], s["effect_sets"], s["false_alarms"], s["effect_free_sets"]) == (1, 2, 1, 2)
    assert (s["both_named"], s["two_effect_sets"], s["false_selection_sets"], s["scored"]) == (0, 1, 1, 4)
    blind_pool.main([str(tmp_path / "d1"), str(tmp_path / "d2")])
    out = capsys.readouterr().out
    assert "| plant | 1/2, 50 % (9-91 %) | 1/2, 50 % (9-91 %) | 0/1, 0 % (0-79 %) | 1/4, 25 % (5-70 %) |" in out
    with pytest.raises(SystemExit, match="no SOURCE/blind.json"):
        blind_pool.main([str(tmp_path)])


def test_wall_times_are_given_per_source_and_kind_of_set_with_the_slowest_set(tmp_path, capsys):
    times = blind_pool.wall_times(blind_pool.scored_sets(_draws(tmp_path)))
    assert list(times) == ["plant, effect sets", "plant, effect-free sets"]
    with_effects, free = times["plant, effect sets"], times["plant, effect-free sets"]
    assert (with_effects["sets"], with_effects["median"], with_effects["max"]) == (2, 140.0, 250.0)
    assert with_effects["p90"] == pytest.approx(228.0)  # 30 + 0.9 (250 - 30)
    assert with_effects["over_target"] == 1 and with_effects["slowest"] == "iron_loss+two_mass"
    assert (free["sets"], free["median"], free["max"], free["over_target"]) == (2, 8.0, 12.0, 0)
    assert free["slowest"] == "none"
    blind_pool.main([str(tmp_path / "d1"), str(tmp_path / "d2")])
    out = capsys.readouterr().out
    assert "| plant, effect sets | 2 | 140 | 228 | 250 | 1 (50 %) | iron_loss+two_mass |" in out
