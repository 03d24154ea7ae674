"""benchmark.api: keyword arguments become the command line's configuration (misspellings named),
a data set round-trips through memory bit for bit, results read and export what the run wrote,
and simulate reproduces a record from the parameters that made it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.io

from benchmark import api
from benchmark._api.overrides import override_value, to_overrides
from benchmark.core.errors import ConfigError, DataError

REPO = Path(__file__).resolve().parents[2]


def test_keyword_arguments_are_hydra_overrides():
    assert to_overrides({"budget": 2000, "problem__stator_resistance": "prior", "polish": True,
                         "bounds": {"Rs": [1, 10.5]}, "candidates": ["double_cage"], "time_limit_s": None}) == [
        "budget=2000", "problem.stator_resistance=prior", "polish=true", "bounds={Rs:[1,10.5]}",
        "candidates=[double_cage]", "time_limit_s=null"]
    assert to_overrides({"experiment": "table1"}, added_groups=["experiment"]) == ["+experiment=table1"]
    # strings that would read as another type, or hold the grammar's characters, are quoted
    assert override_value("true") == "'true'" and override_value("a b,c") == "'a b,c'"
    assert override_value("it's") == "'it\\'s'" and override_value(np.float64(0.5)) == "0.5"
    with pytest.raises(ConfigError, match="double underscore"):
        to_overrides({"_private": 1})


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"budgett": 10}, "budgett: unknown key (did you mean budget?)"),
    ({"problem__stator_resistanse": "prior"}, "problem.stator_resistanse: unknown key (did you mean "
                                              "problem.stator_resistance?)"),
    ({"optimizer": "deep"}, "optimizer=deep: no such option (did you mean deap?)"),
    ({"effect": "double_cage"}, "effect: unknown key (conf/effect/ is the diagnosis's catalogue"),
])
def test_a_misspelt_key_is_named_before_any_work(kwargs, message):
    with pytest.raises(ConfigError) as info:
        api.identify(**kwargs)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_an_in_memory_data_set_is_the_folder_bit_for_bit(tmp_path):
    from synthetic.timedomain import generate
    from tests.conftest import compose_config

    folder = generate(compose_config(["noise=noisy", "motor.test.cycles=10", "motor.test.stop_duration=2"],
                                     name="synthetic"), tmp_path / "data")
    ds = api.load(folder)
    assert ds.kind == "startup" and ds.problem == "timedomain" and ds.unchanged()
    copy = api.DataSet(meta=dict(ds.meta), tables={k: v.copy() for k, v in ds.tables.items()}, truth=ds.truth)
    back = api.load(copy.write(tmp_path / "copy"))
    for name, table in ds.tables.items():
        assert np.array_equal(back.tables[name].to_numpy(), table.to_numpy())  # 17 digits: exact
    from_folder = api.identify(folder, optimizer="least_squares", budget=400)
    from_memory = api.identify(copy, optimizer="least_squares", budget=400)
    assert from_memory.estimate == from_folder.estimate and from_memory.cost == from_folder.cost
    assert from_folder.truth is not None and abs(from_folder.rel_error["Rs"]) < 0.02  # noisy, 10 cycles
    ds.tables["startup"].loc[5, "i_alpha"] += 1.0
    assert not ds.unchanged()


@pytest.mark.parametrize(("edit", "message"), [
    (lambda f: (f / "meta.yaml").write_text((f / "meta.yaml").read_text().replace("sample_time", "sampel_time")),
     "missing key 'sample_time' (found 'sampel_time': misspelt?)"),
    (lambda f: (f / "startup.csv").write_text("\n".join(
        ",".join(c for j, c in enumerate(line.split(",")) if j != 4) for line in
        (f / "startup.csv").read_text().splitlines()) + "\n"), "i_r"),
])
def test_a_mistake_is_refused_by_load_not_later(tmp_path, edit, message):
    """A cold user's misspelt key and missing current column loaded without a word and failed only
    at identify: load reads the folder as the identification will."""
    import shutil

    folder = Path(shutil.copytree(REPO / "examples" / "data" / "bench_1kw", tmp_path / "bench"))
    edit(folder)
    with pytest.raises(DataError) as info:
        api.load(folder)
    assert message in str(info.value) and str(folder) in str(info.value)
    assert api.load(folder, check=False).tables["startup"].shape[0] > 0  # the tables as they are


def test_the_result_reads_writes_and_exports(tmp_path):
    r = api.identify(optimizer="least_squares", budget=300, outdir=tmp_path / "run")
    assert r.status == "converged" and r.units["J"] == "kg m^2" and r.units["fv"] == "N m s/rad"
    assert max(abs(e) for e in r.rel_error.values()) < 1e-5  # the paper's noise-free case
    assert list(r.correlation.index) == ["Rs", "Ls", "Le", "Rr", "J"]
    assert np.allclose(np.diag(r.correlation.to_numpy()), 1.0)
    again = api.Identification.read(tmp_path / "run")
    assert again.to_dict() == r.to_dict() == json.loads((tmp_path / "run" / "result.json").read_text())
    table = str(r).splitlines()
    assert table[0].split()[:3] == ["parameter", "unit", "estimate"] and table[5].split()[:2] == ["J", "kg"]
    mat = scipy.io.loadmat(r.to_mat(tmp_path / "model"), squeeze_me=True)
    assert float(mat["Rs"]) == r.estimate["Rs"] and str(mat["units"]["Rs"]) == "ohm"
    assert float(mat["standard_error"]["Ls"]) == r.standard_error["Ls"] and np.isnan(float(mat["standard_error"]["fv"]))
    assert [str(n) for n in mat["parameter_names"]] == list(r.correlation.index)
    # a run read back from its folder knows its pole pairs (it wrote 0 to the .mat, and motulator refused)
    assert again.pole_pairs == r.pole_pairs == 1  # the paper's motor
    assert int(scipy.io.loadmat(again.to_mat(tmp_path / "read_back"), squeeze_me=True)["pole_pairs"]) == 1
    figures = r.figures()
    assert set(figures) == {"startup", "startup_zoom", "stop"} and figures["startup"].axes


def test_motulator_export_is_the_same_machine():
    pytest.importorskip("motulator")
    from synthetic.motulator_source import project_from_gamma

    est = {"Rs": 4.96434, "Ls": 0.1075, "Le": 0.01098, "Rr": 1.55618, "J": 0.00642, "fv": 0.00033, "fc": 0.04297}
    from benchmark._api.export import motulator_model

    m = motulator_model(est, pole_pairs=2)
    assert isinstance(m, api.MotulatorModel)
    par = m.machine_pars
    assert par.n_p == 2
    # the Gamma model with L_s = Ls holds the same stator impedance: back to Rs, Ls, Le, Rr
    back = project_from_gamma(par.R_s, par.R_r, par.L_ell, par.L_s)
    assert back == pytest.approx({k: est[k] for k in back}, rel=1e-12)
    # leakage of the Gamma model referred to the stator: Le = Ls L_ell / (Ls + L_ell)
    assert par.L_s * par.L_ell / (par.L_s + par.L_ell) == pytest.approx(est["Le"], rel=1e-12)
    assert m.mechanics.par.J == est["J"]
    # the friction torque B_L(w) w: fv w + fc above the smoothing speed
    assert m.mechanics.par.B_L(100.0) * 100.0 == pytest.approx(est["fv"] * 100.0 + est["fc"], rel=1e-12)


def test_simulate_reproduces_a_record_from_its_parameters():
    paper = {"Rs": 4.96434, "Ls": 0.1075, "Le": 0.01098, "Rr": 1.55618, "J": 0.00642, "fv": 0.00033, "fc": 0.04297}
    sim = api.simulate(paper)  # the paper's noise-free synthetic start-up
    assert list(sim.columns[:5]) == ["record", "t", "i_alpha", "i_beta", "speed"]
    peak = float(sim.i_alpha_measured.abs().max())
    assert peak > 10  # a direct start: tens of amperes
    # the generator integrates the same equations on a finer grid: agreement to a millionth of the peak
    assert float((sim.i_alpha - sim.i_alpha_measured).abs().max()) < 1e-6 * peak
    off = api.simulate(dict(paper, Rr=1.1 * paper["Rr"]))
    assert float((off.speed - off.speed_measured).abs().max()) > 1.0  # rad/s: a wrong rotor shows
    with pytest.raises(ConfigError, match="missing"):
        api.simulate({"Rs": 1.0})


def test_a_diagnosis_lists_its_names_that_are_not_firm():
    from benchmark._api.results import Diagnosis

    doc = {"status": "explained", "verdict": "leakage_saturation+sensor_offset",
           "effects": ["leakage_saturation", "sensor_offset"], "explained_share": 0.86,
           "gap_before": {"heldout_rms_over_noise": 1.39}, "gap_after": {"heldout_rms_over_noise": 1.07},
           "per_effect": [{"effect": "leakage_saturation", "firm": True}, {"effect": "sensor_offset", "firm": False}]}
    d = Diagnosis.from_document(doc, "report")
    assert d.not_firm == ["sensor_offset"] and d.gap_after == 1.07
    assert Diagnosis.from_document({**doc, "per_effect": [{"effect": "x"}]}, "").not_firm == []  # older documents
