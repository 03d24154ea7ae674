"""Figures of one run, saved beside its ``result.json`` (PNG and SVG) and listed in ``report.md``.

Which figures a run gets depends on its problem: its own (``problem.plots(x, record)``, e.g.
:mod:`benchmark.problems.timedomain.figures`, :mod:`benchmark.problems.admittance.figures`),
and for every problem the convergence, the best cost against the evaluations (``history.csv``).

The harness calls :func:`write_run_figures` once the result is safely written; each figure is
drawn on its own, so one that fails (listed under ``errors``) does not cost the others. Long
records are reduced before drawing to a min/max envelope of about one bin per pixel column
(:func:`envelope`), which draws the same picture from a few thousand points, so a figure costs
well under a second and an SVG stays a few hundred kB. Matplotlib is used through its object
interface (no pyplot, no global backend switch), so making figures has no side effect on the
process. The SVG files carry no date, so the same run gives the same files.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmark.core.commands import typed_command

__all__ = ["Plot", "envelope", "figure_plots", "write_run_figures", "write_report", "REPORT_NAME"]

REPORT_NAME = "report.md"
DPI = 110
#: Bins of the min/max envelope of a long record (a bit more than the axes' width in pixels).
ENVELOPE_BINS = 1000
#: The zoom on the start of the start-up (Alonge et al. Figs. 17-20 show the first 100 ms).
ZOOM_S = 0.1
MEASURED = "k"
MODEL = "C1"


@dataclass
class Plot:
    """One figure: file stem, title (for the report), caption and the function that draws it
    on a fresh :class:`matplotlib.figure.Figure` of size ``size`` (inches)."""

    name: str
    title: str
    caption: str
    draw: Callable
    size: tuple[float, float] = (9.0, 4.5)
    files: list[str] = field(default_factory=list)


def new_figure(*args, figsize=(9.0, 4.5), **kwargs):
    """``(figure, axes)`` like ``pyplot.subplots`` but through the object interface: no pyplot
    state, no global backend switch, nothing to close. ``args``/``kwargs`` go to
    :meth:`matplotlib.figure.Figure.subplots`."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(*args, **kwargs)


