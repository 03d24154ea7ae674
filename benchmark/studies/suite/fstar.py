"""The best-known cost f* of an instance, and how it was found.

Candidates, all scored by the problem's own cost (eq. 15 for the time domain, the admittance
problem's mean squared misfit) with no nuisance estimated (what the optimisers minimise):

1. ``truth``: the cost at the true parameters (clipped into the bounds);
2. ``truth_polished``: least squares from there (:func:`benchmark.core.polish.polish_least_squares`,
   :data:`POLISH_EVALUATIONS`);
3. ``truth_refined``: Nelder-Mead on the cost itself from the better of 1-2, in coordinates
   normalised to the bounds (least squares minimises the sum of squares, eq. 14; eq. 15's
   minimum is nearby, not the same), :data:`REFINE_EVALUATIONS`;
4. ``best_run``: the best cost any run of the suite reached (its history: optimiser and polish);
5. ``best_run_refined``: Nelder-Mead from that run's best point.

f* is the lowest; ``fstar.json`` in the instance's folder records every candidate, which one
won and its point (``x``, searched parameters) and parameters (``estimate``), which the
success criterion of model-error instances uses. Steps 1-3 run before the runs, 4-5 after.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import minimize as nelder_mead

from benchmark.core.io import write_text_atomic
from benchmark.core.polish import polish_least_squares
from benchmark.core.threads import one_blas_thread

POLISH_EVALUATIONS = 3000
REFINE_EVALUATIONS = 2000
FSTAR_FILE = "fstar.json"


def compose_run(harness_cfg: dict, overrides: list[str] | None = None):
    """The harness configuration of a run on an instance (``instances.harness_config``)."""
    from hydra import compose, initialize_config_dir
    from omegaconf import OmegaConf, open_dict

    from benchmark.studies.suite.spec import CONF

    ov = [f"problem={harness_cfg['problem']}", f"data.path={harness_cfg['data']['path']}", "figures=false",
          "checkpoint=false", "progress=false", *(overrides or [])]
    with initialize_config_dir(config_dir=str(CONF), version_base=None):
        cfg = compose("config", overrides=ov)
    with open_dict(cfg):
        if "bounds" in harness_cfg:
            cfg.bounds = OmegaConf.create(harness_cfg["bounds"])
        for k, v in (harness_cfg.get("problem_options") or {}).items():
            cfg.problem[k] = v
    return cfg


def build(harness_cfg: dict):
    """The instance's problem, built by the harness's own hooks (warnings of the data set
    silenced: the runs report them)."""
    from benchmark.core.harness import build_problem

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build_problem(compose_run(harness_cfg))


def refine(problem, x0: np.ndarray, evaluations: int = REFINE_EVALUATIONS) -> tuple[np.ndarray, float]:
    """Nelder-Mead on the problem's cost from ``x0`` in coordinates normalised to the bounds
    (initial simplex 1e-3 of each range); the best point seen and its cost."""
    lo, hi = np.asarray(problem.lower, float), np.asarray(problem.upper, float)
    span = hi - lo
    best = {"x": np.asarray(x0, float), "f": float(problem.evaluate(np.asarray(x0, float)[None, :])[0])}

    def f(u):
        x = lo + np.clip(u, 0.0, 1.0) * span
        c = float(problem.evaluate(x[None, :])[0])
        if c < best["f"]:
            best["x"], best["f"] = x, c
        return c if math.isfinite(c) else 1e300

    u0 = np.clip((best["x"] - lo) / span, 0.0, 1.0)
    simplex = np.vstack([u0] + [np.clip(u0 + 1e-3 * e, 0, 1) if u0[k] < 0.999 else u0 - 1e-3 * e
                                for k, e in enumerate(np.eye(len(u0)))])
    nelder_mead(f, u0, method="Nelder-Mead", options={"maxfev": int(evaluations), "xatol": 1e-10,
                                                      "fatol": 1e-10 * max(abs(best["f"]), 1e-300),
                                                      "initial_simplex": simplex})
    return best["x"], best["f"]


def _truth_vector(problem) -> np.ndarray:
    t = problem.truth or {}
    x = np.array([float(t[n]) for n in problem.parameter_names])
    return np.clip(x, problem.lower, problem.upper)


@one_blas_thread
def fstar_from_truth(harness_cfg: dict) -> dict:
    """Candidates 1-3 (module docstring)."""
    problem = build(harness_cfg)
    x_t = _truth_vector(problem)
    c_t = float(problem.evaluate(x_t[None, :])[0])
    pol = polish_least_squares(problem, x_t, POLISH_EVALUATIONS)
    x_p, c_p = (pol.best_x, float(pol.best_cost)) if pol.best_x is not None else (x_t, c_t)
    start = x_p if c_p <= c_t else x_t
    x_r, c_r = refine(problem, start)
    doc = {"candidates": {"truth": c_t, "truth_polished": c_p, "truth_refined": c_r}}
    return _with_best(doc, problem, {"truth_refined": x_r, "truth_polished": x_p, "truth": x_t})


def _with_best(doc: dict, problem, points: dict) -> dict:
    cands = doc["candidates"]
    finite = {k: v for k, v in cands.items() if v is not None and math.isfinite(v)}
    how = min(finite, key=finite.get) if finite else None
    doc["fstar"] = finite.get(how, math.inf) if how else math.inf
    doc["how"] = how
    if how in points:
        x = points[how]
        doc["x"] = dict(zip(problem.parameter_names, map(float, x), strict=True))
        doc["estimate"] = problem.estimate(np.asarray(x, float))
    return doc


@one_blas_thread
def add_best_run(doc: dict, harness_cfg: dict, best_cost: float, best_x: dict | None, job: str | None) -> dict:
    """Candidates 4-5 (module docstring); returns the updated document."""
    doc = {**doc, "candidates": dict(doc["candidates"]), "best_run_job": job}
    doc["candidates"]["best_run"] = float(best_cost)
    points = {}
    if doc.get("x"):
        points[doc["how"]] = np.array(list(doc["x"].values()), float)
    problem = build(harness_cfg)
    if best_x is not None:
        x_b = np.array([float(best_x[n]) for n in problem.parameter_names])
        points["best_run"] = x_b
        x_r, c_r = refine(problem, x_b)
        doc["candidates"]["best_run_refined"] = c_r
        points["best_run_refined"] = x_r
    return _with_best(doc, problem, points)


def read_fstar(folder: Path) -> dict | None:
    p = Path(folder) / FSTAR_FILE
    return json.loads(p.read_text()) if p.is_file() else None


def write_fstar(folder: Path, doc: dict) -> None:
    write_text_atomic(Path(folder) / FSTAR_FILE, json.dumps(doc, indent=1) + "\n")
