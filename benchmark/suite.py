"""``python -m benchmark.suite``: the benchmark's suite of instances, its runs and its measures.

The code is in :mod:`benchmark.studies.suite` (``cli.py`` lists the arguments; ``--help``).

    python -m benchmark.suite                         # the small suite -> results/suite/ (under an hour on 2 cores)
    python -m benchmark.suite suite=full launcher=slurm hydra.launcher.partition=NAME
    python -m benchmark.suite user=my_folders.yaml    # the measures on your own data folders
"""

from __future__ import annotations

import os
import sys

# one numba thread here (f*, the cost stage's timed runs), as in a sweep's worker on 2 cores
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from benchmark.studies.suite.cli import run  # noqa: E402

if __name__ == "__main__":
    sys.exit(run(sys.argv[1:]))
