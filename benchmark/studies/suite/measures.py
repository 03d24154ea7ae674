"""The suite's measures, as COCO and IOHprofiler define them, computed from the runs' own files.

* **Targets**, per instance: ``f* + p s`` for the precisions ``p`` of :data:`PRECISIONS` (10^2 down
  to 10^-5, five per decade), ``s = |f*|`` (or 1e-6 of the cost range when f* is ~0:
  :func:`benchmark.analysis.targets.instance_targets`). A run **reaches f*** when its best cost
  is within :data:`REACHED` (1e-3) of it.
* **Runtime ECDF** per optimiser: the fraction of (run, target) pairs whose target the run reached
  within a number of evaluations, pooled over all instances or over the instances of one group.
* **ERT** (COCO's expected running time) at a precision: the evaluations all runs spent until they
  reached the target or stopped, over the number that reached it; pooled over instances it is
  the expected cost of solving an instance drawn at random, restarts included.
* **Success**: every parameter of :data:`SUCCESS_PARAMETERS` within 2 % of the truth, or, on an
  instance with model error, of the best-known fit (the point at f*).
* **Wall time**: the harness's ``wall_time_s`` of each run.

A run's cost is its history's best (the optimiser's and the polish's evaluations: what the
budget counts), not ``result.json``'s ``cost``, which may include a nuisance estimated after them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmark.analysis.runs import Run, load_runs
from benchmark.analysis.targets import Instance, ecdf, ert, instance_targets, quantile

PRECISIONS = np.logspace(2, -5, 36)
#: the groups the measures are broken down by (``instances.groups``)
GROUPS = ("problem", "size", "pole pairs", "experiment", "noise", "model error", "source")
REACHED = 1e-3
SUCCESS_TOL = 0.02
#: parameters scored for success; None: every searched parameter
SUCCESS_PARAMETERS = {"timedomain": ("Rs", "Ls", "Le", "Rr", "J"), "admittance": None}


@dataclass
class SuiteRun:
    """One run as the measures see it."""

    instance: str
    label: str
    seed: int
    run: Run
    cost: float
    status: str
    message: str
    wall: float
    doc: dict = field(default_factory=dict)

    @property
    def evals(self) -> np.ndarray:
        return self.run.evals

    @property
    def total(self) -> int:
        return max(self.run.total_evals, int(self.run.evals[-1]) if len(self.run.evals) else 0)

    def evals_to(self, target: float) -> float:
        return self.run.evals_to(target)


@dataclass
class InstanceResult:
    """An instance with its f*, target scale, reference point for success and its runs."""

    name: str
    doc: dict
    target: Instance
    reference: dict | None
    runs: list[SuiteRun] = field(default_factory=list)

    def precision(self, cost: float) -> float:
        return max(cost - self.target.best, 0.0) / self.target.scale

    def targets(self) -> np.ndarray:
        return self.target.best + PRECISIONS * self.target.scale

    def reached(self, r: SuiteRun, p: float = REACHED) -> bool:
        return r.cost <= self.target.best + p * self.target.scale

    def success(self, r: SuiteRun) -> bool | None:
        est = r.run.rec.get("estimate") or {}
        return parameters_within(est, self.reference, self.doc["problem"], r.run.rec.get("parameter_names"))


def parameters_within(est: dict, ref: dict | None, problem: str, names=None, tol: float = SUCCESS_TOL) -> bool | None:
    """Every scored parameter of ``est`` within ``tol`` of ``ref`` (None without a reference)."""
    if not ref or not est:
        return None if not ref else False
    keys = SUCCESS_PARAMETERS.get(problem) or names or list(ref)
    keys = [k for k in keys if k in ref and ref[k] != 0]
    return all(k in est and abs(est[k] / ref[k] - 1.0) <= tol for k in keys)


def label_of(rec: dict) -> str:
    polish = bool((rec.get("config") or {}).get("polish"))
    return str(rec["optimizer"]) + ("+polish" if polish else "")


def data_path_of(rec: dict) -> str:
    return str(Path(str(((rec.get("config") or {}).get("data") or {}).get("path", "?"))).resolve())


def group_keys(results) -> list[str]:
    """The group keys every instance has: the suite's (:data:`GROUPS`) first, then a user's own."""
    keys = [k for ir in results.values() for k in ir.doc.get("groups", {})]
    common = [k for k in dict.fromkeys(keys) if all(k in ir.doc.get("groups", {}) for ir in results.values())]
    return [k for k in GROUPS if k in common] + [k for k in common if k not in GROUPS]


def in_group(key: str, value: str):
    """The selector of the instances whose label in group ``key`` is ``value``."""
    def select(ir) -> bool:
        return ir.doc["groups"].get(key) == value
    return select


def collect(runs_dir: Path, docs: dict[str, dict], fstars: dict[str, dict]) -> dict[str, InstanceResult]:
    """Every run under ``runs_dir`` attached to its instance (``docs``: instance documents by their
    data folder's resolved path; ``fstars``: ``fstar.json`` by instance name, or {} where f* is the
    best cost any run found)."""
    by: dict[str, list[SuiteRun]] = {}
    for r in load_runs(Path(runs_dir)):
        doc = docs.get(data_path_of(r.rec))
        if doc is None:
            continue
        name = doc["name"]
        cost = float(r.best.min()) if len(r.best) else math.inf
        by.setdefault(name, []).append(SuiteRun(
            instance=name, label=label_of(r.rec), seed=int(r.rec.get("seed", 0)), run=r, cost=cost,
            status=str(r.rec.get("status")), message=str(r.rec.get("message") or ""),
            wall=float(r.rec.get("wall_time_s") or math.nan), doc=doc))
    out = {}
    for name, runs in sorted(by.items()):
        fs = fstars.get(name) or {}
        best_run = min(r.cost for r in runs)
        fstar = min(float(fs.get("fstar", math.inf)), best_run)
        firsts = [float(r.run.best[0]) for r in runs if len(r.run.best)]
        ref = None
        doc = runs[0].doc
        if doc.get("model_error") or not (runs[0].run.rec.get("truth")):
            ref = fs.get("estimate")
        else:
            ref = runs[0].run.rec.get("truth")
        out[name] = InstanceResult(name=name, doc=doc, target=instance_targets(fstar, firsts), reference=ref,
                                   runs=runs)
    return out


def labels(results: dict[str, InstanceResult]) -> list[str]:
    return sorted({r.label for ir in results.values() for r in ir.runs})


def pairs(results, label: str, select=None) -> tuple[np.ndarray, int]:
    """Evaluations each (run, target) pair of ``label`` needed (inf: never), and the run count."""
    hits, n = [], 0
    for ir in results.values():
        if select is not None and not select(ir):
            continue
        targets = ir.targets()
        for r in ir.runs:
            if r.label == label:
                n += 1
                hits.extend(r.evals_to(t) for t in targets)
    return np.asarray(hits, float), n


def ecdf_curve(results, label: str, grid, select=None) -> tuple[np.ndarray, int]:
    hits, n = pairs(results, label, select)
    return ecdf(hits, grid), n


def ert_at(results, label: str, p: float, select=None) -> float:
    hits, totals = [], []
    for ir in results.values():
        if select is not None and not select(ir):
            continue
        t = ir.target.best + p * ir.target.scale
        for r in ir.runs:
            if r.label == label:
                hits.append(r.evals_to(t))
                totals.append(r.total)
    return ert(hits, totals) if hits else math.nan


def summary(results, label: str, select=None) -> dict:
    """One optimiser's line: runs, failed, share of runs reaching f*, instances solved (a run
    reached f*) and all-seeds instances, ERT at 1e-1 and 1e-3, success, median wall time."""
    sel = [ir for ir in results.values() if select is None or select(ir)]
    runs = [(ir, r) for ir in sel for r in ir.runs if r.label == label]
    if not runs:
        return {}
    reached = [ir.reached(r) for ir, r in runs]
    per_inst = {}
    for ir, r in runs:
        per_inst.setdefault(ir.name, []).append(ir.reached(r))
    succ = [ir.success(r) for ir, r in runs]
    scored = [s for s in succ if s is not None]
    return {"optimizer": label, "instances": len(per_inst), "runs": len(runs),
            "failed": sum(r.status == "failed" for _, r in runs),
            "reached_share": float(np.mean(reached)),
            "instances_solved": sum(any(v) for v in per_inst.values()),
            "instances_all_seeds": sum(all(v) for v in per_inst.values()),
            "ert_1e-1": ert_at(results, label, 1e-1, select), "ert_1e-3": ert_at(results, label, REACHED, select),
            "success_share": float(np.mean(scored)) if scored else math.nan,
            "wall_median_s": quantile([r.wall for _, r in runs], 0.5),
            "evaluations_median": quantile([float(r.total) for _, r in runs], 0.5)}


def hardest(results, n: int = 10) -> list[tuple[InstanceResult, float]]:
    """The ``n`` instances where the fewest runs (of every optimiser) reached f*."""
    share = {k: float(np.mean([ir.reached(r) for r in ir.runs])) for k, ir in results.items()}
    order = sorted(results, key=lambda k: (share[k], k))
    return [(results[k], share[k]) for k in order[:n]]


def best_precision(ir: InstanceResult, label: str) -> float:
    """Median over seeds of the precision ``(cost - f*) / s`` the optimiser reached."""
    return quantile([ir.precision(r.cost) for r in ir.runs if r.label == label], 0.5)


def default_check(results, label: str = "multistart") -> dict:
    """How the default pipeline did: runs and instances at f*, the misses (with whether their
    message or the result's warnings warn), and how often a ``converged`` claim (confirmed minimum) sat above f*."""
    runs = [(ir, r) for ir in results.values() for r in ir.runs if r.label == label]
    if not runs:
        return {}
    claims = [(ir, r) for ir, r in runs if r.message.startswith("converged")]
    wrong = [(ir, r) for ir, r in claims if not ir.reached(r)]
    misses = [(ir, r) for ir, r in runs if not ir.reached(r)]
    inst = {}
    for ir, r in runs:
        inst.setdefault(ir.name, []).append(ir.reached(r))
    return {"label": label, "runs": len(runs), "runs_reached": sum(ir.reached(r) for ir, r in runs),
            "instances": len(inst), "instances_all_seeds": sum(all(v) for v in inst.values()),
            "converged_claims": len(claims), "converged_above_fstar": len(wrong),
            "misses": [{"instance": ir.name, "seed": r.seed, "precision": ir.precision(r.cost),
                        "warned": not r.message.startswith("converged") or bool(r.run.rec.get("warnings")),
                        "message": r.message[:240]}
                       for ir, r in misses]}
