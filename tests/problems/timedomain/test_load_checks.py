"""Wiring and unit mistakes made on a correct data set as a user would make them (a CSV header
edited, a column rescaled, a meta.yaml key changed) and run through the command line
(``python -m benchmark data.path=...``): each gives its one-line message
(:mod:`benchmark.problems.timedomain.load_checks`). They used to give a result: swapped S and T
voltage labels Rs = 0.002 ohm with 16 warnings, labels rotated by 120 degrees a bounds error
about a negative J, currents in mA J = 6.42 kg m^2 for a 1 kW motor and no warning, six-step
voltages read as continuous a misfit of 1170 times the noise.

The correct data set: the independent plant's 1 kW motor started direct on line (phase columns
``v_r, v_s, v_t, i_r, i_s``, a nameplate in meta.yaml), and started by a six-step inverter.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from benchmark.problems.timedomain.data import load_startup_dataset
from synthetic.independent import make_dataset, make_spec, write_dataset

REPO = Path(__file__).resolve().parents[3]
FAST = ["figures=false", "checkpoint=false", "progress=false"]


@pytest.fixture(scope="module")
def grid_start(tmp_path_factory):
    spec = make_spec("paper_1kw", "dol", [], seed=3, duration=0.5, sample_rate=5000.0)
    return write_dataset(make_dataset(spec), tmp_path_factory.mktemp("grid") / "ok")


def _cli(folder: Path, *extra: str):
    env = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "benchmark", f"data.path={folder}", *FAST, *extra,
                           f"hydra.run.dir={folder.parent / ('run_' + folder.name)}"],
                          cwd=folder.parent, env=env, capture_output=True, text=True, timeout=600)


def _mistake(ok: Path, name: str) -> Path:
    folder = ok.parent / name
    shutil.copytree(ok, folder)
    return folder


def _rename_header(folder: Path, mapping: dict) -> None:
    path = folder / "startup.csv"
    head, body = path.read_text().split("\n", 1)
    path.write_text(",".join(mapping.get(c, c) for c in head.split(",")) + "\n" + body)


def _error(out) -> str:
    assert out.returncode == 2, (out.returncode, out.stderr[-2000:])
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), out.stderr
    return lines[0]


def test_swapped_s_and_t_voltage_labels(grid_start):
    folder = _mistake(grid_start, "swapped")
    _rename_header(folder, {"v_s": "v_t", "v_t": "v_s"})
    msg = _error(_cli(folder))
    assert f"{folder / 'startup.csv'}, column 'v_r, v_s, v_t'" in msg
    assert "phase sequences disagree" in msg and "swap the columns v_s and v_t" in msg


@pytest.mark.parametrize("labels", [("v_s", "v_t", "v_r"), ("v_t", "v_r", "v_s")])
def test_voltage_labels_rotated_by_120_degrees_and_the_fix_it_names(grid_start, labels):
    folder = _mistake(grid_start, "rotated_" + "".join(labels))
    _rename_header(folder, dict(zip(("v_r", "v_s", "v_t"), labels, strict=True)))
    msg = _error(_cli(folder))
    assert "rotated by 120 degrees" in msg and "which no motor does" in msg
    (fix,) = re.findall(r"rename v_r, v_s, v_t to (v_\w), (v_\w), (v_\w)", msg)
    _rename_header(folder, dict(zip(("v_r", "v_s", "v_t"), fix, strict=True)))  # done as the message says
    fixed, ok = load_startup_dataset(folder).startups[0], load_startup_dataset(grid_start).startups[0]
    assert np.array_equal(fixed.v_alpha, ok.v_alpha) and np.array_equal(fixed.v_beta, ok.v_beta)


def test_currents_in_milliamperes_against_the_nameplate(grid_start):
    folder = _mistake(grid_start, "milliamperes")
    table = pd.read_csv(folder / "startup.csv")
    table[["i_r", "i_s"]] *= 1000.0
    table.to_csv(folder / "startup.csv", index=False)
    msg = _error(_cli(folder))
    assert f"{folder / 'startup.csv'}, column 'i_r, i_s'" in msg
    assert "times the nameplate's, which cannot be" in msg and "mA" in msg


def test_six_step_voltages_read_as_linear_are_told_to_set_input_hold_zoh(tmp_path):
    spec = make_spec("paper_1kw", "six_step", [], seed=3, duration=0.4, sample_rate=6000.0)
    folder = write_dataset(make_dataset(spec), tmp_path / "six_step")
    meta = (folder / "meta.yaml").read_text()
    assert "input_hold: zoh" in meta
    (folder / "meta.yaml").write_text(meta.replace("input_hold: zoh", "input_hold: linear"))
    out = _cli(folder, "budget=200", "polish_budget=50")
    assert out.returncode == 0, out.stderr[-2000:]
    (line,) = [s for s in out.stderr.splitlines() if "input_hold" in s]
    assert line.startswith(f"warning: {folder / 'meta.yaml'}: input_hold is linear") and "set input_hold: zoh" in line
