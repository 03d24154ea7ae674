"""Checkpoints and resume (issue 7, item 4).

Every evaluated batch is journaled (``journal.bin`` in the run folder, flushed per batch). A
run restarted with ``resume=true`` in the same folder reruns its plugin from scratch with the
same seed; batches identical bit for bit to the journaled ones get the journaled costs without
simulating, then the run goes on live. For a deterministic plugin the result is identical to an
uninterrupted run; a non-deterministic plugin is detected and reported; a record cut short by
the kill is ignored.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import benchmark.core.harness as harness
from benchmark.core.budget import BudgetedProblem
from benchmark.core.errors import ResumeError, ResumeWarning
from benchmark.core.journal import KIND_EVALUATE, EvaluationJournal
from benchmark.core.problem import OptimizerOutput, Problem
from tests.conftest import compose_config

REPO = Path(__file__).resolve().parents[2]
SMALL = ["motor.test.cycles=10", "motor.test.stop_duration=3.0"]
#: fields that must be identical between an uninterrupted and a resumed run
SAME = (
    "status",
    "message",
    "estimate",
    "searched",
    "cost",
    "cost_optimizer",
    "evaluations",
    "nit",
    "budget",
    "fingerprint",
    "rel_error",
)


class Sphere(Problem):
    name = "sphere"
    parameter_names = ("a", "b", "c")

    def __init__(self):
        self.lower, self.upper = np.full(3, -1.0), np.full(3, 2.0)
        self.simulated = 0

    def evaluate(self, X):
        self.simulated += len(X)
        return ((X - 0.3) ** 2).sum(axis=1)


def random_search(problem, *, seed, batch=10):
    rng = np.random.default_rng(seed)
    best = None
    while not problem.exhausted:
        X = problem.lower + rng.random((batch, problem.n_var)) * (problem.upper - problem.lower)
        c = problem.evaluate(X)
        best = X[np.argmin(c)]
    return OptimizerOutput(x=best, nit=1)


def unseeded_search(problem, *, seed, batch=10):
    """Not deterministic for a given seed (fresh OS entropy)."""
    return random_search(problem, seed=None, batch=batch)


def unseeded_search_plugin(problem, *, seed):
    return unseeded_search(problem, seed=seed)


# -- the journal ---------------------------------------------------------------------------------
def _journal(path, n_batches=5, n_var=3):
    j = EvaluationJournal.create(path, {"fingerprint": "abc", "n_var": n_var})
    rng = np.random.default_rng(0)
    batches = [(rng.random((k + 1, n_var)), rng.random(k + 1)) for k in range(n_batches)]
    for X, c in batches:
        j.append(KIND_EVALUATE, X, c)
    j.close()
    return batches


def test_journal_round_trip_bit_for_bit(tmp_path):
    path = tmp_path / "journal.bin"
    batches = _journal(path)
    contents = EvaluationJournal.read(path)
    assert contents.header == {"fingerprint": "abc", "n_var": 3} and contents.ignored_bytes == 0
    assert len(contents.records) == 5
    for rec, (X, c) in zip(contents.records, batches, strict=True):
        assert rec.X.tobytes() == X.tobytes() and rec.cost.tobytes() == c.tobytes()


@pytest.mark.parametrize("cut", [1, 4, 17, 40])
def test_truncated_last_record_is_ignored(tmp_path, cut):
    path = tmp_path / "journal.bin"
    _journal(path)
    full = path.read_bytes()
    path.write_bytes(full[:-cut])
    contents = EvaluationJournal.read(path)
    assert len(contents.records) == 4
    assert contents.ignored_bytes == len(full) - cut - contents.valid_end > 0


def test_corrupt_record_ends_the_journal(tmp_path):
    path = tmp_path / "journal.bin"
    _journal(path)
    data = bytearray(path.read_bytes())
    contents = EvaluationJournal.read(path)
    data[contents.records[2].offset + 30] ^= 0xFF  # inside batch 3's points
    path.write_bytes(bytes(data))
    assert len(EvaluationJournal.read(path).records) == 2


def test_journal_header_cut_short_or_foreign_file(tmp_path):
    path = tmp_path / "journal.bin"
    _journal(path)
    data = path.read_bytes()
    path.write_bytes(data[:25])
    assert EvaluationJournal.read(path) is None  # killed while writing the header: nothing to resume
    assert EvaluationJournal.read(tmp_path / "missing.bin") is None
    path.write_bytes(b"not a journal at all, some other file")
    with pytest.raises(ResumeError, match="not an imbench checkpoint journal"):
        EvaluationJournal.read(path)


# -- replay in BudgetedProblem -----------------------------------------------------------------
def _interrupted(tmp_path, plugin, budget, stop_after):
    """Run ``plugin`` with a journal until ``stop_after`` evaluations, as if killed there."""
    path = tmp_path / "journal.bin"
    bp = BudgetedProblem(Sphere(), budget, journal=EvaluationJournal.create(path, {"n_var": 3}))
    real = bp._record

    def record(X, c):
        real(X, c)
        if bp.nfev >= stop_after:
            raise KeyboardInterrupt

    bp._record = record
    with pytest.raises(KeyboardInterrupt):
        plugin(bp, seed=5)
    bp.journal.close()
    return path


def test_replay_reproduces_the_run_without_simulating(tmp_path):
    ref = BudgetedProblem(Sphere(), 200)
    random_search(ref, seed=5)

    path = _interrupted(tmp_path, random_search, 200, stop_after=120)
    contents = EvaluationJournal.read(path)
    problem = Sphere()
    bp = BudgetedProblem(
        problem, 200, journal=EvaluationJournal.reopen(path, contents), replay=contents.records
    )
    bp.verify_replay()
    assert problem.simulated == 1  # the check of the first journaled point
    random_search(bp, seed=5)
    bp.journal.close()
    assert bp.replayed_evaluations == 120 and bp.replay_mismatch is None
    assert problem.simulated == 1 + 80  # then live after the replay
    assert bp.nfev == ref.nfev and bp.best_cost == ref.best_cost
    assert bp.best_x.tobytes() == ref.best_x.tobytes()
    assert bp.history == ref.history
    # the journal now holds the whole run, as an uninterrupted one would
    assert sum(len(r.X) for r in EvaluationJournal.read(path).records) == 200


def test_non_deterministic_plugin_is_detected(tmp_path):
    path = _interrupted(tmp_path, unseeded_search, 200, stop_after=50)
    contents = EvaluationJournal.read(path)
    bp = BudgetedProblem(
        Sphere(), 200, journal=EvaluationJournal.reopen(path, contents), replay=contents.records
    )
    with pytest.warns(ResumeWarning, match="not deterministic"):
        unseeded_search(bp, seed=5)
    bp.journal.close()
    assert bp.replay_mismatch is not None and bp.replay_mismatch["batch"] == 1
    assert bp.replayed_evaluations == 0 and bp.nfev == 200
    # the stale records were cut off: the journal is this run's trajectory
    assert sum(len(r.X) for r in EvaluationJournal.read(path).records) == 200


# -- through the harness, for every plugin ------------------------------------------------------
def _cfg(*overrides):
    return compose_config([*SMALL, *overrides])


def _kill_harness_at(monkeypatch, evaluations):
    real = BudgetedProblem._record

    def record(self, X, c):
        real(self, X, c)
        if self.nfev >= evaluations and self.journal is not None:
            raise KeyboardInterrupt("simulated kill")

    monkeypatch.setattr(BudgetedProblem, "_record", record)


def _same(a: dict, b: dict, adir: Path, bdir: Path):
    for k in SAME:
        assert a[k] == b[k], (k, a[k], b[k])
    pd.testing.assert_frame_equal(
        pd.read_csv(adir / "history.csv"), pd.read_csv(bdir / "history.csv"), check_exact=True
    )


PLUGINS = ["scipy_de", "genesis", "deap", "pygad", "cmaes", "nlopt_crs", "least_squares"]


@pytest.mark.parametrize("optimizer", PLUGINS)
def test_resumed_run_equals_uninterrupted_run(tmp_path, monkeypatch, optimizer):
    import importlib

    from omegaconf import OmegaConf

    target = OmegaConf.load(REPO / "conf" / "optimizer" / f"{optimizer}.yaml").plugin._target_
    try:
        importlib.import_module(target.rsplit(".", 1)[0])
    except ImportError as exc:
        pytest.skip(f"{optimizer}: {exc}")
    budget = 240
    overrides = [f"optimizer={optimizer}", f"budget={budget}", "seed=3"]
    ref = harness.run(_cfg(*overrides), tmp_path / "ref").record

    run_dir = tmp_path / "run"
    kill_at = min(100, ref["evaluations_optimizer"] // 2)  # least squares converges early
    with monkeypatch.context() as m:
        _kill_harness_at(m, kill_at)
        with pytest.raises(KeyboardInterrupt):
            harness.run(_cfg(*overrides), run_dir)
    assert (run_dir / "journal.bin").is_file() and not (run_dir / "result.json").exists()
    # as if killed in the middle of writing the next record
    with open(run_dir / "journal.bin", "ab") as fh:
        fh.write(b"EVAL\x00\x00\x00\x00\x10")

    with pytest.warns(ResumeWarning, match="ignored 9 bytes at the end of the checkpoint"):
        rec = harness.run(_cfg(*overrides, "resume=true"), run_dir).record
    _same(ref, rec, tmp_path / "ref", run_dir)
    info = rec["resume"]
    assert info["replayed_evaluations"] >= kill_at > 0 and info["mismatch"] is None
    assert info["ignored_bytes"] == 9
    assert not (run_dir / "journal.bin").exists()  # done: the checkpoint is removed


def test_resume_reports_a_non_deterministic_plugin(tmp_path, monkeypatch):
    overrides = ["optimizer=scipy_de", "budget=200"]
    cfg = _cfg(*overrides)

    def use_unseeded(c):
        from omegaconf import open_dict

        with open_dict(c):
            c.optimizer.plugin = {"_target_": "tests.core.test_resume.unseeded_search_plugin", "_partial_": True}
        return c

    with monkeypatch.context() as m:
        _kill_harness_at(m, 60)
        with pytest.raises(KeyboardInterrupt):
            harness.run(use_unseeded(cfg), tmp_path)
    with pytest.warns(ResumeWarning, match="not deterministic"):
        rec = harness.run(use_unseeded(_cfg(*overrides, "resume=true")), tmp_path).record
    assert rec["resume"]["mismatch"]["batch"] == 1
    assert any("not deterministic" in w for w in rec["warnings"])
    assert rec["status"] == "budget_spent" and rec["evaluations"] == 200


def test_resume_refuses_another_configuration(tmp_path, monkeypatch):
    with monkeypatch.context() as m:
        _kill_harness_at(m, 50)
        with pytest.raises(KeyboardInterrupt):
            harness.run(_cfg("optimizer=scipy_de", "budget=200", "seed=1"), tmp_path)
    with pytest.raises(ResumeError, match=r"different run configuration.*seed: 1 then, 2 now"):
        harness.run(_cfg("optimizer=scipy_de", "budget=200", "seed=2", "resume=true"), tmp_path)


def test_resume_detects_changed_costs(tmp_path, monkeypatch):
    """Same configuration, but the journal's costs are not what the code computes now."""
    overrides = ["optimizer=scipy_de", "budget=200"]
    with monkeypatch.context() as m:
        _kill_harness_at(m, 100)
        with pytest.raises(KeyboardInterrupt):
            harness.run(_cfg(*overrides), tmp_path)
    path = tmp_path / "journal.bin"
    contents = EvaluationJournal.read(path)
    j = EvaluationJournal.create(path, contents.header)
    for k, r in enumerate(contents.records):
        j.append(r.kind, r.X, r.cost * (1.001 if k == 0 else 1.0))
    j.close()
    with pytest.raises(ResumeError, match="the data or the code changed"):
        harness.run(_cfg(*overrides, "resume=true"), tmp_path)


