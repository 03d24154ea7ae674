"""``python -m benchmark.report DIR [key=value ...]``: tabulate a sweep's runs.

Every ``result.json`` under DIR is aggregated (:mod:`benchmark.analysis.aggregate`, whose
docstring defines the tables): ``summary.md``, ``.csv``, ``.tex``, figures and an IOHprofiler
export. ``--help`` prints the arguments.
"""

from __future__ import annotations

import sys

from benchmark.analysis import aggregate
from benchmark.analysis.runs import ReportError

USAGE = """usage: python -m benchmark.report DIR [out=FOLDER] [target_rel=0.01] [target_abs=X]
                                  [budgets=[1000,5000,20000,60000]] [success_tol=0.01]
                                  [figures=true] [ioh=true]

Aggregates every result.json under DIR (a sweep's multirun folder, or any folder of runs) into
summary.md / summary.csv / summary.tex, figures/ (convergence and ECDF per problem) and ioh/
(an IOHprofiler export), written to DIR or out=FOLDER.

  target_rel   fixed target: within this fraction of the best cost any run found (default 0.01)
  target_abs   an absolute precision instead
  budgets      fixed budgets (evaluations) at which the best costs are compared
  success_tol  a run succeeds when every parameter is within this relative error (default 0.01)
"""

if __name__ == "__main__":
    if any(a in ("-h", "--help", "help") for a in sys.argv[1:]):
        print(USAGE)
        sys.exit(0)
    try:
        aggregate.main(sys.argv[1:])
    except ReportError as exc:
        print(f"error: {exc}\n\n{USAGE}", file=sys.stderr)
        sys.exit(2)
