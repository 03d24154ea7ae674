"""``python -m benchmark.report DIR``: aggregate every ``result.json`` under DIR.

    python -m benchmark.report multirun/2026-01-01/12-00-00
    python -m benchmark.report DIR out=results/reference target_rel=0.001 budgets=[1000,20000]

Arguments are ``key=value`` (Hydra override style) plus, optionally, the folder as the one
plain argument (or ``dir=DIR``):

``out``          where to write (default: DIR)
``target_rel``   fixed-target precision, relative to the best cost any run found on the
                 same problem instance (default 0.01: within 1 % of that cost)
``target_abs``   an absolute precision instead (target = best cost + target_abs)
``budgets``      fixed budgets in evaluations (default [1000, 5000, 20000, 60000])
``success_tol``  a run succeeds when every parameter with a known truth is within this
                 relative error (default 0.01)
``figures``, ``ioh``  write the figures and the IOHprofiler export (default true)

Outputs (in ``out``): ``summary.csv`` (one row per problem and optimiser), ``summary.md``,
``summary.tex`` (booktabs tables), ``figures/convergence_<problem>.{png,svg}`` and
``figures/ecdf_<problem>.{png,svg}``, and ``ioh/`` with ``ioh.zip`` (IOHprofiler's JSON
index + ``.dat`` files, loadable in IOHanalyzer).

Only ``result.json`` and its ``history.csv`` are read, so the report works for any problem.
Definitions:

* **Problem** (a group of runs): the ``problem`` field plus any configuration value that
  differs between runs of that problem, except the optimiser's own settings, ``seed``,
  ``budget``, ``polish*`` and ``noise.seed``. Runs with different ``noise.seed`` are
  *instances* of one problem (COCO's word): they are aggregated together, but the best cost
  and the targets are per instance.
* **Optimiser**: ``optimizer.name``, ``+polish`` when polish was on, plus any of its settings
  (or budget) that differ between runs of the same name.
* **Relative error**: the signed ``rel_error`` of result.json; median and quartiles
  (linear interpolation) over the runs that did not fail. Failed runs are counted and
  listed, and count as unsuccessful.
* **Fixed target**: a run reaches the target ``f* + target_rel |f*|`` (``f*``: the best cost
  of any run on the instance) after the evaluations of the first history row at or below
  it. When ``|f*|`` is below 1e-6 of the cost range (median first cost minus ``f*``: a fit
  that reaches ~0, e.g. noise-free data and the exact model), ``1e-6 x range`` replaces
  ``|f*|``. ERT (expected running time, COCO) = evaluations of all runs until they reached the
  target or stopped, divided by the number of runs that reached it.
* **Fixed budget**: the best cost after B evaluations, from history.csv. A run that spent
  its budget before B has no value at B (it was not given B); a run that stopped on its own
  (status ``converged``) keeps its final cost. Medians are over the runs with a value.
* **ECDF**: fraction of (run, target) pairs reached after a number of evaluations, as COCO
  and IOHanalyzer draw runtime distributions, with 31 targets per instance ``f* + D``, D
  log-spaced from the cost range (median first cost minus ``f*``) down to ``1e-4 |f*|`` (with
  the same replacement of ``|f*|`` as above).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import yaml

from benchmark.analysis.ioh import write_ioh
from benchmark.analysis.runs import (
    DEFAULTS,
    ECDF_FINEST,
    ECDF_TARGETS,
    NEGLIGIBLE,
    ReportError,
    Run,
    label_runs,
    load_runs,
)
from benchmark.analysis.tables import (
    _slug,
    render_markdown,
    render_tex,
    write_csv,
)
from benchmark.analysis.targets import (
    Row,
    ecdf,
    quantile,
    summarize,
)
from benchmark.core.io import write_text_atomic
from benchmark.core.spelling import did_you_mean


# -- figures --------------------------------------------------------------------------------------
def _grid(runs: list[Run], n=400) -> np.ndarray:
    """Evaluation counts at which curves are drawn: n log-spaced whole numbers up to the longest run."""
    top = max([r.total_evals for r in runs] + [int(r.evals[-1]) for r in runs if len(r.evals)] + [1])
    return np.unique(np.round(np.geomspace(1, top, n)))


def _finish(fig, ax, figdir: Path, stem: str) -> str:
    """Grid, legend outside the axes (the curves stay visible), PNG and SVG; the PNG's path
    relative to the output folder."""
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(figdir / f"{stem}.{ext}", dpi=130)
    return f"figures/{stem}.png"


def write_figures(rows: list[Row], inst, out: Path) -> dict[str, dict[str, str]]:
    from benchmark.core.plotting import new_figure

    figdir = out / "figures"
    figdir.mkdir(parents=True, exist_ok=True)
    made: dict[str, dict[str, str]] = {}
    for group in sorted({r.group for r in rows}):
        grp = [r for r in rows if r.group == group]
        allruns = [run for row in grp for run in row.runs]
        if not any(len(r.evals) for r in allruns):
            continue
        slug = _slug(group)
        made[group] = {}
        grid = _grid(allruns)
        # one colour per optimiser; its +polish variant dashed in the same colour
        bases = sorted({r.algorithm.replace("+polish", "") for r in grp})
        style = {
            r.algorithm: (
                f"C{bases.index(r.algorithm.replace('+polish', '')) % 10}",
                "--" if "+polish" in r.algorithm else "-",
            )
            for r in grp
        }

        # convergence: median and quartiles of the best cost over the runs
        fig, ax = new_figure(figsize=(9, 4.5))
        positive = True
        for row in grp:
            color, ls = style[row.algorithm]
            M = np.array([[r.best_at(e) for e in grid] for r in row.runs])
            med = np.array([quantile(list(c), 0.5) for c in M.T])
            lo = np.array([quantile(list(c), 0.25) for c in M.T])
            hi = np.array([quantile(list(c), 0.75) for c in M.T])
            show = np.isfinite(med)
            if not show.any():
                continue
            positive &= bool(np.all(med[show] > 0))
            ax.plot(grid[show], med[show], color=color, ls=ls, lw=1.6, label=f"{row.algorithm} (n={len(row.runs)})")
            band = np.isfinite(lo) & np.isfinite(hi)
            ax.fill_between(grid[band], lo[band], hi[band], color=color, alpha=0.18, lw=0)
        fstars = [inst[key].best for key in inst if key[0] == group and math.isfinite(inst[key].best)]
        if len(fstars) == 1:
            ax.axhline(fstars[0], color="k", ls=":", lw=0.8, label="best cost any run found (f_best)")
        ax.set_xscale("log")
        ax.set_yscale("log" if positive else "symlog")
        ax.set_xlabel("evaluations (counted by the harness)")
        ax.set_ylabel(f"best cost so far (cost units of {grp[0].runs[0].rec['problem']})")
        ax.set_title(f"{group}: median and quartiles over runs", fontsize=10)
        made[group]["convergence"] = _finish(fig, ax, figdir, f"convergence_{slug}")

        # ECDF of (run, target) pairs
        fig, ax = new_figure(figsize=(9, 4.5))
        for row in grp:
            hits = np.array([r.evals_to(t) for r in row.runs for t in inst[(r.group, r.instance)].ecdf_targets()])
            frac = ecdf(hits, grid)
            ax.step(
                grid,
                frac,
                where="post",
                color=style[row.algorithm][0],
                ls=style[row.algorithm][1],
                lw=1.6,
                label=f"{row.algorithm} (n={len(row.runs)})",
            )
        ax.set_xscale("log")
        ax.set_ylim(-0.02, 1.02)
        ax.set_xlabel("evaluations (counted by the harness)")
        ax.set_ylabel("fraction of (run, target) pairs reached (-)")
        ax.set_title(
            f"{group}: ECDF over {ECDF_TARGETS} targets per instance, f* + D, "
            f"D from the cost range down to {ECDF_FINEST:g} max(|f*|, {NEGLIGIBLE:g} range)",
            fontsize=9,
        )
        made[group]["ecdf"] = _finish(fig, ax, figdir, f"ecdf_{slug}")
    return made


# -- entry point ----------------------------------------------------------------------------------
def parse_args(argv: Sequence[str]) -> dict:
    opts = dict(DEFAULTS)
    for a in argv:
        if "=" in a:
            key, val = a.split("=", 1)
            key = key.lstrip("+")
            if key not in DEFAULTS:
                raise ReportError(f"{key}: unknown argument{did_you_mean(key, list(DEFAULTS))}; valid: "
                                  f"{', '.join(DEFAULTS)}")
            opts[key] = val if key in ("dir", "out") else yaml.safe_load(val)
        elif opts["dir"] is None:
            opts["dir"] = a
        else:
            raise ReportError(f"{a}: only one folder can be given (got {opts['dir']} already)")
    if opts["dir"] is None:
        raise ReportError("no folder given: python -m benchmark.report DIR [out=...] [target_rel=...]")
    b = opts["budgets"]
    if isinstance(b, int):
        b = [b]
    if not isinstance(b, list) or not all(isinstance(x, int) and x > 0 for x in b):
        raise ReportError(f"budgets: expected a list of positive whole numbers, got {opts['budgets']!r}")
    opts["budgets"] = sorted(set(b))
    for key in ("target_rel", "success_tol"):
        if not isinstance(opts[key], (int, float)) or isinstance(opts[key], bool) or opts[key] < 0:
            raise ReportError(f"{key}: expected a non-negative number, got {opts[key]!r}")
    if opts["target_abs"] is not None and (not isinstance(opts["target_abs"], (int, float)) or opts["target_abs"] < 0):
        raise ReportError(f"target_abs: expected a non-negative number, got {opts['target_abs']!r}")
    return opts


def main(argv: Sequence[str]) -> list[Row]:
    opts = parse_args(argv)
    root = Path(opts["dir"])
    if not root.is_dir():
        raise ReportError(f"{root}: not a folder")
    out = Path(opts["out"]) if opts["out"] else root
    runs = load_runs(root)
    if not runs:
        raise ReportError(f"{root}: no result.json found under it")
    label_runs(runs)
    rows, inst = summarize(runs, opts)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / "summary.csv")
    figures = write_figures(rows, inst, out) if opts["figures"] else {}
    if opts["ioh"]:
        write_ioh(rows, out)
    command = "python -m benchmark.report " + " ".join(argv)
    write_text_atomic(out / "summary.md", render_markdown(rows, inst, opts, figures, command, len(runs)))
    write_text_atomic(out / "summary.tex", render_tex(rows, opts))
    n_failed = sum(r.failed for r in runs)
    print(
        f"{len(runs)} runs ({n_failed} failed), {len({r.group for r in runs})} problem(s), "
        f"{len(rows)} problem x optimiser rows -> {out / 'summary.md'}"
    )
    return rows
