"""Failures (issue 7, items 2, 3 and 5).

* Configuration errors are caught before any work starts (no data read, nothing simulated,
  nothing written), name the key, list the valid choices, and exit with status 2.
* A plugin that raises, hangs past ``time_limit_s`` (also in a pure-Python loop that never
  evaluates, also when it swallows exceptions), keeps evaluating past the limit where no
  signal can reach it, or returns NaN, is recorded as a failed or timed-out run with its
  reason, and a sweep goes on.
* ``result.json`` and the summaries are written atomically: a crash during the write leaves
  the previous file intact and no temporary file behind.

The misbehaving plugins are the functions below; the sweep test reaches them through optimizer
YAMLs written into a temporary config folder added with ``hydra.searchpath``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from omegaconf import open_dict

import benchmark.core.harness as harness
from benchmark.core.budget import BudgetedProblem, run_plugin
from benchmark.core.errors import ConfigError
from benchmark.core.io import write_text_atomic
from benchmark.core.problem import OptimizerOutput, Status
from tests.conftest import compose_config

REPO = Path(__file__).resolve().parents[2]
SMALL = ["motor.test.cycles=10", "motor.test.stop_duration=3.0"]  # a 0.2 s start-up: fast set-up


# -- misbehaving plugins -------------------------------------------------------------------------
def _some_points(problem, n, seed):
    rng = np.random.default_rng(seed)
    return problem.lower + rng.random((n, problem.n_var)) * (problem.upper - problem.lower)


def plugin_raises(problem, *, seed):
    problem.evaluate(_some_points(problem, 7, seed))
    raise RuntimeError("deliberate failure in the plugin")


def plugin_hangs(problem, *, seed):
    """Evaluates once, then spins in pure Python without evaluating again."""
    problem.evaluate(_some_points(problem, 5, seed))
    x = 0
    while True:
        x += 1


def plugin_hangs_and_swallows(problem, *, seed):
    """Sleeps in a loop that swallows every ``Exception``."""
    problem.evaluate(_some_points(problem, 5, seed))
    while True:
        try:
            time.sleep(0.05)
        except Exception:  # noqa: BLE001 - the point of this plugin
            pass


def plugin_keeps_evaluating(problem, *, seed):
    """Evaluates forever, one point at a time (the budget is set huge)."""
    k = 0
    while True:
        problem.evaluate(_some_points(problem, 1, seed + k))
        k += 1


def plugin_returns_nan_x(problem, *, seed):
    problem.evaluate(_some_points(problem, 6, seed))
    return OptimizerOutput(x=np.full(problem.n_var, np.nan), nit=1)


def plugin_returns_nan(problem, *, seed):
    problem.evaluate(_some_points(problem, 6, seed))
    return float("nan")


def plugin_evaluates_nan(problem, *, seed):
    problem.evaluate(np.full((4, problem.n_var), np.nan))
    return OptimizerOutput(x=None, nit=1)


def _with_plugin(cfg, target: str, name: str):
    with open_dict(cfg):
        cfg.optimizer = {
            "name": name,
            "default_budget": 100,
            "plugin": {"_target_": f"tests.core.test_failures.{target}", "_partial_": True},
        }
    return cfg


# -- 2. configuration errors -------------------------------------------------------------------
CONFIG_ERRORS = [
    (["bounds={Rs:[5,1]}"], "bounds.Rs: low 5.0 >= high 1.0"),
    (["bounds={Rs:[1,1]}"], "bounds.Rs: low 1.0 >= high 1.0"),
    (["bounds={Rs:[-1,5]}"], "bounds.Rs: Rs must be positive"),
    (["bounds={fc:[-0.1,0.2]}"], "bounds.fc: fc cannot be negative"),
    (["bounds={J:[0,1]}"], "bounds.J: J must be positive"),
    (
        ["bounds={Rx:[1,5]}"],
        "bounds: unknown parameter(s) ['Rx']; valid: ['Rs', 'Ls', 'Le', 'Rr', 'J', 'fv', 'fc']",
    ),
    (["bounds={Rs:[1,2,3]}"], "bounds.Rs: expected [low, high]"),
    (["bounds={Rs:[a,2]}"], "bounds.Rs: expected two numbers"),
    (["bounds={Rs:[1,inf]}"], "bounds.Rs: bounds must be finite"),
    (["budget=0"], "budget: must be a positive whole number"),
    (["budget=-5"], "budget: must be a positive whole number"),
    (["optimizer.default_budget=0"], "optimizer.default_budget: must be a positive"),
    (["seed=-1"], "seed: must be a non-negative integer"),
    (["time_limit_s=0"], "time_limit_s: must be a positive number"),
    (["resume=true", "checkpoint=false"], "resume: needs checkpoint=true"),
    (["data.max_file_mib=-1"], "data.max_file_mib: must be a positive"),
    (["problem.cost.exponent=3"], "problem.cost.exponent: must be 1 (eq. 15) or 2 (eq. 14)"),
    (["+problem.cost.weights.torque=1"], "problem.cost.weights.torque: unknown channel; valid: ['i_alpha'"),
    (["problem.friction_case=3"], "problem.friction_case: must be 1"),
    (["problem.held_friction={fv: 0}"], "problem.held_friction: expected {fv: N m s/rad, fc: N m}"),
    (["problem.held_friction={fv: 0, fc: -1}"], "problem.held_friction.fc: must be a non-negative number"),
    (
        ["optimizer=scipy_de", "+optimizer.plugin.popsiz=3"],
        "optimizer.plugin.popsiz: not an option of plugins.scipy_de.minimize; valid: ['strategy', 'popsize'",
    ),
    (
        ["optimizer.plugin._target_=plugins.no_such_module.minimize"],
        "optimizer.plugin._target_: cannot import",
    ),
]


@pytest.mark.parametrize("overrides, expected", CONFIG_ERRORS, ids=[" ".join(c[0]) for c in CONFIG_ERRORS])
def test_config_errors_before_any_work(tmp_path, monkeypatch, overrides, expected):
    """The problem's set-up (data loading, synthetic generation) is never reached."""
    def no_setup(cfg):
        raise AssertionError("set-up reached: the configuration error was not caught first")

    monkeypatch.setattr(harness, "build_problem", no_setup)
    cfg = compose_config(["data.path=/no/such/folder", *overrides])
    with pytest.raises(ConfigError) as err:
        harness.run(cfg, tmp_path / "run")
    assert expected in str(err.value)
    assert not (tmp_path / "run").exists()