def test_resume_without_checkpoint_or_of_a_finished_run(tmp_path):
    overrides = ["optimizer=scipy_de", "budget=60"]
    with pytest.warns(ResumeWarning, match="no checkpoint"):
        first = harness.run(_cfg(*overrides, "resume=true"), tmp_path).record
    stamp = (tmp_path / "result.json").stat().st_mtime_ns
    again = harness.run(_cfg(*overrides, "resume=true"), tmp_path).record  # finished: not run again
    assert (tmp_path / "result.json").stat().st_mtime_ns == stamp
    assert again == json.loads((tmp_path / "result.json").read_text())
    assert again["cost"] == first["cost"]


# -- a real kill ---------------------------------------------------------------------------------
def test_sigkill_then_resume_gives_the_uninterrupted_result(tmp_path):
    args = ["optimizer=scipy_de", "budget=6000", "seed=4"]
    env = {k: v for k, v in os.environ.items() if k not in ("IMBENCH_DEBUG", "HYDRA_FULL_ERROR")}

    def start(rundir, *extra):
        return subprocess.Popen(
            [sys.executable, "-m", "benchmark", *args, f"hydra.run.dir={rundir}", *extra],
            cwd=REPO,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )

    ref_dir, run_dir = tmp_path / "ref", tmp_path / "run"
    ref = start(ref_dir)
    victim = start(run_dir)
    journal = run_dir / "journal.bin"
    killed_at = 0
    try:
        deadline = time.monotonic() + 240
        while time.monotonic() < deadline and victim.poll() is None:
            if journal.exists():
                contents = EvaluationJournal.read(journal)
                killed_at = sum(len(r.X) for r in contents.records) if contents else 0
                if killed_at >= 1500:
                    os.kill(victim.pid, signal.SIGKILL)
                    break
            time.sleep(0.02)
        victim.communicate(timeout=60)
        assert victim.returncode == -signal.SIGKILL, "the run ended before it could be killed"
        assert not (run_dir / "result.json").exists()
        # the kill may fall between two records: cut the last one short as a kill mid-write would
        data = journal.read_bytes()
        journal.write_bytes(data[:-5])

        resumed = start(run_dir, "resume=true")
        out, err = resumed.communicate(timeout=300)
        assert resumed.returncode == 0, err
        ref_out, ref_err = ref.communicate(timeout=300)
        assert ref.returncode == 0, ref_err
    finally:
        for p in (ref, victim):
            if p.poll() is None:
                p.kill()
                p.communicate()
    a = json.loads((ref_dir / "result.json").read_text())
    b = json.loads((run_dir / "result.json").read_text())
    _same(a, b, ref_dir, run_dir)
    assert a["status"] == "budget_spent" and b["evaluations"] == 6000
    assert b["resume"]["replayed_evaluations"] >= killed_at - 75 > 0  # less the record cut short
    assert b["resume"]["ignored_bytes"] > 0 and b["resume"]["mismatch"] is None
    assert not (run_dir / "journal.bin").exists()
