"""The harness: builds the problem and the optimiser from the Hydra config, runs one
identification, scores it against the truth when known, and writes ``result.json``.

Everything is wired through ``hydra.utils.instantiate``: ``cfg.problem.setup`` builds the
problem, ``cfg.optimizer.plugin`` the optimiser. The harness counts evaluations (through
:class:`benchmark.problem.BudgetedProblem`), so every plugin is held to the same budget.
"""

from __future__ import annotations

import json
import math
import platform
import sys
import time
import traceback
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from benchmark.data.tables import write_table_atomic, write_text_atomic
from benchmark.errors import ConfigError, UserError
from benchmark.polish import polish_least_squares
from benchmark.problem import BudgetedProblem, OptimizeResult, Problem, Status, run_plugin

RECORDED_PACKAGES = ("numpy", "scipy", "numba", "pandas", "hydra-core", "deap", "pygad", "nlopt", "cma", "imbench")


@dataclass
class RunOutcome:
    problem: Problem
    result: OptimizeResult
    record: dict


def resolve_budget(cfg: DictConfig) -> int:
    budget = cfg.get("budget")
    if budget is None:
        budget = cfg.optimizer.get("default_budget")
        key = "optimizer.default_budget"
    else:
        key = "budget"
    if isinstance(budget, bool) or not isinstance(budget, int) or budget < 1:
        raise ConfigError(f"{key}: must be a positive whole number of evaluations, got {budget!r}")
    return budget


def validate_config(cfg: DictConfig) -> None:
    """Catch configuration mistakes before any work starts."""
    for key in ("problem", "optimizer", "motor"):
        if key not in cfg or cfg[key] is None:
            raise ConfigError(f"{key}: missing config group")
    if "plugin" not in cfg.optimizer or "_target_" not in cfg.optimizer.plugin:
        raise ConfigError("optimizer.plugin._target_: the optimiser config must name its plugin function")
    if "setup" not in cfg.problem:
        raise ConfigError("problem.setup._target_: the problem config must name its set-up function")
    seed = cfg.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"seed: must be a non-negative integer, got {seed!r}")
    resolve_budget(cfg)
    if cfg.get("polish"):
        pb = cfg.get("polish_budget")
        if isinstance(pb, bool) or not isinstance(pb, int) or pb < 1:
            raise ConfigError(f"polish_budget: must be a positive whole number, got {pb!r}")


def package_versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for name in RECORDED_PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            pass
    return out


def score(estimate: dict[str, float], truth: dict[str, float] | None) -> dict[str, float] | None:
    """Signed relative error of each estimated parameter with a known, non-zero truth."""
    if truth is None:
        return None
    out = {}
    for k, v in estimate.items():
        if k in truth and truth[k] != 0:
            out[k] = (v - truth[k]) / abs(truth[k])
    return out