def test_unknown_bounds_key_for_a_parameter_fixed_by_the_stop_record(tmp_path):
    """fv is a parameter, but with a stop record it is not searched: said so."""
    cfg = compose_config([*SMALL, "bounds={fv:[0,1]}"])
    with pytest.raises(
        ConfigError, match=r"bounds: unknown parameter\(s\) \['fv'\]; searched here: .*not searched"
    ):
        harness.run(cfg, tmp_path)


def test_cli_config_errors_list_the_valid_choices(tmp_path):
    cases = {
        "optimizer=no_such_plugin": [
            "error: optimizer=no_such_plugin: no such option; options: [",
            "'scipy_de'",
            "'genesis'",
        ],
        "problem=no_such_problem": [
            "error: problem=no_such_problem: no such option; options: ['admittance', 'timedomain']",
        ],
        "bounds={Rs:[9,2]}": ["error: bounds.Rs: low 9.0 >= high 2.0 (did you swap low and high?)"],
        "bounds={Rz:[1,2]}": [
            "error: bounds: unknown parameter(s) ['Rz']; valid: ['Rs', 'Ls', 'Le', 'Rr', 'J'"
        ],
        "seed=-3": ["error: seed: must be a non-negative integer, got -3"],
    }
    env = {k: v for k, v in os.environ.items() if k not in ("IMBENCH_DEBUG", "HYDRA_FULL_ERROR")}
    procs = {
        o: subprocess.Popen(
            [sys.executable, "-m", "benchmark", o, f"hydra.run.dir={tmp_path / str(k)}"],
            cwd=REPO,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for k, o in enumerate(cases)
    }
    try:
        for o, expected in cases.items():
            out, err = procs[o].communicate(timeout=120)
            assert procs[o].returncode == 2, (o, out, err)
            assert "Traceback" not in out + err, (o, err)
            for s in expected:
                assert s in err, (o, s, err)
    finally:
        for p in procs.values():
            if p.poll() is None:
                p.kill()
                p.communicate()
    assert not any((tmp_path / str(k) / "result.json").exists() for k in range(len(cases)))


# -- 3. failing plugins ----------------------------------------------------------------------------
def _run(tmp_path, target, *overrides):
    cfg = _with_plugin(compose_config([*SMALL, *overrides]), target, target)
    outcome = harness.run(cfg, tmp_path)
    rec = json.loads((tmp_path / "result.json").read_text())
    assert rec["status"] == outcome.record["status"]
    assert (tmp_path / "history.csv").is_file() and not (tmp_path / "journal.bin").exists()
    return rec


def test_plugin_that_raises_is_a_failed_run(tmp_path):
    rec = _run(tmp_path, "plugin_raises")
    assert rec["status"] == "failed"
    assert rec["message"] == "RuntimeError: deliberate failure in the plugin"
    assert "Traceback" in rec["traceback"] and "plugin_raises" in rec["traceback"]
    assert rec["evaluations"] == 7 and rec["cost"] is not None  # what it evaluated is kept


@pytest.mark.parametrize("target", ["plugin_hangs", "plugin_hangs_and_swallows"])
def test_plugin_that_hangs_is_stopped_at_the_time_limit(tmp_path, target):
    t0 = time.monotonic()
    rec = _run(tmp_path, target, "time_limit_s=0.5")
    assert time.monotonic() - t0 < 20
    assert rec["status"] == "timeout"
    assert rec["message"].startswith("time limit of 0.5 s exceeded after 5 evaluations (best cost so far")
    assert rec["evaluations"] == 5 and rec["cost"] is not None and rec["time_limit_s"] == 0.5
    assert 0.5 <= rec["wall_time_optimizer_s"] < 5


def test_time_limit_without_signals_is_enforced_by_evaluate(tmp_path):
    """Off the main thread SIGALRM cannot be used: the check in evaluate stops the plugin."""
    box = {}

    def target():
        try:
            box["rec"] = _run(tmp_path, "plugin_keeps_evaluating", "time_limit_s=0.5", "budget=100000000")
        except BaseException as exc:  # noqa: BLE001 - reported below
            box["exc"] = exc

    th = threading.Thread(target=target)
    th.start()
    th.join(60)
    assert not th.is_alive() and "exc" not in box, box.get("exc")
    rec = box["rec"]
    assert rec["status"] == "timeout" and "time limit of 0.5 s exceeded after" in rec["message"]
    assert 0 < rec["evaluations"] < 100000000


@pytest.mark.parametrize(
    "target, expected",
    [
        ("plugin_returns_nan_x", "plugin returned a non-finite x"),
        ("plugin_returns_nan", "plugin returned nan (float), expected an OptimizerOutput"),
        ("plugin_evaluates_nan", "no finite cost was found"),
    ],
)
def test_plugin_that_returns_nan_is_a_failed_run(tmp_path, target, expected):
    rec = _run(tmp_path, target)
    assert rec["status"] == "failed"
    assert expected in rec["message"]


class _Toy:
    name, parameter_names, n_var = "toy", ("a",), 1
    lower, upper = np.zeros(1), np.ones(1)
    has_residuals = False

    def __init__(self, sleep=0.0):
        self.sleep, self.simulated = sleep, 0

    def evaluate(self, X):
        time.sleep(self.sleep)
        self.simulated += len(X)
        return X[:, 0]


def test_alarm_during_a_simulation_counts_the_batch_first():
    """SIGALRM arriving while a batch is simulated is held until the batch is counted: every
    simulated point is in the count, the history and the best point."""
    toy = _Toy(sleep=0.2)
    bp = BudgetedProblem(toy, 10**6)
    res = run_plugin(plugin_keeps_evaluating, bp, seed=0, name="toy", time_limit_s=0.5)
    assert res.status == Status.TIMEOUT
    assert res.nfev == toy.simulated == 3  # the alarm came during the third simulation
    assert bp.history.evaluations[-1] <= 3


def test_run_plugin_keeps_propagating_by_default():
    """Direct callers of run_plugin (experiments, tests) still see the plugin's exception."""
    with pytest.raises(RuntimeError, match="deliberate"):
        run_plugin(plugin_raises, BudgetedProblem(_Toy(), 10), seed=0, name="x")
    res = run_plugin(plugin_raises, BudgetedProblem(_Toy(), 10), seed=0, name="x", record_failures=True)
    assert res.status == Status.FAILED and res.nfev == 7 and "deliberate" in res.message


SWEEP_PLUGINS = {
    "fail_raise": "plugin_raises",
    "fail_hang": "plugin_hangs",
    "fail_nan": "plugin_returns_nan_x",
}


def test_sweep_goes_on_past_failing_plugins(tmp_path):
    conf = tmp_path / "conf" / "optimizer"
    conf.mkdir(parents=True)
    for name, target in SWEEP_PLUGINS.items():
        (conf / f"{name}.yaml").write_text(
            f"name: {name}\ndefault_budget: 100\nplugin:\n  _target_: tests.core.test_failures.{target}\n"
            "  _partial_: true\n"
        )
    env = {k: v for k, v in os.environ.items() if k not in ("IMBENCH_DEBUG", "HYDRA_FULL_ERROR")}
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    sweep = tmp_path / "sweep"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmark",
            "-m",
            f"hydra.searchpath=[file://{tmp_path / 'conf'}]",
            "optimizer=fail_raise,fail_hang,fail_nan,scipy_de",
            "budget=40",
            "time_limit_s=1",
            *SMALL,
            f"hydra.sweep.dir={sweep}",
        ],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    runs = {}
    for f in sweep.glob("*/result.json"):
        rec = json.loads(f.read_text())
        runs[rec["optimizer"]] = rec
    assert sorted(runs) == sorted([*SWEEP_PLUGINS, "scipy_de"])
    assert runs["fail_raise"]["status"] == "failed" and "deliberate failure" in runs["fail_raise"]["message"]
    assert runs["fail_hang"]["status"] == "timeout" and "time limit of 1 s" in runs["fail_hang"]["message"]
    assert runs["fail_nan"]["status"] == "failed" and "non-finite x" in runs["fail_nan"]["message"]
    assert runs["scipy_de"]["status"] == "budget_spent" and runs["scipy_de"]["evaluations"] == 40


