"""Issue 13: a record with no speed sensor (an unloaded direct-on-line start of the independent
plant, bench noise): the default pipeline finds Rs, Ls, Le, Rr within 3 % and J from the currents
alone, with its standard error. Friction is not held: with no speed and no stop record ``fv`` and
``fc`` are searched with the rest (the data fix only a combination of them, which the result
says)."""

from __future__ import annotations

from synthetic.independent import make_dataset, make_spec, write_dataset
from tests.conftest import identify_folder


def test_unloaded_start_without_speed_sensor(tmp_path):
    spec = make_spec("paper_1kw", "dol", [], seed=3, duration=0.5, has_speed=False)
    folder = write_dataset(make_dataset(spec), tmp_path / "nospeed")
    assert "speed" not in (folder / "startup.csv").read_text().splitlines()[0]
    rec = identify_folder(folder, tmp_path / "run")
    err, se = rec["rel_error"], rec["standard_error"]
    for k in ("Rs", "Ls", "Le", "Rr"):
        assert abs(err[k]) < 0.03, (k, err[k])
    assert abs(err["J"]) < 0.03 and se["J"] is not None and 0 < se["J"] < 0.05 * rec["estimate"]["J"]
    # the truth lies within a few standard errors of J
    assert abs(rec["estimate"]["J"] - rec["truth"]["J"]) < 4 * se["J"]
    assert any("no speed column" in w for w in rec["warnings"])
