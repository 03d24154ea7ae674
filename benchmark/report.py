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

import json
import math
import re
import shutil
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from benchmark.data.tables import write_text_atomic

DEFAULTS = {
    "dir": None,
    "out": None,
    "target_rel": 0.01,
    "target_abs": None,
    "budgets": [1000, 5000, 20000, 60000],
    "success_tol": 0.01,
    "figures": True,
    "ioh": True,
}
#: Configuration keys that belong to the optimiser or the run, not to the problem.
RUN_KEYS = ("optimizer", "seed", "budget", "polish", "polish_budget", "time_limit_s", "progress", "figures")
INSTANCE_KEY = "noise.seed"
#: f* below this fraction of the cost range (median first cost - f*) counts as zero: target
#: precisions are then relative to NEGLIGIBLE * range instead of |f*|.
NEGLIGIBLE = 1e-6
#: ECDF targets: f* + D, with 31 precisions D log-spaced from the cost range (median first
#: cost - f*) down to ECDF_FINEST * |f*|.
ECDF_TARGETS = 31
ECDF_FINEST = 1e-4
IOH_DAT_HEADER = "evaluations raw_y"
IOH_FORMAT_VERSION = "0.3.22"  # the IOHexperimenter Analyzer-logger format written here


class ReportError(Exception):
    """A bad argument or an empty folder: reported in one line, exit status 2."""


# -- loading ------------------------------------------------------------------------------------
@dataclass
class Run:
    """One result.json with its convergence history (best cost after ``evals[k]`` evaluations)."""

    path: Path
    rec: dict
    evals: np.ndarray
    best: np.ndarray
    group: str = ""
    instance: str = ""
    algorithm: str = ""

    @property
    def status(self) -> str:
        return str(self.rec.get("status"))

    @property
    def failed(self) -> bool:
        return self.status == "failed"

    @property
    def total_evals(self) -> int:
        return int(self.rec.get("evaluations") or 0)

    @property
    def final_cost(self) -> float:
        c = self.rec.get("cost")
        c = math.inf if c is None else float(c)
        return min(c, float(self.best.min())) if len(self.best) else c

    def best_at(self, e: float) -> float:
        """Best cost after ``e`` evaluations (inf before the first finite one); NaN when the
        run was not given ``e`` evaluations (it spent its budget or failed before)."""
        if e > self.total_evals and self.status != "converged":
            return math.nan
        k = int(np.searchsorted(self.evals, e, side="right")) - 1
        return float(self.best[k]) if k >= 0 else math.inf

    def evals_to(self, target: float) -> float:
        """Evaluations to reach ``target`` (inf if never)."""
        hit = np.nonzero(self.best <= target)[0]
        return float(self.evals[hit[0]]) if len(hit) else math.inf


def load_runs(root: Path) -> list[Run]:
    runs = []
    for path in sorted(root.rglob("result.json")):
        try:
            rec = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            print(f"warning: {path}: not readable ({exc}); skipped", file=sys.stderr)
            continue
        if not isinstance(rec, dict) or "problem" not in rec or "optimizer" not in rec:
            print(f"warning: {path}: not a result.json of the harness; skipped", file=sys.stderr)
            continue
        evals, best = np.zeros(0, int), np.zeros(0)
        hist = path.parent / str(rec.get("history") or "history.csv")
        if hist.is_file():
            df = pd.read_csv(hist)
            if len(df):
                order = np.argsort(df["evaluations"].to_numpy(), kind="stable")
                evals = df["evaluations"].to_numpy(dtype=np.int64)[order]
                best = np.minimum.accumulate(df["best_cost"].to_numpy(dtype=float)[order])
        runs.append(Run(path=path, rec=rec, evals=evals, best=best))
    return runs


def _flatten(d, prefix="") -> dict[str, str]:
    out = {}
    if isinstance(d, dict):
        for k, v in d.items():
            out.update(_flatten(v, f"{prefix}{k}."))
    else:
        out[prefix[:-1]] = json.dumps(d, sort_keys=True)
    return out


