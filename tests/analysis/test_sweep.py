"""Sweeps through Hydra launchers (README, "Sweeps and clusters").

Each test runs ``python -m benchmark -m ...`` in a subprocess, as a user would:

* the default launcher (joblib, ``n_jobs`` 2) runs the jobs in worker processes with one numba
  thread each, a plugin that raises is recorded as a failed run and the sweep goes on, and every
  run gives bit for bit the result of the same run made alone in this process;
* ``hydra/launcher=submitit_local`` (the local mode of the path to SLURM) runs a 2-job sweep;
* ``hydra/launcher=imbench_slurm`` turns the keys a user sets into the sbatch script (checked with a
  stand-in ``sbatch`` that records the script, since CI has no SLURM).

The failing plugin is test-only: a module and an optimizer YAML written into a temporary folder,
added to Hydra's config search path with ``hydra.searchpath=[file://...]`` and to PYTHONPATH.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml
from hydra import compose, initialize_config_dir

from benchmark.core.harness import run

REPO = Path(__file__).resolve().parents[2]
CONF = str(REPO / "conf")
BUDGET = 300

PROBE_MODULE = '''
"""Test-only optimiser plugin: evaluates a few random points, then raises."""
import os

import numba
import numpy as np


def minimize(problem, *, seed, evaluations=20):
    rng = np.random.default_rng(seed)
    X = problem.lower + rng.random((evaluations, problem.n_var)) * (problem.upper - problem.lower)
    problem.evaluate(X)
    raise RuntimeError(f"deliberate failure (numba threads {numba.get_num_threads()}, "
                       f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS')})")
'''

PROBE_YAML = """\
name: probe_fail
default_budget: 100
plugin:
  _target_: imbench_sweep_probe.minimize
  _partial_: true
  evaluations: 20
