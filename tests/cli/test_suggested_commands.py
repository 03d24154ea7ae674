"""The fit's verdict tells an optimiser that stopped short from a model that misses the data
(:mod:`benchmark.core.review`, :func:`benchmark.core.quality.misses_data_warning`), and the
command it suggests is complete: copied from the warning and run as it stands (the diagnosis
with a few overrides appended that keep it cheap), it runs.

* The paper's exact synthetic record and DEAP stopped after 600 evaluations: the misfit is the
  optimiser's (a polish from its result, and the true parameters, cost far less); the warning
  says "stopped short" and suggests the same run with a polish, which then converges at the noise
  level.
* An independent-plant start of the paper motor with a double cage the model lacks: a polish
  lowers nothing, the warning says "the model misses the data" and suggests the diagnosis of
  that folder, which runs.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

from synthetic.independent import make_dataset, make_spec, write_dataset

REPO = Path(__file__).resolve().parents[2]
FAST = ["figures=false", "checkpoint=false", "progress=false"]


def _run(argv, cwd, timeout=600):
    env = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg")
    return subprocess.run([sys.executable if a == "python" else a for a in argv], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


def _suggested(warning: str) -> list[list[str]]:
    """The commands a warning suggests (between backticks), split as a shell would."""
    return [shlex.split(c) for c in re.findall(r"`([^`]+)`", warning)]


def _warnings(outdir: Path) -> list[str]:
    return json.loads((outdir / "result.json").read_text())["warnings"]


def test_a_ga_that_stopped_short_is_called_that_and_its_command_runs(tmp_path):
    ga = ["python", "-m", "benchmark", "optimizer=deap", "budget=600", *FAST]
    out = _run(ga + [f"hydra.run.dir={tmp_path / 'ga'}"], tmp_path)
    assert out.returncode == 0, out.stderr
    w = _warnings(tmp_path / "ga")
    short = [s for s in w if s.startswith("the optimiser stopped short")]
    assert len(short) == 1 and not any(s.startswith("the model misses the data") for s in w), w
    assert "the polished fit is at the noise level" in short[0] and "cost at the true parameters" in short[0]
    commands = _suggested(short[0])
    # the run's own overrides, without those that only change what it writes or shows
    assert commands[0] == ["python", "-m", "benchmark", "optimizer=deap", "budget=600", "polish=true"]
    assert commands[1] == ["python", "-m", "benchmark"]  # the default optimiser, its own budget
    again = _run(commands[0] + [*FAST, f"hydra.run.dir={tmp_path / 'polished'}"], tmp_path)
    assert again.returncode == 0, again.stderr
    rec = json.loads((tmp_path / "polished" / "result.json").read_text())
    assert rec["status"] == "converged" and rec["warnings"] == [], rec["warnings"]
    assert all(abs(e) < 1e-4 for e in rec["rel_error"].values()), rec["rel_error"]


def test_a_model_that_misses_suggests_the_diagnosis_of_that_folder_and_it_runs(tmp_path):
    spec = make_spec("paper_1kw", "six_step", ["double_cage"], seed=2, duration=0.4, ideal_supply=True)
    folder = write_dataset(make_dataset(spec), tmp_path / "dc")
    out = _run(["python", "-m", "benchmark", f"data.path={folder}", *FAST, f"hydra.run.dir={tmp_path / 'id'}"],
               tmp_path)
    assert out.returncode == 0, out.stderr
    w = _warnings(tmp_path / "id")
    misses = [s for s in w if s.startswith("the model misses the data")]
    assert len(misses) == 1 and not any(s.startswith("the optimiser stopped short") for s in w), w
    assert "a polish from the result does not lower the cost" in misses[0]
    (command,) = _suggested(misses[0])
    assert command == ["python", "-m", "benchmark.diagnose", f"data.path={folder}"]
    cheap = ["figures=false", "budget=300", "polish_budget=100", "candidates=[double_cage]",
             "diagnosis.screen_iterations=4", "diagnosis.max_iterations=8", f"hydra.run.dir={tmp_path / 'diag'}"]
    diag = _run(command + cheap, tmp_path)
    assert diag.returncode == 0, diag.stderr
    doc = json.loads((tmp_path / "diag" / "diagnosis.json").read_text())
    assert doc["status"] != "no_gap", doc["status"]


def test_the_default_optimiser_is_suggested_without_the_replaced_optimisers_settings():
    """A cold reviewer's Nelder-Mead run with its own tolerances was told to rerun with the default
    optimiser, and the command carried `optimizer.plugin.xatol=0.2`, an unknown key there."""
    from benchmark.core.commands import rerun_command

    cmd = rerun_command(["optimizer=scipy_de", "optimizer.plugin.popsize=5", "+optimizer.plugin.tol=0.1", "seed=3",
                         "budget=400", "data.path=bench", "figures=false"], optimizer=None, budget=None)
    assert cmd == "python -m benchmark seed=3 data.path=bench"
    polished = rerun_command(["optimizer=deap", "seed=1"], polish=True)
    assert polished == "python -m benchmark optimizer=deap seed=1 polish=true"


def test_the_recorded_command_runs_as_typed():
    """result.json recorded '/path/benchmark/__main__.py optimizer=...', which a reader cannot run."""
    from benchmark.core.commands import typed_command

    argv = ["/x/benchmark/__main__.py", "optimizer=deap", "data.path=my data", "++bounds.J=[0.001,0.1]"]
    assert typed_command(argv) == "python -m benchmark optimizer=deap 'data.path=my data' '++bounds.J=[0.001,0.1]'"
    assert typed_command("/x/benchmark/__main__.py seed=1") == "python -m benchmark seed=1"  # an older record
    assert typed_command("python -m benchmark seed=1") == "python -m benchmark seed=1"


def test_a_search_that_stops_on_its_own_short_of_the_minimum_says_so_beside_converged(tmp_path):
    """A cold reviewer's Nelder-Mead with loose tolerances stopped after 6 evaluations at a cost of
    1.26e6 and printed 'status converged'. The status stays the optimiser's (it stopped on its own
    criterion), and the line says what the review found."""
    cmd = ["python", "-m", "benchmark", "optimizer=least_squares", "optimizer.plugin.ftol=0.9",
           "optimizer.plugin.xtol=0.9", *FAST, f"hydra.run.dir={tmp_path / 'loose'}"]
    out = _run(cmd, tmp_path)
    assert out.returncode == 0, out.stderr
    rec = json.loads((tmp_path / "loose" / "result.json").read_text())
    assert rec["status"] == "converged" and rec["review"]["stopped_short"]["short"]
    assert "status converged (the optimiser's own stop; the review finds it stopped short" in out.stdout
