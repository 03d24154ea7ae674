"""The time-domain problem end to end: pre-identification, cost, polish, file vs memory."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from benchmark.core.harness import build_problem, run
from benchmark.core.polish import polish_least_squares
from benchmark.problems.timedomain.bounds import derive_bounds
from benchmark.problems.timedomain.mechanical import fit_free_stop
from tests.conftest import PAPER_MOTOR, compose_config


def test_free_stop_case2_recovers_tau_and_coulomb(paper_records):
    st = paper_records["stop"]
    est = fit_free_stop(st["t"], st["speed"], case=2)
    assert est.tau_m == pytest.approx(PAPER_MOTOR.J / PAPER_MOTOR.fv, rel=1e-5)
    assert est.fc_over_J == pytest.approx(PAPER_MOTOR.fc / PAPER_MOTOR.J, rel=1e-5)
    # the electrical braking part is detected, not assumed (paper: drop the first 0.2 s)
    assert 0.1 < est.t_free < 0.4


def test_free_stop_case1_underestimates_tau(paper_records):
    """Case 1 ignores Coulomb friction: the w0/e time is about half the true tau_m
    (the paper reports 10.455 s against 19.417 s from case 2)."""
    st = paper_records["stop"]
    est = fit_free_stop(st["t"], st["speed"], case=1)
    assert 9.5 < est.tau_m < 11.5
    assert est.fc_over_J == 0.0


def test_free_stop_with_quantised_noisy_speed(paper_records):
    st = paper_records["stop"]
    rng = np.random.default_rng(1)
    w = np.round((st["speed"] + rng.normal(0, 0.2, st["speed"].shape)) / 0.5) * 0.5
    est = fit_free_stop(st["t"], w, case=2)
    assert est.tau_m == pytest.approx(PAPER_MOTOR.J / PAPER_MOTOR.fv, rel=0.01)
    assert est.fc_over_J == pytest.approx(PAPER_MOTOR.fc / PAPER_MOTOR.J, rel=0.01)


@pytest.fixture(scope="module")
def paper_problem():
    return build_problem(compose_config(["+experiment=table1"]))


def test_problem_searches_five_genes_and_truth_is_near_zero_cost(paper_problem):
    assert paper_problem.parameter_names == ("Rs", "Ls", "Le", "Rr", "J")
    truth = np.array([paper_problem.truth[n] for n in paper_problem.parameter_names])
    lo, hi = paper_problem.lower, paper_problem.upper
    centre = 0.5 * (lo + hi)
    assert np.all(np.abs(centre - truth) / (hi - lo) > 0.05)  # ranges are not centred on the truth
    c_truth = paper_problem.evaluate(truth[None])[0]
    c_off = paper_problem.evaluate((truth * 1.01)[None])[0]
    assert c_truth < 1e-3 * c_off  # the plant's finer integration leaves a tiny misfit
    est = paper_problem.estimate(truth)
    assert est["fv"] == pytest.approx(PAPER_MOTOR.fv, rel=1e-5)
    assert est["fc"] == pytest.approx(PAPER_MOTOR.fc, rel=1e-5)


def test_eq15_cost_from_residuals_matches_evaluate(paper_problem):
    x = np.array([paper_problem.truth[n] for n in paper_problem.parameter_names]) * 1.02
    r = paper_problem.residuals(x)
    assert paper_problem.cost_from_residuals(r) == pytest.approx(paper_problem.evaluate(x[None])[0], rel=1e-9)


def test_polish_from_a_rough_point_reaches_0p1_percent(paper_problem):
    truth = np.array([paper_problem.truth[n] for n in paper_problem.parameter_names])
    x0 = truth * np.array([1.06, 0.94, 1.10, 0.92, 1.05])
    bp = polish_least_squares(paper_problem, x0, 500)
    assert bp.nfev <= 500
    assert np.all(np.abs(bp.best_x / truth - 1) < 1e-3)


def test_genesis_short_run_then_polish_regression(tmp_path):
    """A faster variant of Table 1: 6000 trials of the GENESIS clone from the wide ranges,
    then polish. GENESIS alone lands within the tens of per cent it reaches at this budget
    (measured: see the assertion); polish takes every parameter within 0.1 %."""
    cfg = compose_config(["+experiment=table1", "budget=6000", "seed=0", "polish=true"])
    rec = run(cfg, tmp_path).record
    assert rec["evaluations_optimizer"] == 6000
    assert rec["polish"]["evaluations"] > 0
    assert rec["polish"]["cost_after"] < 1e-3 * rec["polish"]["cost_before"]
    assert max(abs(v) for v in rec["rel_error"].values()) < 1e-3
    saved = json.loads((tmp_path / "result.json").read_text())
    for key in ("problem", "optimizer", "seed", "estimate", "truth", "rel_error", "cost", "evaluations",
                "wall_time_s", "history", "versions", "config"):
        assert key in saved
    assert (tmp_path / saved["history"]).is_file()


def test_file_path_gives_same_estimate_as_memory(tmp_path):
    ds = tmp_path / "paper"
    proc = subprocess.run([sys.executable, "-m", "synthetic", f"out={ds}"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    base = ["+experiment=table1", "budget=1500", "seed=3", "polish=true", "polish_budget=300"]
    mem = run(compose_config(base), tmp_path / "mem").record
    disk = run(compose_config(base + [f"data.path={ds}", "use_motor_bounds_with_data=true"]),
               tmp_path / "disk").record
    assert disk["estimate"] == mem["estimate"]
    assert disk["truth"] == {k: v for k, v in mem["truth"].items() if k != "p"}


def test_derived_bounds_contain_truth_for_small_and_large_motors():
    """Bounds from the data alone bracket the truth, for the 1 kW paper motor and a motor
    scaled to ~100 kW (impedances / 100, inertia and friction x 100)."""
    from benchmark.problems.timedomain.data import StartupDataset, StartupRecord
    from benchmark.problems.timedomain.motor import InductionMotor
    from benchmark.problems.timedomain.protocol import StartupStopTest, run_startup_stop

    big = InductionMotor(Rs=0.0496, Ls=0.001075, Le=0.0001098, Rr=0.0156, J=0.642, fv=0.033, fc=4.3, p=2)
    for motor in (PAPER_MOTOR, big):
        rec = run_startup_stop(motor, StartupStopTest(cycles=100 if motor is big else 50, stop_duration=1.0))
        s = rec["startup"]
        ds = StartupDataset(pole_pairs=motor.p, sample_time=1 / 12000, input_hold="zoh", startups=[
            StartupRecord(t=s["t"], v_alpha=s["v_alpha"], v_beta=s["v_beta"], i_alpha=s["i_alpha"],
                          i_beta=s["i_beta"], speed=s["speed"])])
        names = ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")
        b = derive_bounds(ds, names)
        truth = motor.as_dict()
        for n in names:
            assert b[n][0] < truth[n] < b[n][1], (motor, n, b[n], truth[n])
