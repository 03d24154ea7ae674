"""``python -m benchmark``: one identification run (or a sweep with ``-m``).

With no arguments it makes the paper's synthetic case (Alonge et al. 1998, noise-free) and
identifies it with the GENESIS clone at the paper's settings. See README for the options.

Exit status: 0 when the run finished (``budget_spent`` or ``converged``), 2 for a data or
configuration error, 3 when a single run was recorded as ``failed`` or ``timeout`` (its
``result.json`` says why). In a sweep (``-m``) a failed run is recorded and the sweep goes on.
"""

from __future__ import annotations

import sys
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode

from benchmark.core.cli import run_hydra_main, user_errors
from benchmark.core.harness import format_table, run


@hydra.main(version_base="1.3", config_path="../conf", config_name="config")
@user_errors
def main(cfg) -> float | None:
    outdir = Path(HydraConfig.get().runtime.output_dir)
    outcome = run(cfg, outdir)
    print(format_table(outcome.record))
    print(f"result: {outdir / 'result.json'}")
    if (outcome.record.get("figures") or {}).get("report"):
        print(f"report: {outdir / outcome.record['figures']['report']} (figures)")
    if outcome.record["status"] in ("failed", "timeout") and HydraConfig.get().mode == RunMode.RUN:
        sys.exit(3)
    return outcome.record["cost"]


if __name__ == "__main__":
    run_hydra_main(main)
