"""``python -m benchmark.analysis.aggregate``: the numbers of the summary against hand-computed ones.

The fixtures are hand-written result.json + history.csv files (two problems, one with two noise
instances and no truth, a failed run, a run that stopped on its own); every expected value below
is worked out by hand in the comments, not by the code under test.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from benchmark.analysis import aggregate as report
from benchmark.analysis import runs as sweep_runs
from benchmark.analysis import targets

REPO = Path(__file__).resolve().parents[2]
BUDGETS = [10, 50, 100, 200]


def write_run(
    root: Path,
    name: str,
    *,
    problem="toyA",
    optimizer="alpha",
    seed=0,
    status="budget_spent",
    evaluations=100,
    history=((1, 1.0),),
    rel_error=None,
    truth=True,
    noise_seed=0,
    polish=False,
    message="",
    plugin=None,
    params=("a", "b"),
    noise_std=0.0,
):
    d = root / name
    d.mkdir(parents=True)
    evals, best = zip(*history, strict=True)
    pd.DataFrame({"evaluations": evals, "best_cost": best, "phase": "optimizer"}).to_csv(
        d / "history.csv", index=False
    )
    rec = {
        "problem": problem,
        "optimizer": optimizer,
        "seed": seed,
        "status": status,
        "message": message,
        "parameter_names": list(params),
        "searched": {p: 1.0 + k for k, p in enumerate(params)},
        "estimate": {p: 1.0 + k for k, p in enumerate(params)},
        "truth": {p: 1.0 for p in params} if truth else None,
        "rel_error": rel_error,
        "cost": min(best),
        "evaluations": evaluations,
        "budget": 100,
        "polish": {"evaluations": 0} if polish else None,
        "wall_time_s": 2.0 + seed,
        "wall_time_optimizer_s": 0.5 + seed,
        "history": "history.csv",
        "config": {
            "problem": {"name": problem},
            "optimizer": {"name": optimizer, "plugin": plugin or {"k": 1}},
            "seed": seed,
            "budget": 100,
            "polish": polish,
            "noise": {"seed": noise_seed, "std": noise_std},
        },
    }
    (d / "result.json").write_text(json.dumps(rec))


@pytest.fixture
def runs_dir(tmp_path):
    root = tmp_path / "runs"
    # toyA / alpha: three runs that spend their budget of 100
    write_run(
        root, "a0", seed=0, history=[(10, 5.0), (50, 2.0), (100, 1.0)], rel_error={"a": 0.01, "b": -0.005}
    )
    write_run(root, "a1", seed=1, history=[(1, 8.0), (20, 3.0), (80, 1.5)], rel_error={"a": 0.02, "b": 0.0})
    write_run(root, "a2", seed=2, history=[(5, 4.0), (60, 1.2)], rel_error={"a": 0.04, "b": 0.005})
    # toyA / beta: one stops on its own after 40, one spends 100, one fails after 30
    write_run(
        root,
        "b0",
        optimizer="beta",
        seed=0,
        status="converged",
        evaluations=40,
        history=[(1, 3.0), (40, 1.005)],
        rel_error={"a": 0.001, "b": -0.001},
    )
    write_run(
        root,
        "b1",
        optimizer="beta",
        seed=1,
        history=[(2, 6.0), (90, 1.008)],
        rel_error={"a": 0.002, "b": 0.003},
    )
    write_run(
        root,
        "b2",
        optimizer="beta",
        seed=2,
        status="failed",
        evaluations=30,
        history=[(3, 7.0)],
        rel_error={"a": 0.5, "b": 0.5},
        message="RuntimeError: boom",
    )
    # toyB: no truth, two noise instances with their own best cost
    write_run(
        root,
        "c0",
        problem="toyB",
        noise_seed=0,
        history=[(1, 10.0), (10, 2.0)],
        truth=False,
        params=("x", "y"),
    )
    write_run(
        root,
        "c1",
        problem="toyB",
        noise_seed=1,
        history=[(1, 20.0), (10, 4.0)],
        truth=False,
        params=("x", "y"),
    )
    return root


def rows_by_label(rows):
    return {(r.group, r.algorithm): r.values for r in rows}


def test_quantile_is_numpy_linear_and_keeps_inf():
    x = [3.0, 1.0, 4.0, 1.5]
    for q in (0.25, 0.5, 0.75):
        assert targets.quantile(x, q) == pytest.approx(np.quantile(x, q), abs=0)
    assert targets.quantile([1.0, 2.0, math.inf], 0.5) == 2.0
    assert targets.quantile([1.0, math.inf], 0.5) == math.inf
    assert targets.quantile([2.0, math.nan], 0.5) == 2.0  # NaN = no value at this budget
    assert math.isnan(targets.quantile([], 0.5))


def test_summary_numbers(runs_dir):
    opts = report.parse_args([str(runs_dir), f"budgets={BUDGETS}"])
    runs = sweep_runs.load_runs(runs_dir)
    sweep_runs.label_runs(runs)
    rows, inst = targets.summarize(runs, opts)
    v = rows_by_label(rows)
    assert sorted(v) == [("toyA", "alpha"), ("toyA", "beta"), ("toyB", "alpha")]
    A, B, C = v[("toyA", "alpha")], v[("toyA", "beta")], v[("toyB", "alpha")]

    # relative errors of alpha: a = 0.01, 0.02, 0.04 -> median 0.02, q25 0.015, q75 0.03
    assert A["a_median"] == pytest.approx(0.02)
    assert A["a_q25"] == pytest.approx(0.015) and A["a_q75"] == pytest.approx(0.03)
    assert A["a_iqr"] == pytest.approx(0.015)
    assert A["b_median"] == pytest.approx(0.0) and A["b_iqr"] == pytest.approx(0.005)
    # success within 1 %: only a0 (a = 0.01, b = -0.005)
    assert (A["success_n"], A["success_rate"]) == (1, pytest.approx(1 / 3))
    # beta: the failed run is counted, excluded from the error statistics, and unsuccessful
    assert (B["runs"], B["failed"]) == (3, 1)
    assert B["a_median"] == pytest.approx(0.0015)  # median of 0.001, 0.002 (not 0.5)
    assert (B["success_n"], B["success_rate"]) == (2, pytest.approx(2 / 3))
    assert B["wall_time_median_s"] == pytest.approx(3.0)  # 2, 3, 4 s
    assert B["optimizer_time_median_s"] == pytest.approx(1.5)  # the search alone: 0.5, 1.5, 2.5 s

    # f* of toyA = 1.0 (a0); target 1 % above: 1.01. alpha: only a0 reaches it, at 100;
    # ERT = (100 + 100 + 100) / 1. beta: b0 at 40, b1 at 90, b2 (failed after 30) never:
    # ERT = (40 + 90 + 30) / 2 = 80, median 65.
    assert inst[("toyA", "0")].best == 1.0
    assert (A["target_reached"], A["evals_to_target_median"], A["ert"]) == (1, 100.0, 300.0)
    assert (B["target_reached"], B["evals_to_target_median"], B["ert"]) == (2, 65.0, 80.0)

    # fixed budgets. alpha at 10: 5.0 (a0), 8.0 (a1), 4.0 (a2) -> 5.0; at 50: 2, 3, 4 -> 3;
    # at 100: 1, 1.5, 1.2 -> 1.2; at 200 no run was given 200 evaluations.
    assert [A[f"cost_at_{b}_median"] for b in (10, 50, 100)] == [5.0, 3.0, 1.2]
    assert A["cost_at_200_n"] == 0 and math.isnan(A["cost_at_200_median"])
    # beta at 10: 3, 6, 7 -> 6. At 50: b0 stopped on its own (keeps 1.005), b1 6.0, b2 failed at 30
    # (no value) -> median of 1.005 and 6.0 over 2 runs. At 200 only b0 -> 1.005.
    assert B["cost_at_10_median"] == 6.0 and B["cost_at_10_n"] == 3
    assert B["cost_at_50_median"] == pytest.approx(3.5025) and B["cost_at_50_n"] == 2
    assert B["cost_at_200_median"] == 1.005 and B["cost_at_200_n"] == 1

    # toyB: per-instance best costs 2 and 4; both runs reach their own target at 10
    assert inst[("toyB", "0")].best == 2.0 and inst[("toyB", "1")].best == 4.0
    assert (C["instances"], C["target_reached"], C["ert"]) == (2, 2, 10.0)
    assert C["success_n"] is None  # no truth: no success rate

    wins = targets.winners(rows, opts)["toyA"]
    assert wins[0].startswith("at 10 evaluations: **alpha** (median best cost 5")
    assert any(w.startswith("at 50 evaluations: **alpha**") for w in wins)  # beta has 2/3 runs at 50
    assert any(w.startswith("fixed target: **beta** (ERT 80") for w in wins)
    assert any(w.startswith("parameter accuracy: **beta** (2/3") for w in wins)


def test_labels_split_problems_and_optimizer_settings(tmp_path):
    root = tmp_path / "runs"
    write_run(root, "p0", optimizer="alpha", plugin={"popsize": 10}, history=[(1, 2.0)])
    write_run(root, "p1", optimizer="alpha", plugin={"popsize": 20}, history=[(1, 2.0)])
    write_run(root, "p2", optimizer="alpha", plugin={"popsize": 10}, polish=True, history=[(1, 2.0)])
    write_run(root, "p3", optimizer="alpha", plugin={"popsize": 10}, noise_std=0.05, history=[(1, 2.0)])
    runs = sweep_runs.load_runs(root)
    sweep_runs.label_runs(runs)
    labels = {r.path.parent.name: (r.group, r.algorithm) for r in runs}
    assert labels["p0"] == ("toyA (noise.std=0.0)", "alpha (popsize=10)")
    assert labels["p1"] == ("toyA (noise.std=0.0)", "alpha (popsize=20)")
    assert labels["p2"] == ("toyA (noise.std=0.0)", "alpha+polish")
    assert labels["p3"] == ("toyA (noise.std=0.05)", "alpha")


def test_cli_writes_tables_figures_and_ioh_export(runs_dir, tmp_path):
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "benchmark.report", str(runs_dir), f"out={out}", "budgets=[10,50,100,200,5000]"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert "8 runs (1 failed)" in proc.stdout

    df = pd.read_csv(out / "summary.csv")
    row = df[(df.problem == "toyA") & (df.optimizer_label == "alpha")].iloc[0]
    assert row["a_median"] == pytest.approx(0.02) and row["ert"] == 300 and row["cost_at_100_median"] == 1.2

    md = (out / "summary.md").read_text()
    assert "| alpha | 3 | 0 | 1/3 | +2 % [1.5 %] | +0 % [0.5 %] |" in md
    # beta at 100: b0 1.005 (stopped on its own), b1 1.008 -> 1.0065 over 2 of 3 runs
    assert "| beta | 2/3 | 65 | 80 | 6 | 3.502 (2/3) | 1.006 (2/3) | 1.005 (1/3) |" in md
    assert "- beta seed 2: RuntimeError: boom (`b2`)" in md
    # toyA's converged run holds its cost at every budget; no toyB run reached 200: no empty columns
    toy_a, toy_b = md.split("## toyB")[0], md.split("## toyB")[1]
    assert "best cost at 5000" in toy_a and "best cost at 100 |" in toy_b
    assert "best cost at 200" not in toy_b and "best cost at 5000" not in toy_b
    tex = (out / "summary.tex").read_text()
    assert r"\toprule" in tex and r"alpha & 3 & 0 & 1/3 & +2 \% [1.5 \%]" in tex

    for kind in ("convergence", "ecdf"):
        for prob in ("toyA", "toyB"):
            assert (out / "figures" / f"{kind}_{prob}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
            assert "<svg" in (out / "figures" / f"{kind}_{prob}.svg").read_text()

    # IOHprofiler export: JSON index + .dat, one folder per optimiser
    doc = json.loads((out / "ioh" / "beta" / "IOHprofiler_f1_toyA.json").read_text())
    assert doc["maximization"] is False and doc["function_id"] == 1 and doc["algorithm"]["name"] == "beta"
    (scen,) = doc["scenarios"]
    assert scen["dimension"] == 2
    assert [(r["evals"], r["best"]["y"]) for r in scen["runs"]] == [(40, 1.005), (100, 1.008), (30, 7.0)]
    dat = (out / "ioh" / "beta" / scen["path"]).read_text().splitlines()
    # a header per run; every run starts at evaluation 1 and ends at its last evaluation
    assert dat == [
        "evaluations raw_y",
        "1 3",
        "40 1.005",
        "evaluations raw_y",
        "1 6",
        "2 6",
        "90 1.008",
        "100 1.008",
        "evaluations raw_y",
        "1 7",
        "3 7",
        "30 7",
    ]
    assert (out / "ioh.zip").stat().st_size > 0
    doc_b = json.loads((out / "ioh" / "alpha" / "IOHprofiler_f2_toyB.json").read_text())
    assert sorted(r["instance"] for r in doc_b["scenarios"][0]["runs"]) == [1, 2]


def test_bad_arguments_are_one_line_errors(tmp_path):
    for args, msg in (
        ([str(tmp_path)], "no result.json"),
        ([str(tmp_path), "bogus=1"], "bogus: unknown"),
        ([str(tmp_path), "budget=[100]"], r"budget: unknown argument \(did you mean budgets\?\)"),
        ([str(tmp_path / "nope")], "not a folder"),
        ([str(tmp_path), "budgets=[0]"], "budgets"),
        ([], "no folder given"),
    ):
        with pytest.raises(sweep_runs.ReportError, match=msg):
            report.main(args)
    proc = subprocess.run(
        [sys.executable, "-m", "benchmark.report", str(tmp_path)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2 and proc.stderr.startswith("error: ") and "no result.json" in proc.stderr


# -- results/crb.md: the Cramer-Rao bounds of benchmark.studies.crb -----------------------------


class LinearOutputs:
    """A stand-in for TimeDomainProblem.simulate: outputs (i_alpha, i_beta, speed) linear in theta,
    y_c = A_c theta, so the Fisher information is exactly sum_c A_c^T A_c / sigma_c^2."""

    def __init__(self, A):
        self.A = A  # (3, N, n)

    def simulate(self, X):
        return [np.einsum("cjk,mk->mcj", self.A, np.atleast_2d(X))]


def test_startup_fisher_of_a_linear_model():
    from benchmark.studies import crb

    rng = np.random.default_rng(1)
    A = rng.normal(size=(3, 50, 7))
    theta = np.array([5.0, 0.1, 0.01, 1.5, 0.006, 0.0003, 0.04])
    sc, sw = 0.05, 0.25
    F = crb.startup_fisher(LinearOutputs(A), theta, sc, sw)
    expected = (A[0].T @ A[0] + A[1].T @ A[1]) / sc**2 + A[2].T @ A[2] / sw**2
    np.testing.assert_allclose(F, expected, rtol=1e-6)


def test_stop_bound_matches_monte_carlo_least_squares():
    """The free-stop information on (w0, tau, b) against the spread of least-squares fits of
    the closed form to 300 noisy records (the fit is efficient here: linearisation is exact to
    well below the noise)."""
    from scipy import optimize

    from benchmark.studies import crb

    t = np.arange(0.0, 25.0, 0.01)
    w0, tau, b, sw = 260.0, 19.45, 6.69, 0.5
    bound = np.sqrt(np.diag(np.linalg.inv(crb.stop_fisher(t, w0, tau, b, sw))))

    def model(q):
        w = (q[0] + q[1] * q[2]) * np.exp(-t / q[1]) - q[1] * q[2]
        return np.where(w > 0, w, 0.0)

    clean = model([w0, tau, b])
    rng = np.random.default_rng(0)
    est = []
    for _ in range(300):
        y = clean + rng.normal(0.0, sw, t.shape)
        est.append(optimize.least_squares(lambda q, y=y: model(q) - y, [w0, tau, b], x_scale=[w0, tau, b]).x)
    spread = np.std(np.array(est), axis=0)
    # 300 fits: the sample standard deviation is within ~12 % of the truth at 3 sigma
    np.testing.assert_allclose(spread, bound, rtol=0.12)


def test_joint_bound_between_conditional_and_startup_only():
    """With a stop record that pins tau_m and fc/J, the joint bound of the 5 searched parameters
    tends to the conditional one; with a stop record that says nothing, to the start-up-only one."""
    from benchmark.studies import crb

    rng = np.random.default_rng(2)
    M = rng.normal(size=(40, 7))
    F7 = M.T @ M
    theta = np.array([1.2, 0.8, 1.1, 0.9, 1.3, 0.7, 1.05])  # O(1): the limits stay well conditioned
    sure = np.diag([1.0, 1e10, 1e10])  # (w0, tau, b): tau and b known exactly
    b = crb.bounds(theta, F7, sure)
    np.testing.assert_allclose(b["joint"][:5], b["conditional"][:5], rtol=1e-5)
    vague = np.diag([1.0, 1e-10, 1e-10])
    b = crb.bounds(theta, F7, vague)
    np.testing.assert_allclose(b["joint"], b["startup_only"], rtol=1e-5)
    # conditional fv and fc carry J's relative bound
    assert b["conditional"][5] / theta[5] == pytest.approx(b["conditional"][4] / theta[4])
    assert b["conditional"][6] / theta[6] == pytest.approx(b["conditional"][4] / theta[4])
