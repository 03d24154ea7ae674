"""The stator resistance's prior acts where the data are biased
(:mod:`benchmark.problems.timedomain.stator_prior`).

Independent plant (no code shared with the model): a 3.7 kW motor started direct on line, its
current probes compressing the starting current and every channel carrying an offset, the DC
resistance in meta.yaml::

    python -m synthetic.independent --motor simulink_5hp --scenario dol \\
        --effects current_sensor_saturation,sensor_offset --dc-resistance --seed 1 --duration 0.6

The base model misses these data by tens of times the noise and, left free, puts Rs 83 % above
its DC value (the prior used to be weighed as one sample against 20 000 residuals: with it Rs
came out at +82.7 %, free +83.4 %). Weighed by the data's own uncertainty of Rs, the prior, the default when
meta.yaml gives the DC value, keeps Rs within a few per cent of it, and the result says what that
cost in misfit. On clean data the same prior moves nothing (the quantised and DC-warning tests
of :mod:`tests.core.test_quality` keep Rs where the data put it).
"""

from __future__ import annotations

import warnings

import pytest

from benchmark.core.harness import run
from synthetic.independent import make_dataset, make_spec, write_dataset
from tests.conftest import compose_config


@pytest.fixture(scope="module")
def biased(tmp_path_factory):
    spec = make_spec("simulink_5hp", "dol", ["current_sensor_saturation", "sensor_offset"], seed=1, duration=0.6)
    spec["meta"]["dc_resistance"] = True
    made = make_dataset(spec)
    return write_dataset(made, tmp_path_factory.mktemp("biased") / "motor"), made.meta["stator_dc_resistance"]


def _identify(folder, *overrides):
    cfg = compose_config([f"data.path={folder}", "figures=false", "checkpoint=false", "progress=false", *overrides])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run(cfg, folder.parent / f"run{'_'.join(overrides)}").record


def test_free_departs_the_prior_holds_and_says_what_it_cost(biased):
    folder, dc = biased
    free = _identify(folder, "problem.stator_resistance=free")
    assert free["estimate"]["Rs"] / dc - 1.0 > 0.5, free["estimate"]
    assert any("departs from the DC resistance" in w and "problem.stator_resistance=prior" in w
               for w in free["warnings"]), free["warnings"]
    assert free["notes"] == []

    prior = _identify(folder)  # the default: meta.yaml gives the DC resistance
    assert abs(prior["estimate"]["Rs"] / dc - 1.0) < 0.25, prior["estimate"]
    assert prior["problem_info"]["stator_resistance"] == "prior"
    (note,) = prior["notes"]
    assert note.startswith("Rs prior (the default where meta.yaml gives stator_dc_resistance;")
    assert "What it cost in misfit (RMS / noise): i_alpha" in note
    explained = prior["review"]["explained"]
    assert explained["weight"] == "HAC variance of Rs at the fit" and explained["Rs_data_alone"] / dc - 1.0 > 0.5
    # the cost, in misfit: the data alone fit the currents better than with the prior
    for ch in ("i_alpha", "i_beta"):
        assert explained["fit_quality_data_alone"][ch]["ratio"] < prior["fit_quality"][ch]["ratio"]
    assert not any("departs from the DC resistance" in w for w in prior["warnings"]), prior["warnings"]