def _varying(flats: list[dict[str, str]], keep) -> list[str]:
    keys = sorted({k for f in flats for k in f if keep(k)})
    return [k for k in keys if len({f.get(k) for f in flats}) > 1]


def _is_run_key(k: str) -> bool:
    return k.split(".")[0] in RUN_KEYS or k == INSTANCE_KEY


def _short(v: str) -> str:
    v = json.loads(v)
    return "null" if v is None else str(v).lower() if isinstance(v, bool) else str(v)


def label_runs(runs: list[Run]) -> None:
    """Set each run's problem group, instance and optimiser label (see the module docstring)."""
    flats = [_flatten(r.rec.get("config") or {}) for r in runs]
    by_problem: dict[str, list[int]] = {}
    for i, r in enumerate(runs):
        by_problem.setdefault(str(r.rec["problem"]), []).append(i)
    for problem, idx in by_problem.items():
        keys = _varying([flats[i] for i in idx], lambda k: not _is_run_key(k))
        for i in idx:
            extra = ", ".join(f"{k}={_short(flats[i][k])}" for k in keys if k in flats[i])
            runs[i].group = f"{problem} ({extra})" if extra else problem
            inst = flats[i].get(INSTANCE_KEY)
            runs[i].instance = _short(inst) if inst is not None else "0"
    by_alg: dict[tuple[str, str], list[int]] = {}
    for i, r in enumerate(runs):
        polish = bool((r.rec.get("config") or {}).get("polish")) or bool(r.rec.get("polish"))
        base = str(r.rec["optimizer"]) + ("+polish" if polish else "")
        by_alg.setdefault((r.group, base), []).append(i)
    for (_, base), idx in by_alg.items():
        keys = _varying(
            [flats[i] for i in idx],
            lambda k: (
                k.split(".")[0] in ("optimizer", "budget", "polish_budget", "time_limit_s") and k != "optimizer.name"
            ),
        )
        for i in idx:
            extra = ", ".join(
                f"{k.removeprefix('optimizer.plugin.')}={_short(flats[i][k])}" for k in keys if k in flats[i]
            )
            runs[i].algorithm = f"{base} ({extra})" if extra else base


# -- statistics ----------------------------------------------------------------------------------
def quantile(values, q: float) -> float:
    """Linear-interpolation quantile (numpy's default) that ignores NaN and keeps +inf exact
    (an interpolation that touches +inf is +inf). NaN when there is no value."""
    x = np.sort(np.asarray([v for v in values if not (isinstance(v, float) and math.isnan(v))], float))
    if not len(x):
        return math.nan
    pos = q * (len(x) - 1)
    lo, hi = int(math.floor(pos)), int(math.ceil(pos))
    if math.isinf(x[lo]) or math.isinf(x[hi]):
        return float(x[hi]) if math.isinf(x[hi]) else float(x[lo])
    return float(x[lo] + (pos - lo) * (x[hi] - x[lo]))


@dataclass
class Instance:
    best: float  # f*: the best cost of any run on this instance
    scale: float  # what target precisions are relative to (|f*|, see NEGLIGIBLE)
    span: float = 1.0  # median first cost - f*

    def target(self, precision: float) -> float:
        return self.best + precision * self.scale

    def ecdf_targets(self) -> np.ndarray:
        finest = ECDF_FINEST * self.scale
        top = self.span if self.span > finest else 1e6 * finest
        return self.best + np.geomspace(top, finest, ECDF_TARGETS)


def instances(runs: list[Run]) -> dict[tuple[str, str], Instance]:
    out = {}
    for key in sorted({(r.group, r.instance) for r in runs}):
        sel = [r for r in runs if (r.group, r.instance) == key]
        fstar = min((r.final_cost for r in sel), default=math.inf)
        firsts = [float(r.best[0]) for r in sel if len(r.best) and math.isfinite(r.best[0])]
        span = abs(quantile(firsts, 0.5) - fstar) if firsts and math.isfinite(fstar) else math.nan
        span = span if span > 0 and math.isfinite(span) else 1.0
        # a fit that reaches ~0 (noise-free data, exact model): precisions relative to the range
        scale = max(abs(fstar), NEGLIGIBLE * span) if math.isfinite(fstar) else span
        out[key] = Instance(best=fstar, scale=scale, span=span)
    return out


