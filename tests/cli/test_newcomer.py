"""What a newcomer trips over, each fixed and held here: help texts, a misspelt key, the
wrong problem for a data folder, what the generators and a failed diagnosis leave behind,
file modes, and one line per run in a sweep."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def _run(*args, cwd=REPO, timeout=600):
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout)


def test_help_says_what_the_project_does():
    out = _run("benchmark", "--help")
    assert out.returncode == 0
    assert "imbench: identify the parameters of an induction-motor model" in out.stdout
    assert "optimizer  cmaes" in out.stdout and "python -m benchmark.diagnose" in out.stdout
    rep = _run("benchmark.report", "--help")
    assert rep.returncode == 0 and rep.stdout.startswith("usage: python -m benchmark.report DIR")


def test_a_misspelt_key_is_refused_with_the_right_one():
    out = _run("benchmark", "+seeed=1")
    assert out.returncode == 2
    assert "seeed: unknown key (did you mean seed?)" in out.stderr


def test_effect_size_override_and_a_clean_data_folder(tmp_path):
    folder = tmp_path / "sat"
    out = _run("synthetic", "effects=[main_saturation]", "effect_size={main_saturation: 0.3}", f"out={folder}")
    assert out.returncode == 0, out.stderr
    assert sorted(p.name for p in folder.iterdir()) == ["meta.yaml", "startup.csv", "stop.csv", "truth.yaml"]
    truth = (folder / "truth.yaml").read_text()
    assert "size: 0.3" in truth
    # a start-up folder given to the admittance problem: the message names the right problem
    wrong = _run("benchmark", "problem=admittance", f"data.path={folder}", "figures=false",
                 f"hydra.run.dir={tmp_path / 'run'}")
    assert wrong.returncode == 2
    assert "holds kind: startup, which problem=admittance does not read; use problem=timedomain" in wrong.stderr


def test_a_failed_diagnosis_leaves_no_folder(tmp_path):
    out = _run("benchmark.diagnose", f"data.path={tmp_path / 'missing'}", f"hydra.run.dir={tmp_path / 'diag'}")
    assert out.returncode == 2
    assert not (tmp_path / "diag").exists()


def test_sweep_prints_one_line_per_run_and_results_are_readable(tmp_path):
    out = _run("benchmark", "-m", "optimizer=scipy_de", "seed=0,1", "budget=60", "figures=false",
               "progress=false", f"hydra.sweep.dir={tmp_path / 'sweep'}")
    assert out.returncode == 0, out.stderr
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("timedomain/scipy_de seed ")]
    assert len(lines) == 2, out.stdout
    assert "| parameter |" not in out.stdout and "Rs" not in out.stdout  # no full tables
    results = sorted((tmp_path / "sweep").rglob("result.json"))
    assert len(results) == 2
    for f in [*results, *(tmp_path / "sweep").rglob("history.csv")]:
        mode = stat.S_IMODE(f.stat().st_mode)
        assert mode & stat.S_IRGRP and mode & stat.S_IROTH, oct(mode)  # 0644 under the usual umask
    assert json.loads(results[0].read_text())["evaluations"] >= 60
