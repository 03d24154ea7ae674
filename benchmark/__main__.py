"""``python -m benchmark``: one identification run (or a sweep with ``-m``).

With no arguments it makes the paper's noise-free synthetic start-up (Alonge et al. 1998) and
identifies it with the default pipeline (``multistart``: differential evolution, then least
squares from several starts); ``optimizer=genesis`` runs the paper's GA. A thin shell over
:func:`benchmark.api.identify`'s path: the same configuration gives the same numbers.

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

from benchmark.api import identification_of
from benchmark.core.cli import run_hydra_main, user_errors
from benchmark.core.config_files import CONFIG_DIR
from benchmark.core.harness import run

TITLE = ("imbench: identify the parameters of an induction-motor model from a start-up record (Alonge et al. "
         "1998)\nor a slip sweep (Lindsay and Barton 1972), and say how good the fit is.")
USAGE = ("python -m benchmark [group=option ...] [key=value ...]          one run -> outputs/.../result.json",
         "python -m benchmark -m optimizer=deap,cmaes seed='range(5)'      a sweep -> multirun/...")
FOOTER = ("", "Other commands (each with --help): python -m benchmark.diagnose (why the model misses the data),",
          "python -m benchmark.report DIR (tabulate a sweep), python -m synthetic (write a data set),",
          "python -m benchmark.blind (the diagnosis evaluated blind). The user guide: README.md and docs/.")


@hydra.main(version_base="1.3", config_path=str(CONFIG_DIR), config_name="config")
@user_errors
def main(cfg) -> float | None:
    outdir = Path(HydraConfig.get().runtime.output_dir)
    result = identification_of(run(cfg, outdir), outdir)
    rec = result.record
    if HydraConfig.get().mode == RunMode.MULTIRUN:  # a sweep: one line per run, not interleaved tables
        # One write of the whole line: the sweep's workers share one pipe, and print's separate
        # newline write let two lines run together.
        sys.stdout.write(one_line(rec, outdir) + "\n")
        sys.stdout.flush()
        return rec["cost"]
    print(result)
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
    run_hydra_main(main, "config", TITLE, USAGE, FOOTER)