@dataclass
class Row:
    """One problem x optimiser line of the summary."""

    group: str
    algorithm: str
    runs: list[Run]
    parameters: list[str]
    values: dict = field(default_factory=dict)


def summarize(runs: list[Run], opts: dict) -> tuple[list[Row], dict]:
    """Statistics per problem and optimiser (see the module docstring); also returns the
    instances (best cost and target scale) used for the targets."""
    inst = instances(runs)
    rows = []
    for group in sorted({r.group for r in runs}):
        grp = [r for r in runs if r.group == group]
        params: list[str] = []
        for r in grp:
            for k in r.rec.get("rel_error") or {}:
                if k not in params:
                    params.append(k)
        for alg in sorted({r.algorithm for r in grp}):
            sel = [r for r in grp if r.algorithm == alg]
            rows.append(_row(group, alg, sel, params, inst, opts))
    return rows, inst


def _target(r: Run, inst, opts) -> float:
    i = inst[(r.group, r.instance)]
    if opts.get("target_abs") is not None:
        return i.best + float(opts["target_abs"])
    return i.target(float(opts["target_rel"]))


def _row(group, alg, sel: list[Run], params, inst, opts) -> Row:
    v: dict = {}
    ok = [r for r in sel if not r.failed]
    v["runs"] = len(sel)
    v["failed"] = len(sel) - len(ok)
    v["optimizer"] = str(sel[0].rec["optimizer"])
    v["polish"] = "+polish" in alg
    v["budget"] = "/".join(str(b) for b in sorted({int(r.rec.get("budget") or 0) for r in sel}))
    v["instances"] = len({r.instance for r in sel})
    scored = [r for r in ok if r.rec.get("rel_error")]
    for p in params:
        e = [float(r.rec["rel_error"][p]) for r in scored if p in r.rec["rel_error"]]
        q25, med, q75 = quantile(e, 0.25), quantile(e, 0.5), quantile(e, 0.75)
        v[f"{p}_median"], v[f"{p}_q25"], v[f"{p}_q75"] = med, q25, q75
        v[f"{p}_iqr"] = q75 - q25
        v[f"{p}_abs_median"] = quantile([abs(x) for x in e], 0.5)
    tol = float(opts["success_tol"])
    with_truth = [r for r in sel if r.rec.get("rel_error")]
    if with_truth or not any(r.rec.get("truth") is None for r in sel):
        succ = [
            r
            for r in sel
            if not r.failed
            and r.rec.get("rel_error")
            and all(abs(float(x)) <= tol for x in r.rec["rel_error"].values())
        ]
        v["success_n"] = len(succ)
        v["success_rate"] = len(succ) / len(sel)
        v["max_abs_error_median"] = quantile(
            [max(abs(float(x)) for x in r.rec["rel_error"].values()) for r in scored], 0.5
        )
    else:
        v["success_n"], v["success_rate"], v["max_abs_error_median"] = None, math.nan, math.nan
    v["cost_median"] = quantile([r.final_cost for r in sel if not r.failed], 0.5)
    v["cost_best"] = min((r.final_cost for r in sel), default=math.inf)
    v["evaluations_median"] = quantile([float(r.total_evals) for r in sel], 0.5)
    v["wall_time_median_s"] = quantile(
        [
            float(r.rec["wall_time_s"])
            for r in sel
            if r.rec.get("wall_time_s") is not None and math.isfinite(float(r.rec["wall_time_s"]))
        ],
        0.5,
    )
    # fixed target
    hits = [r.evals_to(_target(r, inst, opts)) for r in sel]
    reached = [h for h in hits if math.isfinite(h)]
    v["target_reached"] = len(reached)
    v["evals_to_target_median"] = quantile(reached, 0.5)
    spent = sum(h if math.isfinite(h) else r.total_evals for h, r in zip(hits, sel, strict=True))
    v["ert"] = spent / len(reached) if reached else math.inf
    # fixed budgets
    for b in opts["budgets"]:
        at = [r.best_at(b) for r in sel]
        have = [c for c in at if not math.isnan(c)]
        v[f"cost_at_{b}_median"] = quantile(have, 0.5)
        v[f"cost_at_{b}_n"] = len(have)
    return Row(group=group, algorithm=alg, runs=sel, parameters=list(params), values=v)


