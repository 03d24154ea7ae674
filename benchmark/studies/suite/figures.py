"""The suite's figures: runtime ECDFs (all instances, then one panel per value of each group) and
ERT against the target precision, one line per optimiser (a colour per optimiser, dashed with
polish, dotted for a variant such as the previous default)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from benchmark.analysis.fmt import _slug
from benchmark.core.plotting import new_figure
from benchmark.studies.suite.measures import (
    PRECISIONS,
    REACHED,
    ecdf_curve,
    ert_at,
    group_keys,
    in_group,
    labels,
)


def _styles(names: list[str], base_names: list[str]) -> dict[str, tuple[str, str]]:
    bases = sorted({n.replace("+polish", "") for n in names if n.replace("+polish", "") in base_names})
    out = {}
    for n in names:
        b = n.replace("+polish", "")
        if b in bases:
            out[n] = (f"C{bases.index(b) % 10}", "--" if n.endswith("+polish") else "-")
        else:
            out[n] = ("0.35", ":")
    return out


def _save(fig, out: Path, stem: str) -> str:
    (out / "figures").mkdir(parents=True, exist_ok=True)
    for ext in ("png", "svg"):
        fig.savefig(out / "figures" / f"{stem}.{ext}", dpi=120)
    return f"figures/{stem}.png"


def _grid(results) -> np.ndarray:
    top = max(r.total for ir in results.values() for r in ir.runs)
    return np.unique(np.round(np.geomspace(1, max(top, 2), 300)))


def _ecdf_axes(ax, results, names, styles, grid, select=None, legend=True) -> None:
    for name in names:
        frac, n = ecdf_curve(results, name, grid, select)
        if n:
            c, ls = styles[name]
            ax.step(grid, frac, where="post", color=c, ls=ls, lw=1.4, label=f"{name} ({n} runs)")
    ax.set_xscale("log")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(True, which="both", alpha=0.3)
    if legend:
        ax.legend(fontsize=6.5, loc="center left", bbox_to_anchor=(1.01, 0.5))


def write_figures(results, out: Path, base_names: list[str]) -> dict[str, str]:
    """Every figure into ``out/figures``; returns {name: relative PNG path}."""
    names = labels(results)
    styles = _styles(names, base_names)
    grid = _grid(results)
    made = {}
    fig, ax = new_figure(figsize=(10, 5))
    _ecdf_axes(ax, results, names, styles, grid)
    ax.set_xlabel("evaluations (counted by the harness)")
    ax.set_ylabel("fraction of (run, target) pairs reached")
    ax.set_title(f"All {len(results)} instances: runtime ECDF over {len(PRECISIONS)} targets per instance, "
                 f"f* + p |f*|, p = 1e2 ... 1e-5", fontsize=9)
    fig.tight_layout()
    made["ecdf_all"] = _save(fig, out, "ecdf_all")
    for g in group_keys(results):
        values = sorted({ir.doc["groups"][g] for ir in results.values()})
        if len(values) < 2:
            continue
        cols = min(3, len(values))
        rows = math.ceil(len(values) / cols)
        fig, axes = new_figure(rows, cols, figsize=(4.2 * cols + 3, 3.2 * rows), squeeze=False)
        for k, v in enumerate(values):
            ax = axes.flat[k]
            sel = [ir for ir in results.values() if ir.doc["groups"][g] == v]
            _ecdf_axes(ax, results, names, styles, grid, select=in_group(g, v), legend=False)
            ax.set_title(f"{g}: {v} ({len(sel)} instances)", fontsize=8)
            ax.tick_params(labelsize=7)
        for ax in list(axes.flat)[len(values):]:
            ax.set_visible(False)
        handles, labs = axes.flat[0].get_legend_handles_labels()
        fig.legend(handles, [lab.split(" (")[0] for lab in labs], fontsize=7, loc="center right")
        fig.supxlabel("evaluations", fontsize=8)
        fig.supylabel("fraction of (run, target) pairs reached", fontsize=8)
        fig.tight_layout(rect=(0, 0, 1 - 2.6 / (4.2 * cols + 3), 1))
        made[f"ecdf_{_slug(g)}"] = _save(fig, out, f"ecdf_{_slug(g)}")
    problems = sorted({ir.doc["problem"] for ir in results.values()})
    fig, axes = new_figure(1, len(problems), figsize=(5.5 * len(problems) + 2.5, 4.2), squeeze=False)
    for ax, prob in zip(axes.flat, problems, strict=True):
        sel = in_group("problem", prob)
        for name in names:
            e = np.array([ert_at(results, name, p, sel) for p in PRECISIONS])
            ok = np.isfinite(e)
            if ok.any():
                c, ls = styles[name]
                ax.plot(PRECISIONS[ok], e[ok], color=c, ls=ls, lw=1.4, marker=".", ms=3, label=name)
        ax.axvline(REACHED, color="k", lw=0.8, ls=":")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.invert_xaxis()
        ax.grid(True, which="both", alpha=0.3)
        ax.set_xlabel("target precision p (target f* + p |f*|)")
        ax.set_ylabel("ERT (evaluations)")
        ax.set_title(f"{prob}: ERT over all its instances (missing: never reached)", fontsize=9)
    axes.flat[-1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    made["ert"] = _save(fig, out, "ert")
    return made
