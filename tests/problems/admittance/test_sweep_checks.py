"""A slip sweep's careless mistakes are refused on load with the fix
(:mod:`benchmark.problems.admittance.sweep_checks`). A cold user's sweep of a textbook circuit
gave, with the slip in per cent, "converged" with R2 100 times too large; in mS a circuit 1000
times too small with 20 warnings, none on units; with B positive, an error about readings near
synchronous speed."""

from __future__ import annotations

import pandas as pd
import pytest

from benchmark.core.errors import DataError
from benchmark.problems.admittance.circuit import slip_from_speed
from benchmark.problems.admittance.data import load_admittance
from synthetic.admittance import generate
from tests.conftest import compose_config


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """Lindsay and Barton's noisy sweep through braking (slip 2), motoring and generating, with
    its DC resistance, written with a ``slip`` column instead of the speed."""
    cfg = compose_config(["problem=admittance", "noise=noisy", "noise.seed=3"])
    folder = generate(cfg, tmp_path_factory.mktemp("sweep") / "ok")
    table = pd.read_csv(folder / "sweep01.csv")
    table.insert(0, "slip", slip_from_speed(table.pop("speed_rpm").to_numpy(), 60.0, 2))
    table.to_csv(folder / "sweep01.csv", index=False)
    return folder


def _variant(ok, tmp_path, edit):
    table = pd.read_csv(ok / "sweep01.csv")
    edit(table)
    folder = tmp_path / "variant"
    folder.mkdir()
    (folder / "meta.yaml").write_text((ok / "meta.yaml").read_text())
    table.to_csv(folder / "sweep01.csv", index=False)
    return folder


def test_the_sweep_as_measured_loads(sweep):
    data = load_admittance(sweep)
    assert data.slip.max() == pytest.approx(2.0) and data.slip.min() < 0  # braking to generating


@pytest.mark.parametrize(("edit", "words"), [
    (lambda t: t.__setitem__("slip", 100.0 * t["slip"]), ["column 'slip'", "per cent? Divide it by 100"]),
    (lambda t: t.__setitem__("B", -t["B"]), ["column 'B'", "negate the column B"]),
    (lambda t: t.__setitem__(["G", "B"], 1000.0 * t[["G", "B"]]), ["column 'G, B'", "not mS",
                                                                   "stator_dc_resistance"]),
])
def test_a_careless_sweep_is_refused_with_the_fix(sweep, tmp_path, edit, words):
    with pytest.raises(DataError) as info:
        load_admittance(_variant(sweep, tmp_path, edit))
    assert all(w in str(info.value) for w in words), str(info.value)
