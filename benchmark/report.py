"""``python -m benchmark.report DIR``: tabulate a sweep's runs (:mod:`benchmark.analysis.aggregate`)."""

from __future__ import annotations

import sys

from benchmark.analysis.aggregate import ReportError, main

if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except ReportError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
