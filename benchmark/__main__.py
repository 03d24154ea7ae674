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
    rec = outcome.record
    if HydraConfig.get().mode == RunMode.MULTIRUN:  # a sweep: one line per run, not interleaved tables
        # One write of the whole line: the sweep's workers share one pipe, and print's separate
        # newline write let two lines run together.
        sys.stdout.write(one_line(rec, outdir) + "\n")
        sys.stdout.flush()
        return rec["cost"]
    print(format_table(rec))
    print(f"result: {outdir / 'result.json'}")
    if (rec.get("figures") or {}).get("report"):
        print(f"report: {outdir / rec['figures']['report']} (figures)")
    if rec["status"] in ("failed", "timeout"):
        sys.exit(3)
    return rec["cost"]


def one_line(rec: dict, outdir: Path) -> str:
    """``problem/optimizer seed S: status, cost C, N evaluations, T s, W warnings -> folder``."""
    cost = rec.get("cost")
    warnings = len(rec.get("warnings") or [])
    return (f"{rec['problem']}/{rec['optimizer']} seed {rec['seed']}: {rec['status']}, cost "
            f"{'-' if cost is None else f'{cost:.6g}'}, {rec['evaluations']} evaluations, "
            f"{rec['wall_time_s']:.1f} s" + (f", {warnings} warning(s)" if warnings else "") + f" -> {outdir}")


if __name__ == "__main__":
    run_hydra_main(main)
