"""The runs of a sweep: every ``result.json`` under a folder, with labels for what varies
between them (optimiser, seed, overrides), and the options of the summary."""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from benchmark.core.mappings import flatten

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
    flats = [{k: json.dumps(v, sort_keys=True) for k, v in flatten(r.rec.get("config") or {}).items()}
             for r in runs]
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
