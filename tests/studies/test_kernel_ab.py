"""The kernel study (``benchmark.studies.perf.kernel_ab``) compares a reference checkout's kernel
and brake coast with this one's on captured rows: against this checkout itself, the outputs are
the same bit for bit, and a reference that computes otherwise is reported as not the same. Marked
``slow``: the reference's copies of the kernel compile afresh."""

import pickle
import shutil

import numpy as np
import pytest

from benchmark.problems.timedomain.extended import base_rows
from benchmark.problems.timedomain.extended_rows import IDX
from benchmark.studies.perf.common import ROOT
from benchmark.studies.perf.kernel_ab import compare


def _captured(path):
    rows = base_rows(np.array([[3.0, 0.2, 0.02, 2.0, 0.01, 0.001, 0.01],
                               [3.3, 0.2, 0.02, 2.1, 0.01, 0.001, 0.01]]), 2)
    rows[1, IDX["T_s"]], rows[1, IDX["t_step"]], rows[1, IDX["tau_s"]] = 2.0, 0.01, 0.005
    rows[1, IDX["w_ref"]] = 157.0
    t = np.arange(400) * 1e-4
    v = 300.0 * np.cos(2 * np.pi * 50 * t)
    n = 3
    coast = (np.arange(0.0, 1.0, 1e-3), np.full(n, 100.0), np.full(n, 0.01), np.full(n, 0.001),
             np.full(n, 0.1), np.zeros(n), np.full(n, 1.0), np.full(n, 157.0), np.full(n, 1.0),
             np.array([0.0, 1e-4, 0.05]))
    with open(path, "wb") as f:
        pickle.dump({"record": "synthetic", "verdict": "none", "rows": rows,
                     "input": (v, 300.0 * np.sin(2 * np.pi * 50 * t), True, 1e-4, 1), "coasts": [coast]}, f)


@pytest.mark.slow  # compiles two copies of the kernel afresh (about 30 s)
def test_the_study_finds_this_checkout_equal_to_itself_and_a_changed_one_not(tmp_path):
    _captured(tmp_path / "rows.pkl")
    same = compare(tmp_path / "rows.pkl", ROOT, rows=2, rounds=1)
    assert same["kernel_same"] and same["coast_same"] and same["rows"] == 2 and same["coast_rows"] == 3
    # a "reference" whose coast takes twice as long steps on a lagged row: its outputs differ, and the study says so
    ref = tmp_path / "ref"
    src = ROOT / "benchmark" / "problems" / "timedomain"
    (ref / "benchmark" / "problems" / "timedomain" / "diagnosis").mkdir(parents=True)
    shutil.copy(src / "extended.py", ref / "benchmark" / "problems" / "timedomain" / "extended.py")
    coast_src = (src / "diagnosis" / "free_coast.py").read_text()
    changed = coast_src.replace("STEPS_PER_LAG = 4", "STEPS_PER_LAG = 2")
    assert changed != coast_src
    (ref / "benchmark" / "problems" / "timedomain" / "diagnosis" / "free_coast.py").write_text(changed)
    other = compare(tmp_path / "rows.pkl", ref, rows=2, rounds=1)
    assert other["kernel_same"] and not other["coast_same"]
