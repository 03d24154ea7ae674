"""The default pipeline's own behaviour: the cost stage reaches the minimum of a cost that is not
the sum of squares (checked against a linear program's exact L1 fit), a sum-of-squares cost
skips it, and an unconfirmed minimum says so with what to try instead."""

from __future__ import annotations

from functools import partial

import numpy as np
from scipy.optimize import linprog

import plugins.multistart as ms
from benchmark.core.budget import BudgetedProblem, run_plugin
from benchmark.core.problem import Problem


class LineFit(Problem):
    """Fit ``y = a + b t + c t^2`` to data with outliers; the cost is the sum of absolute
    residuals (like eq. 15) or of squares (``l1=False``)."""

    name = "line_fit"
    parameter_names = ("a", "b", "c")
    lower = np.array([0.1, 0.1, 0.01])
    upper = np.array([10.0, 10.0, 1.0])

    def __init__(self, l1: bool = True):
        rng = np.random.default_rng(7)
        self.t = np.linspace(0.0, 3.0, 400)
        self.y = 2.0 + 1.5 * self.t + 0.3 * self.t**2 + rng.laplace(0.0, 0.2, self.t.size)
        self.y[::37] += 4.0  # outliers pull the least-squares fit away from the L1 fit
        self.l1 = l1

    def residuals_batch(self, X):
        X = np.atleast_2d(X)
        return self.y[None, :] - (X[:, :1] + X[:, 1:2] * self.t + X[:, 2:3] * self.t**2)

    def residuals(self, x):
        return self.residuals_batch(np.asarray(x, float)[None, :])[0]

    def evaluate(self, X):
        R = self.residuals_batch(X)
        return np.abs(R).sum(axis=1) if self.l1 else (R**2).sum(axis=1)

    def cost_from_residuals(self, r):
        return float(np.abs(r).sum()) if self.l1 else float(r @ r)


def _l1_optimum(p: LineFit) -> float:
    """The exact least-absolute-deviations fit, as a linear program (min sum e+ + e-)."""
    n = p.t.size
    A = np.column_stack([np.ones(n), p.t, p.t**2])
    res = linprog(np.r_[np.zeros(3), np.ones(2 * n)], A_eq=np.hstack([A, np.eye(n), -np.eye(n)]), b_eq=p.y,
                  bounds=[(lo, hi) for lo, hi in zip(p.lower, p.upper, strict=True)] + [(0, None)] * (2 * n))
    return float(res.fun)


def test_the_cost_stage_reaches_the_l1_minimum_least_squares_misses():
    p = LineFit()
    exact = _l1_optimum(p)
    ls_point = np.linalg.lstsq(np.column_stack([np.ones(p.t.size), p.t, p.t**2]), p.y, rcond=None)[0]
    at_ls = float(p.evaluate(ls_point[None, :])[0])
    assert at_ls > exact * 1.005  # the outliers make the two minima differ
    res = run_plugin(ms.minimize, BudgetedProblem(p, 6000), seed=1, name="multistart")
    assert "cost stage" in res.message and res.message.startswith("converged")
    assert res.fun <= exact * (1 + 1e-5)
    # with a token global stage (its 30 samples cannot find the L1 minimum) the cost stage does it
    tiny = partial(ms.minimize, global_fraction=0.005)
    assert run_plugin(tiny, BudgetedProblem(p, 6000), seed=1, name="m").fun <= exact * (1 + 1e-5)
    without = run_plugin(partial(tiny, cost_fraction=0.0), BudgetedProblem(p, 6000), seed=1, name="m")
    assert without.fun > exact * 1.004  # least squares' point


def test_a_sum_of_squares_cost_skips_the_cost_stage():
    res = run_plugin(ms.minimize, BudgetedProblem(LineFit(l1=False), 6000), seed=1, name="multistart")
    assert res.message.startswith("converged") and "cost stage" not in res.message


def test_an_unconfirmed_minimum_says_so_and_what_to_try():
    res = run_plugin(partial(ms.minimize, starts=1), BudgetedProblem(LineFit(), 6000), seed=1, name="m")
    assert res.message.startswith("not confirmed") and ms.ADVICE in res.message
