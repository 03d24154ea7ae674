"""An experiment for the selection layer: the diagnosis with the linearised score tests in place of
the fitted screening (:meth:`Selector.prescreen`), its time and its verdict.

The selection itself is not changed by this module: it replaces ``Selector.prescreen`` in this
process only, ordering the additions by the score tests'
(:func:`benchmark.problems.timedomain.diagnosis.score_tests.score_tests`) predicted held-out
chi^2 from the same state (the current set's fit on fold A, scored on fold B), and reports
the table in the screening's format. Each record is diagnosed with the default configuration
(no figures), and its CPU time and verdict are written out beside the record's name.

    python -m benchmark.studies.perf.score_screening RECORDS_DIR OUT.json [only=a,b]
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from benchmark.problems.timedomain.diagnosis import selection
from benchmark.problems.timedomain.diagnosis.score_tests import score_tests
from benchmark.studies.perf.diagnosis_runs import summary
from benchmark.studies.perf.score_agreement import _diagnose, screening_starts


def prescreen_by_score_tests(self, chosen, additions, cur, progress=None):
    """Selector.prescreen's contract (the additions ordered, the table) from the score tests."""
    if progress:
        progress("score tests " + " + ".join(e.name for e in chosen))
    rows = score_tests(self.model, list(chosen), cur.xs["A"], self.masks["A"], self.masks["B"], additions,
                       self.ctx, screening_starts(self, chosen))
    by_name = {"+".join(e.name for e in a): a for a in additions}
    held_cur = float(np.mean(cur.held[self.masks["B"]] ** 2))
    table = [{"effect": r["effect"], "heldout_chi2_fold_B": r["score"],
              "heldout_chi2_base_fold_B": held_cur} for r in rows]
    return [by_name[r["effect"]] for r in rows], table


def main(argv: list[str]) -> None:
    from benchmark.studies.perf.diagnosis_records import make_records

    opts = dict(a.split("=", 1) for a in argv[2:])
    names = opts["only"].split(",") if opts.get("only") else None
    selection.Selector.prescreen = prescreen_by_score_tests
    out = {}
    for name, folder in make_records(Path(argv[0]), names):
        c0 = time.process_time()
        doc = _diagnose(folder)
        out[name] = {"cpu_s": time.process_time() - c0, **summary(doc)}
        print(name, f"{out[name]['cpu_s']:.1f} CPU s", out[name]["verdict"], out[name]["status"], flush=True)
    Path(argv[1]).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    np.seterr(all="ignore")
    main(sys.argv[1:])