def winners(rows: list[Row], opts: dict) -> dict[str, list[str]]:
    """Plain sentences per problem: who wins at each fixed budget, at the fixed target, and
    on parameter accuracy."""
    out: dict[str, list[str]] = {}
    for group in sorted({r.group for r in rows}):
        grp = [r for r in rows if r.group == group]
        lines = []
        for b in opts["budgets"]:
            full = [
                r
                for r in grp
                if r.values[f"cost_at_{b}_n"] == r.values["runs"] and math.isfinite(r.values[f"cost_at_{b}_median"])
            ]
            if not full:
                continue
            lines.append(f"at {b} evaluations: " + _ranking(full, f"cost_at_{b}_median", "median best cost"))
        fin = [r for r in grp if math.isfinite(r.values["cost_median"])]
        if fin:
            lines.append("whole budget (with polish where on): " + _ranking(fin, "cost_median", "median final cost"))
        reach = sorted([r for r in grp if r.values["target_reached"]], key=lambda r: r.values["ert"])
        if reach:
            lines.append(
                f"fixed target: **{reach[0].algorithm}** (ERT {_g(reach[0].values['ert'])} evaluations, "
                f"{reach[0].values['target_reached']}/{reach[0].values['runs']} runs reached it)"
            )
        acc = [r for r in grp if r.values.get("success_n") is not None]
        if acc:
            acc.sort(key=lambda r: (-r.values["success_rate"], _nan_last(r.values["max_abs_error_median"])))
            lines.append(
                f"parameter accuracy: **{acc[0].algorithm}** ({acc[0].values['success_n']}/"
                f"{acc[0].values['runs']} runs with every parameter within "
                f"{100 * float(opts['success_tol']):g} %, median largest error "
                f"{_pct(acc[0].values['max_abs_error_median'])})"
            )
        out[group] = lines
    return out


def _ranking(rows: list[Row], key: str, what: str) -> str:
    """The sentence '**best** (what X, tied with ...; next other, Y)' over rows sorted by values[key];
    values within 1e-6 (relative) of the best are ties (the same optimum found by other methods)."""
    rows = sorted(rows, key=lambda r: r.values[key])
    best = rows[0].values[key]

    def same(x):
        return abs(x - best) <= 1e-6 * max(abs(x), abs(best))

    tied = [r.algorithm for r in rows[1:] if same(r.values[key])]
    rest = [r for r in rows[1:] if not same(r.values[key])]
    s = f"**{rows[0].algorithm}** ({what} {_g(best)}"
    if tied:
        s += ", tied with " + ", ".join(tied)
    if rest:
        s += f"; next {rest[0].algorithm}, {_g(rest[0].values[key])}"
    return s + ")"


def _nan_last(x):
    return math.inf if x is None or math.isnan(x) else x


# -- formatting -----------------------------------------------------------------------------------
def _g(x, digits=4) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "inf"
    return f"{x:.{digits}g}"


def _pct(x) -> str:
    return "–" if x is None or math.isnan(x) else f"{100 * x:.3g} %"


def _signed_pct(x) -> str:
    return "–" if x is None or math.isnan(x) else f"{100 * x:+.3g} %"


