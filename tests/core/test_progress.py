"""Progress of long runs: a tqdm bar (evaluations/budget, best cost, time left) on a terminal
only, quiet in CI, in sweeps and with progress=false, shown when forced with progress=true;
fed by BudgetedProblem.on_evaluate without changing what is counted."""

from __future__ import annotations

import io
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

from benchmark.core import harness
from benchmark.core.budget import BudgetedProblem
from benchmark.core.errors import ConfigError
from benchmark.core.harness import ProgressBar, progress_wanted, run
from benchmark.core.problem import Problem
from tests.conftest import compose_config


class TTY(io.StringIO):
    def isatty(self):
        return True


class Pipe(io.StringIO):
    def isatty(self):
        return False


def test_who_sees_the_bar():
    tty, pipe = TTY(), Pipe()
    assert progress_wanted("auto", stream=tty, environ={}, multirun=False)
    assert not progress_wanted("auto", stream=pipe, environ={}, multirun=False)
    assert not progress_wanted("auto", stream=tty, environ={"CI": "true"}, multirun=False)
    assert not progress_wanted("auto", stream=tty, environ={}, multirun=True)
    assert not progress_wanted(False, stream=tty, environ={}, multirun=False)
    assert progress_wanted(True, stream=pipe, environ={"CI": "1"}, multirun=True)
    assert progress_wanted("auto", stream=tty, environ={"CI": ""}, multirun=False)  # set but empty: not CI
    assert not progress_wanted("auto", stream=object(), environ={}, multirun=False)  # no isatty at all


def test_progress_must_be_auto_true_or_false(tmp_path):
    with pytest.raises(ConfigError, match="progress: must be auto, true or false, got 'yes'"):
        run(compose_config(["progress=yes", "budget=10"]), tmp_path)


def _tiny(*extra):
    return compose_config(["optimizer=genesis", "budget=200", "figures=false", "checkpoint=false", *extra])


def test_silent_when_stderr_is_not_a_terminal(tmp_path, capfd):
    run(_tiny(), tmp_path)  # pytest captures stderr: not a terminal
    assert "eval" not in capfd.readouterr().err


def test_terminal_shows_the_bar_but_not_in_ci(tmp_path, monkeypatch):
    fake = TTY()
    monkeypatch.setattr(sys, "stderr", fake)
    monkeypatch.setenv("CI", "true")
    run(_tiny(), tmp_path / "ci")
    assert fake.getvalue() == ""
    monkeypatch.delenv("CI")
    run(_tiny(), tmp_path / "tty")
    shown = fake.getvalue()
    assert "timedomain/genesis" in shown and "/200" in shown and "eval" in shown and "best" in shown


def test_forced_bar_shows_in_captured_stderr_and_changes_nothing(tmp_path, capsys):
    quiet = run(_tiny("progress=false"), tmp_path / "quiet").record
    assert capsys.readouterr().err == ""
    shown = run(_tiny("progress=true"), tmp_path / "shown").record
    err = capsys.readouterr().err
    assert "200/200" in err and "best" in err, err
    for key in ("estimate", "cost", "evaluations", "fingerprint"):
        assert shown[key] == quiet[key], key


class Sphere(Problem):
    name = "sphere"
    parameter_names = ("a", "b")
    lower = np.array([-1.0, -1.0])
    upper = np.array([1.0, 1.0])

    def evaluate(self, X):
        return np.sum(np.asarray(X) ** 2, axis=1)


def test_on_evaluate_sees_each_counted_batch():
    seen = []
    bp = BudgetedProblem(Sphere(), 12)
    bp.on_evaluate = lambda b: seen.append((b.nfev, b.best_cost))
    rng = np.random.default_rng(0)
    bp.evaluate(rng.uniform(-1, 1, (5, 2)))
    bp.evaluate(rng.uniform(-1, 1, (5, 2)))
    bp.evaluate(rng.uniform(-1, 1, (5, 2)))  # trimmed to the budget: 2 rows counted
    assert [n for n, _ in seen] == [5, 10, 12]
    assert seen[-1][1] == bp.best_cost
    bp.evaluate(np.zeros((3, 2)))  # past the budget nothing is counted, so no call
    assert len(seen) == 3


def test_bar_redraws_at_most_ten_times_a_second():
    out = Pipe()
    bar = ProgressBar(100_000, "probe", file=out)
    t0 = time.monotonic()
    b = SimpleNamespace(nfev=0, budget=100_000, best_cost=1.0)
    for k in range(1, 100_001):
        b.nfev = k
        bar(b)
    elapsed = time.monotonic() - t0
    bar.close(b)
    frames = out.getvalue().count("\r")
    assert frames <= 4 + 10 * elapsed + 2, (frames, elapsed)
    assert "100000/100000" in out.getvalue()


def test_a_broken_stream_does_not_fail_the_run(tmp_path, monkeypatch):
    class Closed(TTY):
        def write(self, s):
            raise OSError("stream closed")

    monkeypatch.setattr(sys, "stderr", Closed())
    rec = run(_tiny("progress=true"), tmp_path).record
    assert rec["status"] == "budget_spent" and rec["evaluations"] == 200
    assert harness.ProgressBar.interval == 0.1
