"""Figures beside every result.json (PNG and SVG), listed in report.md; a figure that fails
costs a warning, never the result; figures=false makes none."""

from __future__ import annotations

import json

import numpy as np
import pytest

import benchmark.core.plotting as figures
from benchmark.core.harness import build_problem, run
from tests.conftest import compose_config

PNG = b"\x89PNG\r\n\x1a\n"
EXPECTED = {
    "timedomain": ["startup", "startup_zoom", "stop", "convergence"],
    "admittance": ["admittance", "current_power_factor", "torque", "convergence"],
}


def _check_figures(folder, names):
    rec = json.loads((folder / "result.json").read_text())
    assert rec["figures"]["errors"] == [], rec["figures"]
    assert rec["figures"]["files"] == [f"{n}.{ext}" for n in names for ext in ("png", "svg")]
    report = (folder / "report.md").read_text()
    for n in names:
        png, svg = folder / f"{n}.png", folder / f"{n}.svg"
        assert png.read_bytes()[:8] == PNG
        assert svg.read_text().lstrip().startswith("<?xml") and "<svg" in svg.read_text()
        assert 2_000 < svg.stat().st_size < 1_000_000, (svg, svg.stat().st_size)  # long records are reduced
        assert f"]({n}.png)" in report and f"[SVG]({n}.svg)" in report
    return rec, report


@pytest.mark.parametrize("problem", ["timedomain", "admittance"])
def test_a_tiny_run_gets_its_figures_and_report(tmp_path, problem):
    run(compose_config([f"problem={problem}", "optimizer=genesis", "budget=200", "checkpoint=false"]), tmp_path)
    rec, report = _check_figures(tmp_path, EXPECTED[problem])
    assert report.startswith(f"# {problem} / genesis, seed 0")
    assert "| parameter | unit | estimate | truth | error |" in report
    assert ("| J | kg m^2 |" if problem == "timedomain" else "| X1 | ohm |") in report
    assert rec["figures"]["report"] == "report.md" and rec["figures"]["time_s"] > 0


def test_time_domain_without_stop_record_has_no_stop_figure(tmp_path):
    from benchmark.problems.timedomain.data import write_startup_dataset
    from synthetic.timedomain import make_dataset

    ds, truth = make_dataset(compose_config([]))
    ds.stops = []
    write_startup_dataset(tmp_path / "ds", ds, truth)
    run(compose_config([f"data.path={tmp_path / 'ds'}", "budget=100", "checkpoint=false"]), tmp_path / "run")
    _check_figures(tmp_path / "run", ["startup", "startup_zoom", "convergence"])


def test_a_figure_failure_never_loses_the_result(tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("no display for you")

    monkeypatch.setattr(figures, "write_run_figures", broken)
    out = run(compose_config(["budget=100", "checkpoint=false"]), tmp_path)
    rec = json.loads((tmp_path / "result.json").read_text())
    assert rec["status"] == "budget_spent" and rec["estimate"] == out.record["estimate"]
    assert any("figure not made (RuntimeError: no display for you)" in w for w in rec["warnings"])
    assert rec["figures"]["files"] == []


def test_one_failing_figure_leaves_the_others(tmp_path, monkeypatch):
    def broken_stop(stop, used_case):
        def draw(fig):
            raise ValueError("bad stop")
        return draw

    import benchmark.problems.timedomain.figures as td_figures

    monkeypatch.setattr(td_figures, "_stop_drawer", broken_stop)
    run(compose_config(["budget=100", "checkpoint=false"]), tmp_path)
    rec = json.loads((tmp_path / "result.json").read_text())
    assert rec["figures"]["errors"] == ["stop: ValueError: bad stop"]
    assert not (tmp_path / "stop.png").exists() and (tmp_path / "startup.png").exists()
    assert "stop: ValueError: bad stop" in (tmp_path / "report.md").read_text()
    assert any("stop: ValueError: bad stop" in w for w in rec["warnings"])


def test_figures_false_makes_none(tmp_path):
    rec = run(compose_config(["budget=50", "figures=false", "checkpoint=false"]), tmp_path).record
    assert "figures" not in rec
    assert not list(tmp_path.glob("*.png")) and not (tmp_path / "report.md").exists()


def test_envelope_draws_the_same_extremes_from_few_points():
    rng = np.random.default_rng(1)
    t = np.arange(123_457) * 1e-4
    y = np.sin(2 * np.pi * 50 * t) * np.exp(-t) + 0.01 * rng.standard_normal(len(t))
    y[5000:5010] = np.nan  # a diverged stretch stays a gap, and the rest still reduces
    te, ye = figures.envelope(t, y, bins=500)
    assert len(te) <= 2 * 500 + 2 * 247
    assert np.all(np.diff(te) >= 0)
    assert np.nanmax(ye) == np.nanmax(y) and np.nanmin(ye) == np.nanmin(y)
    assert len(figures.envelope(t[:900], y[:900], bins=500)[1]) == 900  # short records as they are


def test_admittance_model_curves_pass_through_the_data_at_the_truth():
    """The figure's model (admittance, current, torque) at the true parameters reproduces the
    noise-free synthetic readings, so the curves drawn are the identified model's."""

    cfg = compose_config(["problem=admittance"])
    problem = build_problem(cfg)
    x = np.array([problem.truth[n] for n in problem.parameter_names])
    from benchmark.problems.admittance.figures import _admittance_curves

    (c,) = _admittance_curves(problem, x)
    m = (len(c["model_Y"]) - 1) // (len(c["Y"]) - 1)
    np.testing.assert_allclose(c["model_Y"][::m], c["Y"], atol=1e-5 * np.abs(c["Y"]).max())
    np.testing.assert_allclose(c["model_T"][::m], c["T"], atol=1e-5 * np.abs(c["T"]).max())


def test_diverged_or_failing_simulation_costs_only_the_start_up_figures(tmp_path):

    cfg = compose_config(["budget=50"])
    problem = build_problem(cfg)
    record = {"problem": "timedomain", "optimizer": "probe", "seed": 0, "evaluations": 0, "warnings": []}
    x = np.array([4.9, 0.1075, 1e-7, 1.5, 0.0064])  # Le -> 0: diverges at once
    info = figures.write_run_figures(problem, record, x, tmp_path / "diverged")
    assert info["errors"] == [] and "startup.png" in info["files"]

    def boom(X):
        raise FloatingPointError("simulator exploded")

    problem.simulate = boom
    info = figures.write_run_figures(problem, record, x, tmp_path / "failed")
    assert info["errors"] == ["startup: FloatingPointError: simulator exploded",
                              "startup_zoom: FloatingPointError: simulator exploded"]
    assert info["files"] == ["stop.png", "stop.svg"]  # no history.csv here: no convergence plot