# -- 5. atomic writes ------------------------------------------------------------------------------
def _temp_files(folder: Path) -> list[str]:
    return [p.name for p in folder.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("where", ["os.replace", "os.fsync", "write"])
def test_write_text_atomic_crash_keeps_previous_file(tmp_path, monkeypatch, where):
    path = tmp_path / "result.json"
    write_text_atomic(path, '{"old": 1}\n')

    def crash(*args, **kwargs):
        raise OSError("simulated crash")

    if where == "write":
        real_fdopen = os.fdopen

        class HalfWriter:
            def __init__(self, fh):
                self.fh = fh

            def __enter__(self):
                return self

            def __exit__(self, *exc):
                self.fh.close()

            def write(self, text):
                self.fh.write(text[: len(text) // 2])
                self.fh.flush()
                raise OSError("simulated crash mid-write")

        monkeypatch.setattr(os, "fdopen", lambda *a, **kw: HalfWriter(real_fdopen(*a, **kw)))
    else:
        monkeypatch.setattr(where, crash)
    with pytest.raises(OSError, match="simulated crash"):
        write_text_atomic(path, '{"new": 2, "long": "' + "x" * 10000 + '"}\n')
    monkeypatch.undo()
    assert path.read_text() == '{"old": 1}\n'
    assert _temp_files(tmp_path) == []


def test_harness_crash_while_writing_result_keeps_previous_result(tmp_path, monkeypatch):
    """A second run into the same folder crashes while serialising / renaming result.json:
    the first run's result.json stays whole, no temporary file is left."""
    cfg = compose_config([*SMALL, "optimizer=scipy_de", "budget=30"])
    harness.run(cfg, tmp_path)
    before = (tmp_path / "result.json").read_text()
    json.loads(before)

    real_dumps = json.dumps

    def dumps_then_crash(obj, *a, **kw):
        text = real_dumps(obj, *a, **kw)
        if isinstance(obj, dict) and "fingerprint" in obj:
            raise KeyboardInterrupt("simulated crash during serialisation")
        return text

    monkeypatch.setattr(harness.json, "dumps", dumps_then_crash)
    with pytest.raises(KeyboardInterrupt):
        harness.run(cfg, tmp_path)
    monkeypatch.undo()

    real_replace = os.replace

    def replace_crash(src, dst):
        if str(dst).endswith("result.json"):
            raise KeyboardInterrupt("simulated crash at the rename")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace_crash)
    with pytest.raises(KeyboardInterrupt):
        harness.run(cfg, tmp_path)
    monkeypatch.undo()
    assert (tmp_path / "result.json").read_text() == before
    assert _temp_files(tmp_path) == []


def test_single_failed_run_exits_3_with_its_result_written(tmp_path):
    """A single run whose plugin fails is recorded (result.json, status failed) and the command
    exits 3, so a script can tell it from a finished run (0) and a user error (2)."""
    conf = tmp_path / "conf" / "optimizer"
    conf.mkdir(parents=True)
    (conf / "fail_raise.yaml").write_text(
        "name: fail_raise\ndefault_budget: 100\nplugin:\n  _target_: tests.core.test_failures.plugin_raises\n"
        "  _partial_: true\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("IMBENCH_DEBUG", "HYDRA_FULL_ERROR")}
    env["PYTHONPATH"] = os.pathsep.join([str(REPO), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    run_dir = tmp_path / "run"
    proc = subprocess.run(
        [sys.executable, "-m", "benchmark", f"hydra.searchpath=[file://{tmp_path / 'conf'}]", "optimizer=fail_raise",
         "budget=40", *SMALL, f"hydra.run.dir={run_dir}"],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 3, proc.stdout[-2000:] + proc.stderr[-2000:]
    rec = json.loads((run_dir / "result.json").read_text())
    assert rec["status"] == "failed" and "deliberate" in rec["message"]
    assert "Traceback" not in proc.stderr
