"""The suite's tables (Markdown, CSV, LaTeX) and its IOHprofiler export, from the measures.

``summary.md`` (every table, figures linked), ``leaderboard.csv`` (one row per optimiser, over all
instances and per group value), ``instances.csv`` (f*, how it was found, groups, share of runs at
f*), ``runs.csv`` (one row per run), ``hardest.csv``, ``summary.tex`` (the leaderboards) and
``ioh/`` + ``ioh.zip``: one IOHprofiler function per instance, ``raw_y`` the run's best cost's
precision ``(cost - f*) / s`` (0 at f*), so that IOHanalyzer's fixed targets are the precisions
the suite uses.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from benchmark.analysis.fmt import _g, _pct
from benchmark.analysis.ioh import write_ioh
from benchmark.analysis.runs import Run
from benchmark.analysis.tables import _md_table, _tex_table
from benchmark.analysis.targets import Row
from benchmark.core.io import write_text_atomic
from benchmark.studies.suite.measures import (
    REACHED,
    best_precision,
    default_check,
    group_keys,
    hardest,
    in_group,
    labels,
    summary,
)

HEAD = ["optimizer", "instances", "runs", "failed", "runs at f*", "instances solved", "all seeds at f*",
        "ERT to 1e-1", "ERT to f* (1e-3)", "success (2 %)", "median wall (s)"]


def _cells(s: dict) -> list[str]:
    return [s["optimizer"], str(s["instances"]), str(s["runs"]), str(s["failed"]), _pct(s["reached_share"]),
            str(s["instances_solved"]), str(s["instances_all_seeds"]), _g(s["ert_1e-1"], 4), _g(s["ert_1e-3"], 4),
            _pct(s["success_share"]), _g(s["wall_median_s"], 3)]


def _ranked(results, select=None) -> list[dict]:
    rows = [summary(results, lab, select) for lab in labels(results)]
    rows = [r for r in rows if r]
    return sorted(rows, key=lambda s: (-s["reached_share"], s["ert_1e-3"]))


def leaderboard_frame(results) -> pd.DataFrame:
    recs = [{"group": "all", "value": "all", **s} for s in _ranked(results)]
    for g in group_keys(results):
        for v in sorted({ir.doc["groups"][g] for ir in results.values()}):
            recs += [{"group": g, "value": v, **s} for s in _ranked(results, in_group(g, v))]
    return pd.DataFrame(recs)


def runs_frame(results) -> pd.DataFrame:
    recs = []
    for ir in results.values():
        for r in ir.runs:
            recs.append({"instance": ir.name, "optimizer": r.label, "seed": r.seed, "status": r.status,
                         "cost": r.cost, "fstar": ir.target.best, "precision": ir.precision(r.cost),
                         "reached": ir.reached(r), "success": ir.success(r), "evaluations": r.total,
                         "wall_time_s": r.wall, "message": r.message[:300]})
    return pd.DataFrame(recs)


def instances_frame(results, fstars: dict) -> pd.DataFrame:
    recs = []
    for ir in results.values():
        fs = fstars.get(ir.name) or {}
        recs.append({"instance": ir.name, **ir.doc["groups"], "fstar": ir.target.best, "scale": ir.target.scale,
                     "how": fs.get("how", "best run"), "cost_at_truth": (fs.get("candidates") or {}).get("truth"),
                     "runs_at_fstar": float(np.mean([ir.reached(r) for r in ir.runs])),
                     "fstar_point_within_2pct_of_truth": _ceiling(ir)})
    return pd.DataFrame(recs)


def _ceiling(ir) -> bool | None:
    """Whether the best-known fit itself is within 2 % of the truth (success is attainable)."""
    from benchmark.studies.suite.measures import parameters_within

    truth = ir.runs[0].run.rec.get("truth")
    best = min(ir.runs, key=lambda r: r.cost)
    est = best.run.rec.get("estimate")
    return parameters_within(est or {}, truth, ir.doc["problem"], best.run.rec.get("parameter_names"))


def _group_table(results, g: str) -> list[str]:
    values = sorted({ir.doc["groups"][g] for ir in results.values()})
    head = ["optimizer"] + [f"{v} ({sum(ir.doc['groups'][g] == v for ir in results.values())})" for v in values]
    body = []
    for lab in labels(results):
        cells = [lab]
        for v in values:
            s = summary(results, lab, in_group(g, v))
            cells.append("–" if not s else f"{_pct(s['reached_share'])} / {_g(s['ert_1e-3'], 3)}")
        body.append(cells)
    return _md_table(head, body)


def _hardest_table(results, n: int) -> list[str]:
    labs = labels(results)
    head = ["instance", "f*", "runs at f*"] + labs
    body = []
    for ir, share in hardest(results, n):
        body.append([ir.name, _g(ir.target.best, 6), _pct(share)] + [_g(best_precision(ir, lab), 2) for lab in labs])
    return _md_table(head, body)


def _default_section(results, label: str) -> list[str]:
    d = default_check(results, label)
    if not d:
        return []
    lines = [f"**{label}**: {d['runs_reached']}/{d['runs']} runs at f* (within {REACHED:g}), "
             f"{d['instances_all_seeds']}/{d['instances']} instances with every seed at f*; "
             f"{d['converged_claims']} runs claimed a confirmed minimum (`converged: ...`), "
             f"{d['converged_above_fstar']} of them above f*."]
    for m in d["misses"][:20]:
        lines.append(f"- miss: {m['instance']} seed {m['seed']}, precision {_g(m['precision'], 3)}, "
                     f"{'warned' if m['warned'] else 'NOT warned'}: {m['message']}")
    return lines + [""]


def write_ioh_export(results, out: Path) -> None:
    rows = []
    for ir in results.values():
        for lab in labels(results):
            mine = [r for r in ir.runs if r.label == lab and len(r.run.evals)]
            if not mine:
                continue
            runs = [Run(path=r.run.path, rec=r.run.rec, evals=r.run.evals,
                        best=np.maximum(r.run.best - ir.target.best, 0.0) / ir.target.scale,
                        group=ir.name, instance="0", algorithm=lab) for r in mine]
            rows.append(Row(group=ir.name, algorithm=lab, runs=runs, parameters=[], values={"optimizer": lab}))
    write_ioh(rows, out, y_note="raw_y is the precision (best cost so far - f*) / s of the suite's targets "
                                "(0 at f*; s = |f*| unless f* is ~0); one function per instance.")


def write_report(results, fstars: dict, out: Path, figures: dict, meta: dict, defaults=("multistart",)) -> None:
    out.mkdir(parents=True, exist_ok=True)
    lb = leaderboard_frame(results)
    write_text_atomic(out / "leaderboard.csv", lb.to_csv(index=False, float_format="%.6g"))
    write_text_atomic(out / "runs.csv", runs_frame(results).to_csv(index=False, float_format="%.10g"))
    write_text_atomic(out / "instances.csv", instances_frame(results, fstars).to_csv(index=False, float_format="%.10g"))
    hard = [{"instance": ir.name, "fstar": ir.target.best, "runs_at_fstar": share,
             **{lab: best_precision(ir, lab) for lab in labels(results)}} for ir, share in hardest(results, 15)]
    write_text_atomic(out / "hardest.csv", pd.DataFrame(hard).to_csv(index=False, float_format="%.6g"))
    md = [f"# Suite `{meta.get('suite', '?')}`: summary", "", f"Command: `{meta.get('command', '')}`", "",
          f"{len(results)} instances, {sum(len(ir.runs) for ir in results.values())} runs. Targets f* + p s "
          f"(s = |f*|); a run is **at f*** within p = {REACHED:g}; ERT = evaluations of all runs until they "
          "reached the target or stopped, over the runs that reached it (pooled over instances); success: "
          "every scored parameter within 2 % of the truth (with model error: of the best-known fit). "
          "Definitions: `benchmark/studies/suite/measures.py`.", "", "## Leaderboard, all instances", ""]
    md += _md_table(HEAD, [_cells(s) for s in _ranked(results)]) + [""]
    for prob in sorted({ir.doc["problem"] for ir in results.values()}):
        md += [f"## Leaderboard, {prob}", ""]
        md += _md_table(HEAD, [_cells(s) for s in _ranked(results, in_group("problem", prob))]) + [""]
    md += ["## Per group: runs at f* / ERT to f*", ""]
    for g in group_keys(results):
        md += [f"### {g}", ""] + _group_table(results, g) + [""]
    md += ["## Hardest instances (median precision (cost - f*)/s each optimiser reached; 0 = f*)", ""]
    md += _hardest_table(results, 15) + [""]
    md += ["## The default pipeline", ""]
    for lab in defaults:
        md += _default_section(results, lab)
    for name, path in figures.items():
        md += [f"![{name}]({path})", ""]
    write_text_atomic(out / "summary.md", "\n".join(md).rstrip() + "\n")
    tex = ["% Written by python -m benchmark.suite; needs \\usepackage{booktabs}.", ""]
    tex += _tex_table(HEAD, [_cells(s) for s in _ranked(results)], caption="All instances: leaderboard.",
                      label="tab:suite-all")
    for prob in sorted({ir.doc["problem"] for ir in results.values()}):
        tex += _tex_table(HEAD, [_cells(s) for s in _ranked(results, in_group("problem", prob))],
                          caption=f"{prob}: leaderboard.", label=f"tab:suite-{prob}")
    write_text_atomic(out / "summary.tex", "\n".join(tex))
    write_ioh_export(results, out)