def run(cfg: DictConfig, outdir: Path) -> RunOutcome:
    """One identification run, written to ``outdir``."""
    validate_config(cfg)
    budget = resolve_budget(cfg)
    seed = int(cfg.seed)
    t_start = time.perf_counter()
    problem: Problem = instantiate(cfg.problem.setup)(cfg)
    setup_time = time.perf_counter() - t_start
    plugin = instantiate(cfg.optimizer.plugin)
    name = str(cfg.optimizer.get("name", "optimizer"))

    budgeted = BudgetedProblem(problem, budget)
    try:
        result = run_plugin(plugin, budgeted, seed=seed, name=name)
    except UserError:
        raise
    except Exception as exc:  # a failing plugin is a failed run, recorded with its reason
        result = OptimizeResult(
            x=budgeted.best_x, fun=budgeted.best_cost, nfev=budgeted.nfev, nit=0, status=Status.FAILED,
            message=f"{type(exc).__name__}: {exc}", optimizer=name, seed=seed, wall_time_s=math.nan,
        )
        result_trace = traceback.format_exc()
    else:
        result_trace = None

    history = [(e, c, "optimizer") for e, c in zip(budgeted.history.evaluations, budgeted.history.best_cost,
                                                   strict=True)]
    polish_info = None
    x_best, f_best = result.x, result.fun
    if cfg.get("polish") and result.x is not None and problem.has_residuals:
        t0 = time.perf_counter()
        pol = polish_least_squares(problem, result.x, int(cfg.polish_budget))
        polish_info = {"evaluations": pol.nfev, "cost_before": result.fun, "cost_after": pol.best_cost,
                       "wall_time_s": time.perf_counter() - t0, "message": pol.message}
        history += [(result.nfev + e, c, "polish") for e, c in zip(pol.history.evaluations,
                                                                   pol.history.best_cost, strict=True)]
        if pol.best_x is not None and pol.best_cost <= f_best:
            x_best, f_best = pol.best_x, pol.best_cost
    elif cfg.get("polish") and not problem.has_residuals:
        polish_info = {"evaluations": 0, "message": f"problem {problem.name!r} has no residual vector"}
    wall = time.perf_counter() - t_start

    estimate = problem.estimate(x_best) if x_best is not None else None
    truth = problem.truth
    rel_error = score(estimate, truth) if estimate is not None else None
    write_table_atomic(outdir / "history.csv", {
        "evaluations": np.array([h[0] for h in history], dtype=int),
        "best_cost": np.array([h[1] for h in history], dtype=float),
        "phase": np.array([h[2] for h in history], dtype=object),
    }, float_format="%.10g")
    record = {
        "problem": problem.name,
        "optimizer": name,
        "seed": seed,
        "status": result.status.value,
        "message": result.message,
        "parameter_names": list(problem.parameter_names),
        "searched": None if x_best is None else dict(zip(problem.parameter_names, map(float, x_best),
                                                         strict=True)),
        "estimate": estimate,
        "truth": truth,
        "rel_error": rel_error,
        "cost": _finite_or_none(f_best),
        "cost_optimizer": _finite_or_none(result.fun),
        "evaluations": result.nfev + (polish_info or {}).get("evaluations", 0),
        "evaluations_optimizer": result.nfev,
        "budget": budget,
        "nit": result.nit,
        "polish": polish_info,
        "wall_time_s": wall,
        "wall_time_optimizer_s": result.wall_time_s,
        "setup_time_s": setup_time,
        "history": "history.csv",
        "bounds": {n: [float(lo), float(hi)] for n, lo, hi in zip(problem.parameter_names, problem.lower,
                                                                 problem.upper, strict=True)},
        "problem_info": problem.describe(),
        "config": OmegaConf.to_container(cfg, resolve=True),
        "versions": package_versions(),
        "command": " ".join(sys.argv),
    }
    if result_trace:
        record["traceback"] = result_trace
    write_text_atomic(outdir / "result.json", json.dumps(record, indent=2, default=_json_default) + "\n")
    return RunOutcome(problem=problem, result=result, record=record)


def _finite_or_none(x):
    return float(x) if x is not None and math.isfinite(x) else None


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    return str(o)


def format_table(record: dict) -> str:
    """The short table printed after a run: parameter, estimate, truth, error."""
    est, truth, err = record["estimate"] or {}, record["truth"] or {}, record["rel_error"] or {}
    lines = [f"{'parameter':<10}{'estimate':>14}{'truth':>14}{'error':>10}"]
    for k, v in est.items():
        t = f"{truth[k]:14.6g}" if k in truth else f"{'-':>14}"
        e = f"{100 * err[k]:+9.3f}%" if k in err else f"{'-':>10}"
        lines.append(f"{k:<10}{v:14.6g}{t}{e}")
    cost = record["cost"]
    lines.append(
        f"{record['problem']} / {record['optimizer']} seed {record['seed']}: status {record['status']}, "
        f"cost {cost if cost is None else f'{cost:.6g}'}, {record['evaluations']} evaluations, "
        f"{record['wall_time_s']:.2f} s"
    )
    if record["status"] == Status.FAILED.value:
        lines.append(f"failed: {record['message']}")
    return "\n".join(lines)