# -- drawing helpers ---------------------------------------------------------------------------
def envelope(t: np.ndarray, y: np.ndarray, bins: int = ENVELOPE_BINS) -> tuple[np.ndarray, np.ndarray]:
    """``(t, y)`` reduced to at most about ``2 bins`` points that draw the same line: for each
    bin of consecutive samples its smallest and largest value, in time order. Short records
    are returned as they are; non-finite values (a diverged simulation) stay gaps."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    n = len(y)
    if n <= 2 * bins:
        return t, y
    k = int(math.ceil(n / bins))
    m = (n // k) * k
    Y = y[:m].reshape(-1, k)
    finite = np.isfinite(Y)
    lo = np.argmin(np.where(finite, Y, np.inf), axis=1)
    hi = np.argmax(np.where(finite, Y, -np.inf), axis=1)
    idx = np.sort(np.stack([lo, hi], axis=1), axis=1) + (np.arange(len(Y)) * k)[:, None]
    idx = np.concatenate([idx.ravel(), np.arange(m, n)])
    return t[idx], y[idx]


def rms(a: np.ndarray, b: np.ndarray) -> float:
    d = np.asarray(a, float) - np.asarray(b, float)
    d = d[np.isfinite(d)]
    return float(np.sqrt(np.mean(d * d))) if len(d) else math.nan


def _save(fig, outdir: Path, name: str) -> list[str]:
    import matplotlib

    files = []
    with matplotlib.rc_context({"svg.hashsalt": "imbench"}):
        for ext in ("png", "svg"):
            path = outdir / f"{name}.{ext}"
            meta = {"Date": None} if ext == "svg" else None
            fig.savefig(path, dpi=DPI, metadata=meta)
            files.append(path.name)
    return files


# -- convergence -------------------------------------------------------------------------------
def convergence_plot(problem, record: dict, outdir: Path) -> Plot | None:
    path = outdir / str(record.get("history") or "history.csv")
    if not path.is_file():
        return None
    import pandas as pd

    h = pd.read_csv(path)
    if h.empty:
        return None
    total = int(record.get("evaluations") or h["evaluations"].max())

    phases = list(dict.fromkeys(h["phase"].astype(str)))
    n_opt = record.get("evaluations_optimizer")

    def draw(fig):
        ax = fig.subplots()
        cost = h["best_cost"].to_numpy(float)
        positive = bool(np.all(cost[np.isfinite(cost)] > 0))
        colors = {"optimizer": "C0", "polish": "C1"}
        last = None
        for k, phase in enumerate(phases):
            part = h[h["phase"].astype(str) == phase]
            e = part["evaluations"].to_numpy(float)
            c = part["best_cost"].to_numpy(float)
            if last is not None:  # the polish starts from the optimiser's best point
                e, c = np.concatenate([[last[0]], e]), np.concatenate([[last[1]], c])
            if k < len(phases) - 1:
                nxt = float(h["evaluations"][h["phase"].astype(str) == phases[k + 1]].iloc[0])
                end = float(n_opt) if phase == "optimizer" and n_opt else nxt - 1
            else:
                end = float(total)
            e, c = np.concatenate([e, [max(end, e[-1])]]), np.concatenate([c, [c[-1]]])
            name = record.get("optimizer", "optimizer") if phase == "optimizer" else phase
            ax.step(e, c, where="post", color=colors.get(phase, f"C{k + 2}"), lw=1.6,
                    label=f"{name}: {c[-1]:.4g} after {int(e[-1])} evaluations")
            last = (e[-1], c[-1])
        ax.set_xscale("log")
        ax.set_yscale("log" if positive else "symlog")
        ax.set_xlabel("evaluations (counted by the harness)")
        ax.set_ylabel(f"best cost so far\n({_cost_unit(problem)})", fontsize=9)
        ax.grid(True, which="major", alpha=0.3)
        ax.grid(True, which="minor", axis="x", alpha=0.1)
        ax.legend(fontsize=8, loc="lower left")
        ax.set_title(f"Convergence: {record.get('problem')} / {record.get('optimizer')}, seed {record.get('seed')} "
                     f"(budget {record.get('budget')})", fontsize=10)

    return Plot("convergence", "Convergence",
                "Best cost found against the evaluations counted by the harness (history.csv), log scales; "
                "the polish phase, when run, continues from the optimiser's best point.",
                draw, size=(8.0, 4.5))


def _cost_unit(problem) -> str:
    return getattr(problem, "cost_unit", "the problem's cost")


# -- the run's figures and report --------------------------------------------------------------


def figure_plots(problem, record: dict, x: np.ndarray | None, outdir: Path) -> tuple[list[Plot], list[str]]:
    """The figures of this run (not yet drawn), and the errors met while preparing them."""
    plots, errors = [], []
    make = getattr(problem, "plots", None)  # the problem's own figures (Problem.plots)
    if make is not None:
        try:
            with np.errstate(all="ignore"):
                plots += make(x, record)
        except Exception as exc:
            errors.append(f"{problem.name} figures: {type(exc).__name__}: {exc}")
    try:
        conv = convergence_plot(problem, record, Path(outdir))
        if conv is not None:
            plots.append(conv)
    except Exception as exc:
        errors.append(f"convergence: {type(exc).__name__}: {exc}")
    return plots, errors


def write_run_figures(problem, record: dict, x: np.ndarray | None, outdir) -> dict:
    """Draw and save every figure of the run into ``outdir`` and write ``report.md`` listing them.

    Returns ``{"report", "files", "errors", "time_s"}`` for ``result.json``. A figure that cannot
    be drawn is left out and its error listed; the others are still made."""
    from matplotlib.figure import Figure

    t0 = time.perf_counter()
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    plots, errors = figure_plots(problem, record, x, outdir)
    done = []
    for plot in plots:
        fig = Figure(figsize=plot.size, layout="constrained")
        try:
            with np.errstate(all="ignore"):
                plot.draw(fig)
                plot.files = _save(fig, outdir, plot.name)
            done.append(plot)
        except Exception as exc:
            errors.append(f"{plot.name}: {type(exc).__name__}: {exc}")
    write_report(outdir, record, done, errors)
    return {"report": REPORT_NAME, "files": [f for p in done for f in p.files], "errors": errors,
            "time_s": time.perf_counter() - t0}


def write_report(outdir: Path, record: dict, plots: list[Plot], errors: list[str]) -> Path:
    """``report.md``: what was run, the estimate against the truth, warnings, and the figures."""
    from benchmark.core.io import write_text_atomic

    r = record
    cost = r.get("cost")
    lines = [f"# {r.get('problem')} / {r.get('optimizer')}, seed {r.get('seed')}", ""]
    if r.get("command"):
        lines += [f"Command: `{typed_command(r['command'])}`", ""]
    info = r.get("problem_info") or {}
    if info.get("data"):
        lines += [f"Data: {info['data']}", ""]
    if info.get("conditioning"):  # what the problem's loader did to the record (bench records)
        lines += ["Conditioning on load:", ""] + [f"- {c}" for c in info["conditioning"]] + [""]
    from benchmark.core.harness import evaluations_text

    evals = evaluations_text(r)
    lines += [f"Status **{r.get('status')}**: cost {'-' if cost is None else f'{cost:.6g}'} after {evals}, "
              f"budget {r.get('budget')}, {r.get('wall_time_s', 0):.2f} s."
              + (f" {r['message']}" if r.get("message") and r.get("status") != "budget_spent" else ""), ""]
    est, truth, err = r.get("estimate") or {}, r.get("truth") or {}, r.get("rel_error") or {}
    se, units = r.get("standard_error") or {}, r.get("units") or {}

    def _se(k):
        return f"{se[k]:.3g}" if se.get(k) is not None else "-"

    if est and truth:
        lines += ["| parameter | unit | estimate | truth | error | standard error |", "|---|---|---|---|---|---|"]
        for k, v in est.items():
            t = f"{truth[k]:.6g}" if k in truth else "-"
            e = f"{100 * err[k]:+.3f} %" if k in err else "-"
            lines.append(f"| {k} | {units.get(k) or '-'} | {v:.6g} | {t} | {e} | {_se(k)} |")
        lines.append("")
    elif est:  # measured data: no truth to score against
        lines += ["| parameter | unit | estimate | standard error |", "|---|---|---|---|"] + \
            [f"| {k} | {units.get(k) or '-'} | {v:.6g} | {_se(k)} |" for k, v in est.items()] + [""]
    unc = r.get("uncertainty") or {}
    if se:
        lines += ["Standard errors (searched parameters): " + unc.get("method", "") + "; "
                  + f"{unc.get('evaluations', '?')} extra evaluations, not counted in the budget. "
                  "Parameters not searched (fixed by the data or derived) have none.", ""]
    corr = r.get("correlation")
    names = r.get("parameter_names") or []
    if corr and len(corr) == len(names):
        lines += ["Correlation of the searched parameters:", "", "| | " + " | ".join(names) + " |",
                  "|---" * (len(names) + 1) + "|"]
        for n, row in zip(names, corr, strict=True):
            lines.append(f"| {n} | " + " | ".join("-" if c is None else f"{c:+.3f}" for c in row) + " |")
        lines.append("")
    fq = {k: v for k, v in (r.get("fit_quality") or {}).items() if isinstance(v, dict)}
    if fq:
        lines += ["Fit quality: RMS misfit over the noise estimated from the data (at the noise level when "
                  "the ratio is inside the band):", "", "| channel | RMS misfit | noise | ratio | band | verdict |",
                  "|---|---|---|---|---|---|"]
        for k, v in fq.items():
            verdict = "at noise level" if v["at_noise_level"] else (
                "model misses the data" if v["ratio"] > v["threshold"] else "below noise level")
            lines.append(f"| {k} | {v['rms_misfit']:.4g} | {v['noise']:.4g} | {v['ratio']:.3g} | "
                         f"{v['lower']:.3g}-{v['threshold']:.3g} | {verdict} |")
        lines.append("")
    mech = info.get("mechanical")
    if mech:
        lines += [f"Free-stop pre-identification (case {mech['case']}): tau_m = {mech['tau_m']:.6g} s, "
                  f"fc/J = {mech['fc_over_J']:.6g} rad/s^2.", ""]
    warns = list(r.get("warnings") or []) + [f"figure not made: {e}" for e in errors]
    lines += (["Warnings:", ""] + [f"- {w}" for w in warns] + [""]) if warns else ["Warnings: none.", ""]
    lines += ["## Figures", ""]
    if not plots:
        lines += ["(none could be made)", ""]
    for p in plots:
        png = next((f for f in p.files if f.endswith(".png")), None)
        svg = next((f for f in p.files if f.endswith(".svg")), None)
        lines += [f"### {p.title}", "", f"![{p.title}]({png})", "", p.caption + (f" [SVG]({svg})" if svg else ""), ""]
    lines.append("Full record: [result.json](result.json); convergence history: [history.csv](history.csv).")
    path = Path(outdir) / REPORT_NAME
    write_text_atomic(path, "\n".join(lines) + "\n")
    return path
