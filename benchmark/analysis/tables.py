"""The sweep summary as tables: CSV, Markdown (accuracy, budget, rankings) and LaTeX."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from benchmark.analysis.fmt import _g, _pct, _signed_pct, _slug
from benchmark.analysis.targets import Row, winners
from benchmark.core.io import write_text_atomic


# -- formatting -----------------------------------------------------------------------------------
def write_csv(rows: list[Row], path: Path) -> pd.DataFrame:
    recs = [{"problem": r.group, "optimizer_label": r.algorithm, **r.values} for r in rows]
    df = pd.DataFrame(recs)
    write_text_atomic(path, df.to_csv(index=False, float_format="%.10g"))
    return df


def _accuracy_table(grp: list[Row], params: list[str], tol: float) -> tuple[list[str], list[list[str]]]:
    head = (
        ["optimizer", "runs", "failed", f"success (all within {100 * tol:g} %)"]
        + params
        + ["median cost", "median optimiser time (s)", "median run time (s)"]
    )
    body = []
    for r in grp:
        v = r.values
        succ = "–" if v.get("success_n") is None else f"{v['success_n']}/{v['runs']}"
        cells = [r.algorithm, str(v["runs"]), str(v["failed"]), succ]
        for p in params:
            cells.append(
                f"{_signed_pct(v[f'{p}_median'])} [{_pct(v[f'{p}_iqr'])}]" if not math.isnan(v[f"{p}_median"]) else "–"
            )
        cells += [_g(v["cost_median"]), _g(v["optimizer_time_median_s"], 3), _g(v["wall_time_median_s"], 3)]
        body.append(cells)
    return head, body


def _budget_table(grp: list[Row], budgets) -> tuple[list[str], list[list[str]]]:
    # a fixed budget no run of the group reached (a sweep at budget 2000 against the default
    # 5000-60000) would be a column of dashes: left out
    budgets = [b for b in budgets if any(r.values[f"cost_at_{b}_n"] for r in grp)]
    head = ["optimizer", "target reached", "median evaluations to target", "ERT"] + [
        f"best cost at {b}" for b in budgets
    ]
    body = []
    for r in grp:
        v = r.values
        cells = [
            r.algorithm,
            f"{v['target_reached']}/{v['runs']}",
            _g(v["evals_to_target_median"], 5),
            _g(v["ert"], 5),
        ]
        for b in budgets:
            n = v[f"cost_at_{b}_n"]
            c = "–" if n == 0 else _g(v[f"cost_at_{b}_median"])
            cells.append(c if n in (0, v["runs"]) else f"{c} ({n}/{v['runs']})")
        body.append(cells)
    return head, body


def _md_table(head, body) -> list[str]:
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)] + [
        "| " + " | ".join(c.replace("|", "\\|") for c in row) + " |" for row in body
    ]


def _target_text(opts) -> str:
    if opts.get("target_abs") is not None:
        return f"best cost found + {opts['target_abs']:g}"
    return f"within {100 * float(opts['target_rel']):g} % of the best cost any run found on the instance"


def render_markdown(rows: list[Row], inst, opts, figures: dict, command: str, n_files: int) -> str:
    tol = float(opts["success_tol"])
    out = [
        "# Benchmark summary",
        "",
        f"Command: `{command}`",
        "",
        f"{n_files} runs read. Relative errors: median of the signed error over the runs that did not fail, "
        f"[interquartile range]. Success: every parameter within {100 * tol:g} % (failed runs count as "
        f"unsuccessful). Fixed target: {_target_text(opts)}; ERT = evaluations spent by all runs until they "
        f"reached it or stopped, over the number that reached it. Fixed budget: median best cost after B "
        f"evaluations over the runs given at least B (a count n/N shows when fewer). Times: the optimiser's "
        f"search alone, and the whole run (set-up, search, polish, standard errors, review). See "
        f"`benchmark/report.py` for the definitions.",
        "",
    ]
    wins = winners(rows, opts)
    for group in sorted({r.group for r in rows}):
        grp = [r for r in rows if r.group == group]
        params = grp[0].parameters
        keys = sorted(k for k in inst if k[0] == group)
        fstar = ", ".join(f"{_g(inst[k].best, 8)}" + (f" (noise.seed {k[1]})" if len(keys) > 1 else "") for k in keys)
        out += [f"## {group}", "", f"Best cost any run in this folder found (f_best): {fstar}. It is not the "
                "problem's optimum: the fixed targets are relative to it and move when runs are added "
                "(`target_abs=` fixes one).", ""]
        if wins.get(group):
            out += ["Who wins:", ""] + [f"- {line}" for line in wins[group]] + [""]
        out += ["### Parameter errors", ""] + _md_table(*_accuracy_table(grp, params, tol)) + [""]
        if {"J", "fv", "fc"} <= set(params):
            out += ["fv and fc follow J (a free stop fixes J/fv and fc/J, not J): where the stop record "
                    "fixes them their errors are J's.", ""]
        out += ["### Fixed target and fixed budget", ""] + _md_table(*_budget_table(grp, opts["budgets"])) + [""]
        if not any(r.values[f"cost_at_{b}_n"] for r in grp for b in opts["budgets"]):
            out += [f"No run was given any of the fixed budgets {list(opts['budgets'])}: give "
                    "`budgets=[...]` within the runs' budget for those columns.", ""]
        failed = [r for row in grp for r in row.runs if r.failed]
        if failed:
            out += ["### Failed runs", ""]
            out += [
                f"- {r.algorithm} seed {r.rec.get('seed')}: {r.rec.get('message')} (`{r.path.parent.name}`)"
                for r in failed
            ] + [""]
        for kind, path in figures.get(group, {}).items():
            out += [f"![{kind}: {group}]({path})", ""]
    return "\n".join(out).rstrip() + "\n"


def _tex_escape(s: str) -> str:
    s = s.replace("\\", r"\textbackslash{}")
    for a, b in (
        ("_", r"\_"),
        ("%", r"\%"),
        ("&", r"\&"),
        ("#", r"\#"),
        ("$", r"\$"),
        ("{", r"\{"),
        ("}", r"\}"),
        ("–", "--"),
    ):
        s = s.replace(a, b)
    return s.replace(r"\textbackslash\{\}", r"\textbackslash{}")


def _tex_table(head, body, caption: str, label: str) -> list[str]:
    cols = "l" + "r" * (len(head) - 1)
    lines = [
        r"\begin{table}[htbp]",
        r"\centering",
        r"\scriptsize",
        f"\\caption{{{_tex_escape(caption)}}}",
        f"\\label{{{label}}}",
        f"\\begin{{tabular}}{{{cols}}}",
        r"\toprule",
        " & ".join(_tex_escape(h) for h in head) + r" \\",
        r"\midrule",
    ]
    lines += [" & ".join(_tex_escape(c) for c in row) + r" \\" for row in body]
    return lines + [r"\bottomrule", r"\end{tabular}", r"\end{table}", ""]


def render_tex(rows: list[Row], opts) -> str:
    tol = float(opts["success_tol"])
    out = ["% Written by python -m benchmark.report; needs \\usepackage{booktabs}.", ""]
    for group in sorted({r.group for r in rows}):
        grp = [r for r in rows if r.group == group]
        slug = _slug(group)
        out += _tex_table(
            *_accuracy_table(grp, grp[0].parameters, tol),
            caption=f"{group}: median signed relative error [interquartile range] per parameter, "
            f"success rate (every parameter within {100 * tol:g} %), median cost, optimiser time and run time.",
            label=f"tab:{slug}-accuracy",
        )
        out += _tex_table(
            *_budget_table(grp, opts["budgets"]),
            caption=f"{group}: fixed target ({_target_text(opts)}) and median best cost at fixed "
            f"budgets (evaluations).",
            label=f"tab:{slug}-budget",
        )
    return "\n".join(out)