def _slug(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", s).strip("_") or "problem"


def write_csv(rows: list[Row], path: Path) -> pd.DataFrame:
    recs = [{"problem": r.group, "optimizer_label": r.algorithm, **r.values} for r in rows]
    df = pd.DataFrame(recs)
    write_text_atomic(path, df.to_csv(index=False, float_format="%.10g"))
    return df


def _accuracy_table(grp: list[Row], params: list[str], tol: float) -> tuple[list[str], list[list[str]]]:
    head = (
        ["optimizer", "runs", "failed", f"success (all within {100 * tol:g} %)"]
        + params
        + ["median cost", "median wall time (s)"]
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
        cells += [_g(v["cost_median"]), _g(v["wall_time_median_s"], 3)]
        body.append(cells)
    return head, body


def _budget_table(grp: list[Row], budgets) -> tuple[list[str], list[list[str]]]:
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
        f"evaluations over the runs given at least B (a count n/N shows when fewer). See "
        f"`benchmark/report.py` for the definitions.",
        "",
    ]
    wins = winners(rows, opts)
    for group in sorted({r.group for r in rows}):
        grp = [r for r in rows if r.group == group]
        params = grp[0].parameters
        keys = sorted(k for k in inst if k[0] == group)
        fstar = ", ".join(f"{_g(inst[k].best, 8)}" + (f" (noise.seed {k[1]})" if len(keys) > 1 else "") for k in keys)
        out += [f"## {group}", "", f"Best cost found (f*): {fstar}.", ""]
        if wins.get(group):
            out += ["Who wins:", ""] + [f"- {line}" for line in wins[group]] + [""]
        out += ["### Parameter errors", ""] + _md_table(*_accuracy_table(grp, params, tol)) + [""]
        out += ["### Fixed target and fixed budget", ""] + _md_table(*_budget_table(grp, opts["budgets"])) + [""]
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
            f"success rate (every parameter within {100 * tol:g} %), median cost and wall time.",
            label=f"tab:{slug}-accuracy",
        )
        out += _tex_table(
            *_budget_table(grp, opts["budgets"]),
            caption=f"{group}: fixed target ({_target_text(opts)}) and median best cost at fixed "
            f"budgets (evaluations).",
            label=f"tab:{slug}-budget",
        )
    return "\n".join(out)


# -- figures --------------------------------------------------------------------------------------
def _grid(runs: list[Run], n=400) -> np.ndarray:
    """Evaluation counts at which curves are drawn: n log-spaced whole numbers up to the longest run."""
    top = max([r.total_evals for r in runs] + [int(r.evals[-1]) for r in runs if len(r.evals)] + [1])
    return np.unique(np.round(np.geomspace(1, top, n)))


def write_figures(rows: list[Row], inst, out: Path) -> dict[str, dict[str, str]]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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
        fig, ax = plt.subplots(figsize=(9, 4.5))
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
            ax.axhline(fstars[0], color="k", ls=":", lw=0.8, label="best cost found (f*)")
        ax.set_xscale("log")
        ax.set_yscale("log" if positive else "symlog")
        ax.set_xlabel("evaluations (counted by the harness)")
        ax.set_ylabel(f"best cost so far (cost units of {grp[0].runs[0].rec['problem']})")
        ax.set_title(f"{group}: median and quartiles over runs", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))  # outside: curves stay visible
        fig.tight_layout()
        for ext in ("png", "svg"):
            fig.savefig(figdir / f"convergence_{slug}.{ext}", dpi=130)
        plt.close(fig)
        made[group]["convergence"] = f"figures/convergence_{slug}.png"

        # ECDF of (run, target) pairs
        fig, ax = plt.subplots(figsize=(9, 4.5))
        for row in grp:
            hits = np.array([r.evals_to(t) for r in row.runs for t in inst[(r.group, r.instance)].ecdf_targets()])
            frac = np.array([np.mean(hits <= e) for e in grid])
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
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))  # outside: curves stay visible
        fig.tight_layout()
        for ext in ("png", "svg"):
            fig.savefig(figdir / f"ecdf_{slug}.{ext}", dpi=130)
        plt.close(fig)
        made[group]["ecdf"] = f"figures/ecdf_{slug}.png"
    return made


