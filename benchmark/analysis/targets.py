"""Per problem and optimiser: accuracy quantiles, success rate, expected running time to a target
(ERT) and the data of the fixed-target ECDFs; who wins at which budget."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from benchmark.analysis.fmt import _g, _pct
from benchmark.analysis.runs import ECDF_FINEST, ECDF_TARGETS, NEGLIGIBLE, Run


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


def instance_targets(fstar: float, first_costs) -> Instance:
    """The target scale of an instance whose best-known cost is ``fstar``, given the runs' first
    costs: precisions are relative to ``|f*|``, or to ``NEGLIGIBLE`` times the cost range
    (median first cost - f*) when f* is ~0 (noise-free data, exact model)."""
    firsts = [float(c) for c in first_costs if math.isfinite(c)]
    span = abs(quantile(firsts, 0.5) - fstar) if firsts and math.isfinite(fstar) else math.nan
    span = span if span > 0 and math.isfinite(span) else 1.0
    scale = max(abs(fstar), NEGLIGIBLE * span) if math.isfinite(fstar) else span
    return Instance(best=fstar, scale=scale, span=span)


def instances(runs: list[Run]) -> dict[tuple[str, str], Instance]:
    out = {}
    for key in sorted({(r.group, r.instance) for r in runs}):
        sel = [r for r in runs if (r.group, r.instance) == key]
        fstar = min((r.final_cost for r in sel), default=math.inf)
        out[key] = instance_targets(fstar, [r.best[0] for r in sel if len(r.best)])
    return out


def ert(hits, totals) -> float:
    """Expected running time (COCO): the evaluations all runs spent until they reached the target
    (``hits``, inf when never) or stopped (``totals``), over the number that reached it."""
    hits = np.asarray(hits, float)
    reached = np.isfinite(hits)
    spent = float(np.sum(np.where(reached, hits, np.asarray(totals, float))))
    return spent / int(reached.sum()) if reached.any() else math.inf


def ecdf(hits, grid) -> np.ndarray:
    """Fraction of (run, target) pairs reached within each budget of ``grid`` (``hits``: the
    evaluations each pair needed, inf when never), as COCO and IOHanalyzer draw runtime ECDFs."""
    hits = np.sort(np.asarray(hits, float).ravel())
    if not len(hits):
        return np.zeros(len(grid))
    return np.searchsorted(hits, np.asarray(grid, float), side="right") / len(hits)


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
    # the whole run (set-up, search, polish, uncertainty, review) and the optimiser's search alone
    for key, name in (("wall_time_median_s", "wall_time_s"), ("optimizer_time_median_s", "wall_time_optimizer_s")):
        v[key] = quantile([float(r.rec[name]) for r in sel
                           if r.rec.get(name) is not None and math.isfinite(float(r.rec[name]))], 0.5)
    # fixed target
    hits = [r.evals_to(_target(r, inst, opts)) for r in sel]
    reached = [h for h in hits if math.isfinite(h)]
    v["target_reached"] = len(reached)
    v["evals_to_target_median"] = quantile(reached, 0.5)
    v["ert"] = ert(hits, [r.total_evals for r in sel])
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
