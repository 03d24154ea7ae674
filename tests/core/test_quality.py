"""Uncertainty, fit quality and warnings in every result (benchmark.core.quality), the run's
real final status after a polish, the default pipeline, and the time-domain problem's speed
and stator-resistance options."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import least_squares

import benchmark.core.harness as harness
from benchmark.core.errors import ConfigError
from benchmark.core.identify import final_status, polish_converged
from benchmark.core.problem import OptimizeResult, Problem, Status
from benchmark.core.quality import assess, parameter_uncertainty
from tests.conftest import compose_config

FAST = ["figures=false", "checkpoint=false", "progress=false"]


@pytest.fixture(scope="module")
def good_run(tmp_path_factory):
    """The default pipeline on the built-in noisy paper record."""
    cfg = compose_config(["noise=noisy", *FAST])
    return harness.run(cfg, tmp_path_factory.mktemp("good")).record


@pytest.fixture(scope="module")
def bad_run(tmp_path_factory):
    """A deliberately bad fit: 200 evaluations of differential evolution."""
    cfg = compose_config(["optimizer=scipy_de", "budget=200", "noise=noisy", *FAST])
    return harness.run(cfg, tmp_path_factory.mktemp("bad")).record


def test_default_pipeline_is_multistart_and_converges(good_run):
    assert good_run["optimizer"] == "multistart"
    assert good_run["status"] == "converged"
    assert all(abs(e) < 0.005 for k, e in good_run["rel_error"].items() if k in ("Rs", "Ls", "Le", "Rr", "J"))


def test_a_good_fit_carries_no_warning(good_run):
    assert good_run["warnings"] == []
    fq = good_run["fit_quality"]
    assert set(fq) == {"i_alpha", "i_beta", "speed"}
    for v in fq.values():
        assert v["at_noise_level"], fq
        assert 0.8 < v["ratio"] < 1.2


def test_a_bad_fit_carries_the_warnings(bad_run):
    """200 evaluations of DE on an exact model: the misfit is the optimiser's, and the warning says
    so (a polish from its result, and the true parameters, cost far less), not "the model misses"."""
    w = bad_run["warnings"]
    assert bad_run["status"] == "budget_spent"
    assert any(s.startswith("the optimiser stopped short: a least-squares polish from the result lowers the cost")
               and "the polished fit is at the noise level" in s for s in w), w
    assert not any(s.startswith("the model misses the data") for s in w), w
    assert any(not v["at_noise_level"] and v["ratio"] > 10 for v in bad_run["fit_quality"].values())
    short = bad_run["review"]["stopped_short"]
    assert short["short"] and short["polished_cost"] < 0.1 * short["cost"] and short["truth_cost"] < short["cost"]


def test_standard_errors_and_correlation_are_sane(good_run):
    names = good_run["parameter_names"]
    se, R = good_run["standard_error"], np.array(good_run["correlation"], float)
    assert list(se) == names and R.shape == (len(names), len(names))
    assert np.allclose(R, R.T) and np.allclose(np.diag(R), 1.0) and np.all(np.abs(R) <= 1.0)
    est, truth = good_run["estimate"], good_run["truth"]
    for k in names:
        assert 0 < se[k] < 0.01 * abs(est[k])  # well determined on this record
        assert abs(est[k] - truth[k]) < 5 * se[k]  # and honest: the truth within a few SE
    unc = good_run["uncertainty"]
    assert unc["counted_in_budget"] is False and unc["evaluations"] == 2 * len(names) + 1
    assert good_run["evaluations"] <= good_run["budget"]


def test_report_has_standard_errors_correlation_and_verdict(tmp_path):
    cfg = compose_config(["noise=noisy", "budget=3000", "progress=false", "checkpoint=false"])
    rec = harness.run(cfg, tmp_path).record
    text = (tmp_path / "report.md").read_text()
    assert "standard error" in text and "Correlation of the searched parameters" in text
    assert "Fit quality" in text and ("Warnings" in text)
    assert rec["standard_error"] is not None


# -- coverage on a small Monte-Carlo --------------------------------------------------------
class _Decay(Problem):
    """y = a exp(-t / tau) + c sampled fast, with AR(1) (coloured) or white noise."""

    name = "decay"
    parameter_names = ("a", "tau", "c")

    def __init__(self, y, t):
        self.y, self.t = y, t
        self.lower, self.upper = np.array([0.1, 0.01, -1.0]), np.array([10.0, 10.0, 1.0])

    def model(self, X):
        X = np.atleast_2d(X)
        return X[:, :1] * np.exp(-self.t[None, :] / X[:, 1:2]) + X[:, 2:3]

    def residuals_batch(self, X):
        return self.y[None, :] - self.model(X)

    def residuals(self, x):
        return self.residuals_batch(np.asarray(x)[None, :])[0]

    @property
    def has_residuals(self):
        return True

    def evaluate(self, X):
        R = self.residuals_batch(X)
        return np.einsum("ij,ij->i", R, R)

    def estimate(self, x):
        return dict(zip(self.parameter_names, map(float, x), strict=True))


@pytest.mark.parametrize("phi", [0.0, 0.9])
def test_coverage_of_95_percent_intervals_on_a_small_monte_carlo(phi):
    rng = np.random.default_rng(7)
    t = np.linspace(0, 3, 1500)
    truth = np.array([2.0, 0.7, 0.3])
    hit = n = 0
    for _ in range(60):
        e = rng.normal(0, 0.05, len(t))
        if phi:
            for k in range(1, len(t)):
                e[k] = phi * e[k - 1] + np.sqrt(1 - phi**2) * e[k]
        p = _Decay(_Decay(None, t).model(truth)[0] + e, t)
        x = least_squares(p.residuals, np.array([1.5, 1.0, 0.0]), bounds=(p.lower, p.upper)).x
        se = np.array(list(parameter_uncertainty(p, x)["standard_error"].values()))
        hit += int(np.sum(np.abs(x - truth) <= 1.96 * se))
        n += 3
    assert 0.85 <= hit / n <= 0.99, hit / n


# -- status of a polished run ------------------------------------------------------------
def _result(status):
    return OptimizeResult(x=np.ones(2), fun=1.0, nfev=10, nit=1, status=status, message="", optimizer="x", seed=0,
                          wall_time_s=0.0)


def test_a_polished_run_reports_how_the_polish_ended():
    assert polish_converged("`ftol` termination condition is satisfied.")
    assert not polish_converged("budget of 2000 evaluations spent")
    assert final_status(_result(Status.BUDGET_SPENT), {"evaluations": 50, "converged": True}) == "converged"
    assert final_status(_result(Status.BUDGET_SPENT), {"evaluations": 2000, "converged": False}) == "budget_spent"
    assert final_status(_result(Status.FAILED), {"evaluations": 5, "converged": True}) == "failed"
    assert final_status(_result(Status.BUDGET_SPENT), None) == "budget_spent"


def test_polished_record_keeps_the_optimizers_status(tmp_path):
    cfg = compose_config(["optimizer=scipy_de", "budget=1500", "polish=true", *FAST])
    rec = harness.run(cfg, tmp_path).record
    assert rec["status_optimizer"] == "budget_spent"
    assert rec["status"] == ("converged" if rec["polish"]["converged"] else "budget_spent")


# -- time-domain problem: no speed sensor, stator resistance options ---------------------------
@pytest.fixture(scope="module")
def paper_problem():
    cfg = compose_config(["motor.test.cycles=10", "motor.test.stop_duration=3.0", "noise=noisy"])
    return harness.build_problem(cfg)


def _rebuild(problem, **kw):
    from benchmark.problems.timedomain.problem import TimeDomainProblem

    ds = kw.pop("dataset", problem.dataset)
    names = [n for n in problem.parameter_names if not (kw.get("stator_resistance") == "fixed" and n == "Rs")]
    idx = [problem.parameter_names.index(n) for n in names]
    return TimeDomainProblem(ds, problem.lower[idx], problem.upper[idx], mechanical=problem.mechanical,
                             inertia=problem.inertia, exponent=problem.exponent, weights=problem.weights,
                             truth=problem.truth, **kw)


def test_a_record_without_speed_gets_speed_weight_zero(paper_problem):
    ds = paper_problem.dataset
    no_speed = replace(ds, startups=[replace(r, speed=np.full_like(r.speed, np.nan)) for r in ds.startups])
    p = _rebuild(paper_problem, dataset=no_speed)
    assert p.weights[2] == 0 and not p.speed_measured
    x = np.array([paper_problem.truth[n] for n in p.parameter_names])
    c = p.evaluate(x[None, :])
    assert np.all(np.isfinite(c))
    assert [name for name, *_ in p.fit_channels(x)] == ["i_alpha", "i_beta"]


def test_stator_resistance_fixed_prior_and_dc_warning(paper_problem):
    ds = paper_problem.dataset
    rs = paper_problem.truth["Rs"]
    with pytest.raises(ConfigError, match="stator_dc_resistance"):
        _rebuild(paper_problem, stator_resistance="fixed")
    with_dc = replace(ds, stator_dc_resistance=rs, winding_temperature=20.0)
    fixed = _rebuild(paper_problem, dataset=with_dc, stator_resistance="fixed")
    assert "Rs" not in fixed.parameter_names
    assert fixed.estimate(np.array([paper_problem.truth[n] for n in fixed.parameter_names]))["Rs"] == rs
    prior = _rebuild(paper_problem, dataset=with_dc, stator_resistance="prior")
    x = np.array([paper_problem.truth[n] for n in prior.parameter_names])
    x_off = x.copy()
    x_off[0] *= 1.3
    assert prior.residuals(x).shape[0] == paper_problem.residuals(x).shape[0] + 1
    assert prior.residuals(x)[-1] == 0.0 and prior.residuals(x_off)[-1] > 0
    free = _rebuild(paper_problem, dataset=with_dc)
    assert free.quality_warnings(x) == []
    w = free.quality_warnings(x_off)
    assert len(w) == 1 and "departs from the DC resistance" in w[0] and "+30 %" in w[0]


def test_assess_never_raises_and_reports_bounds(paper_problem):
    x = paper_problem.lower.copy()
    out = assess(paper_problem, x, status="converged")
    assert any("sits at its lower bound" in w for w in out["warnings"])
    assert assess(paper_problem, None, status="failed")["warnings"] == []