# -- IOHprofiler export ---------------------------------------------------------------------------
def write_ioh(rows: list[Row], out: Path) -> Path:
    """Runs in the format of IOHexperimenter's Analyzer logger (what IOHanalyzer loads): per
    optimiser a folder with ``IOHprofiler_f<id>_<problem>.json`` (meta-data: function, algorithm,
    one scenario per dimension with each run's instance, evaluations and best point) and
    ``data_f<id>_<problem>/IOHprofiler_f<id>_DIM<n>.dat`` (per run a header line
    ``evaluations raw_y``, then one line per improvement of the best cost and one at the last
    evaluation). Minimisation. Zipped as ``ioh.zip`` for IOHanalyzer's upload page.

    Readers (IOHanalyzer, iohinspector) start a new run at the line of evaluation 1, which
    IOHexperimenter always writes. The harness's history has one row per batch that improved
    the best cost, at the evaluation that did it, so when the first row is later than 1 a line
    ``1 <first best cost>`` is written: optimistic by less than one population."""
    root = out / "ioh"
    if root.exists():
        shutil.rmtree(root)
    groups = sorted({r.group for r in rows})
    fids = {g: k + 1 for k, g in enumerate(groups)}
    for row in rows:
        runs = [r for r in row.runs if len(r.evals)]
        if not runs:
            continue
        fid, fname = fids[row.group], _slug(row.group)
        folder = root / _slug(row.algorithm)
        scenarios = []
        for dim in sorted({len(r.rec.get("parameter_names") or []) for r in runs}):
            rel = f"data_f{fid}_{fname}/IOHprofiler_f{fid}_DIM{dim}.dat"
            lines, meta = [], []
            for r in runs:
                if len(r.rec.get("parameter_names") or []) != dim:
                    continue
                lines.append(IOH_DAT_HEADER)
                if int(r.evals[0]) > 1:
                    # readers split runs at evaluation 1; the history holds the best of each batch
                    lines.append(f"1 {r.best[0]:.10g}")
                for e, c in zip(r.evals, r.best, strict=True):
                    lines.append(f"{int(e)} {c:.10g}")
                last = max(r.total_evals, int(r.evals[-1]))
                if last > int(r.evals[-1]):
                    lines.append(f"{last} {r.best[-1]:.10g}")
                k = int(np.argmin(r.best))
                x = [float(v) for v in (r.rec.get("searched") or {}).values()]
                meta.append(
                    {
                        "instance": _instance_id(r.instance),
                        "evals": last,
                        "best": {"evals": int(r.evals[k]), "y": float(r.best[k]), "x": x},
                    }
                )
            (folder / rel).parent.mkdir(parents=True, exist_ok=True)
            (folder / rel).write_text("\n".join(lines) + "\n")
            scenarios.append({"dimension": dim, "path": rel, "runs": meta})
        budgets = sorted({int(r.rec.get("budget") or 0) for r in runs})
        doc = {
            "version": IOH_FORMAT_VERSION,
            "suite": "imbench",
            "function_id": fid,
            "function_name": fname,
            "maximization": False,
            "algorithm": {
                "name": row.algorithm,
                "info": f"imbench plugin {row.values['optimizer']}, budget {'/'.join(map(str, budgets))}",
            },
            "attributes": ["evaluations", "raw_y"],
            "scenarios": scenarios,
        }
        (folder / f"IOHprofiler_f{fid}_{fname}.json").write_text(json.dumps(doc, indent=1) + "\n")
    (root / "README.txt").write_text(
        "Runs exported by python -m benchmark.report in IOHexperimenter's Analyzer format "
        f"(version {IOH_FORMAT_VERSION}): load this folder, or ioh.zip, in IOHanalyzer.\n"
        "Function ids: " + "; ".join(f"f{fids[g]} = {g}" for g in groups) + ".\n"
        "Rows are the harness's history (one per improvement of the best cost) plus the last evaluation, "
        "so raw_y is the best cost so far; a first row at evaluation 1 carries the best cost of the first "
        "batch (readers split runs there). Instances are noise.seed + 1.\n"
    )
    shutil.make_archive(str(out / "ioh"), "zip", root_dir=root)
    return root


def _instance_id(instance: str) -> int:
    try:
        return int(float(instance)) + 1
    except ValueError:
        return 1


# -- entry point ----------------------------------------------------------------------------------
def parse_args(argv: Sequence[str]) -> dict:
    opts = dict(DEFAULTS)
    for a in argv:
        if "=" in a:
            key, val = a.split("=", 1)
            key = key.lstrip("+")
            if key not in DEFAULTS:
                raise ReportError(f"{key}: unknown argument; valid: {', '.join(DEFAULTS)}")
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


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except ReportError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