"""


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    """(config dir for hydra.searchpath, environment with the probe importable)."""
    root = tmp_path_factory.mktemp("probe")
    (root / "imbench_sweep_probe.py").write_text(PROBE_MODULE)
    (root / "conf" / "optimizer").mkdir(parents=True)
    (root / "conf" / "optimizer" / "probe_fail.yaml").write_text(PROBE_YAML)
    env = dict(os.environ)
    env.pop("NUMBA_NUM_THREADS", None)  # test the launcher's own thread limit
    env["PYTHONPATH"] = os.pathsep.join([str(root), str(REPO), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return root / "conf", env


def multirun(args, env, timeout=240) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        [sys.executable, "-m", "benchmark", "-m", *args],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc


def results(sweep_dir: Path) -> dict[tuple[str, int], dict]:
    out = {}
    for f in sweep_dir.glob("*/result.json"):
        rec = json.loads(f.read_text())
        rec["_dir"] = f.parent
        out[(rec["optimizer"], rec["seed"])] = rec
    return out


def alone(overrides) -> dict:
    """The same run made in this process (numba's default thread count), as a single run would."""
    import tempfile

    with initialize_config_dir(config_dir=CONF, version_base="1.3"):
        cfg = compose("config", overrides=list(overrides))
    with tempfile.TemporaryDirectory() as d:
        rec = run(cfg, Path(d)).record
        rec["_history"] = pd.read_csv(Path(d) / "history.csv")
    return rec


def test_joblib_sweep_parallel_failure_recorded_and_bit_identical(probe, tmp_path):
    conf_dir, env = probe
    sweep = tmp_path / "sweep"
    multirun(
        [
            f"hydra.searchpath=[file://{conf_dir}]",
            "optimizer=deap,probe_fail",
            "seed=0,1",
            f"budget={BUDGET}",
            f"hydra.sweep.dir={sweep}",
        ],
        env,
    )
    runs = results(sweep)
    assert sorted(runs) == [("deap", 0), ("deap", 1), ("probe_fail", 0), ("probe_fail", 1)]

    # the default multirun launcher is joblib with no more jobs than the 2 cores
    hydra_cfg = yaml.safe_load((runs[("deap", 0)]["_dir"] / ".hydra" / "hydra.yaml").read_text())["hydra"]
    assert hydra_cfg["launcher"]["_target_"].endswith("JoblibLauncher")
    assert hydra_cfg["launcher"]["n_jobs"] == 2

    # the failing plugin: recorded as failed with its error, after its 20 counted evaluations
    for seed in (0, 1):
        rec = runs[("probe_fail", seed)]
        assert rec["status"] == "failed"
        assert "RuntimeError: deliberate failure" in rec["message"]
        assert rec["evaluations"] == 20
        assert "RuntimeError" in rec["traceback"]
        # joblib's worker got NUMBA_NUM_THREADS = 2 cores // 2 jobs = 1: no oversubscription
        assert "numba threads 1," in rec["message"] and "NUMBA_NUM_THREADS=1" in rec["message"]

    # the sweep went on: the other runs finished normally, exactly at the budget
    for seed in (0, 1):
        rec = runs[("deap", seed)]
        assert rec["status"] == "budget_spent", rec["message"]
        assert rec["evaluations"] == BUDGET

    # same seed in a worker (one numba thread, reused: 4 jobs on 2 workers) == the run alone here
    for seed in (0, 1):
        ref = alone(["optimizer=deap", f"seed={seed}", f"budget={BUDGET}"])
        rec = runs[("deap", seed)]
        assert rec["estimate"] == ref["estimate"]
        assert rec["cost"] == ref["cost"]
        hist = pd.read_csv(rec["_dir"] / "history.csv")
        pd.testing.assert_frame_equal(hist, ref["_history"], check_exact=True)


def test_submitit_local_sweep(probe, tmp_path):
    """The local mode of Hydra's submitit launcher: each job is pickled and run in its own
    process by submitit, as it would be on a SLURM node."""
    _, env = probe
    sweep = tmp_path / "sweep"
    multirun(
        [
            "hydra/launcher=submitit_local",
            "hydra.launcher.timeout_min=5",
            "optimizer=scipy_de",
            "seed=0,1",
            "budget=200",
            f"hydra.sweep.dir={sweep}",
        ],
        env,
    )
    runs = results(sweep)
    assert sorted(runs) == [("scipy_de", 0), ("scipy_de", 1)]
    assert (sweep / ".submitit").is_dir()
    for rec in runs.values():
        assert rec["status"] == "budget_spent"
        assert rec["evaluations"] == 200
    ref = alone(["optimizer=scipy_de", "seed=1", "budget=200"])
    assert runs[("scipy_de", 1)]["estimate"] == ref["estimate"]
    assert runs[("scipy_de", 1)]["cost"] == ref["cost"]


def test_slurm_launcher_writes_the_sbatch_script(probe, tmp_path):
    """hydra/launcher=imbench_slurm on a machine without SLURM: a stand-in ``sbatch`` records the
    script submitit hands it and refuses the job, so the keys a user sets can be checked."""
    _, env = probe
    fakebin = tmp_path / "bin"
    fakebin.mkdir()
    (fakebin / "sbatch").write_text(
        '#!/bin/sh\ncp "$1" "$FAKE_SBATCH_OUT"\necho "sbatch: refused (test)" >&2\nexit 1\n'
    )
    (fakebin / "srun").write_text("#!/bin/sh\nexit 1\n")  # submitit only checks that srun exists
    for f in fakebin.iterdir():
        f.chmod(0o755)
    script = tmp_path / "submitted.sh"
    env = dict(env, PATH=f"{fakebin}{os.pathsep}{env['PATH']}", FAKE_SBATCH_OUT=str(script))
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "benchmark",
            "-m",
            "hydra/launcher=imbench_slurm",
            "hydra.launcher.partition=short",
            "hydra.launcher.timeout_min=30",
            "optimizer=scipy_de",
            "seed=0,1,2",
            f"hydra.sweep.dir={tmp_path / 'sweep'}",
        ],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode != 0 and "sbatch: refused (test)" in proc.stderr
    text = script.read_text()
    for line in (
        "#SBATCH --partition=short",
        "#SBATCH --time=30",
        "#SBATCH --cpus-per-task=1",
        "#SBATCH --mem=2GB",
        "#SBATCH --array=0-2%3",
        "#SBATCH --job-name=imbench",
        "export NUMBA_NUM_THREADS=1",
    ):
        assert line in text, text
