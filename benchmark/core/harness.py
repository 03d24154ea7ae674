"""The harness: builds the problem and the optimiser from the Hydra config, runs one
identification, scores it against the truth when known, and writes ``result.json``.

Everything is wired through ``hydra.utils.instantiate``: ``cfg.problem.setup`` builds the
problem, ``cfg.optimizer.plugin`` the optimiser. The harness counts evaluations (through
:class:`benchmark.core.problem.BudgetedProblem`), so every plugin is held to the same budget.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import platform
import subprocess
import sys
import time
import warnings
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np
import yaml
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from benchmark.core.budget import BudgetedProblem, run_plugin
from benchmark.core.commands import run_overrides, typed_command
from benchmark.core.config_checks import resolve_budget, validate_config
from benchmark.core.errors import ConfigError, ResumeError, ResumeWarning
from benchmark.core.identify import identify, polish_and_keep_better
from benchmark.core.io import write_table_atomic, write_text_atomic
from benchmark.core.journal import EvaluationJournal
from benchmark.core.nuisance import refine_nuisance
from benchmark.core.problem import OptimizeResult, Problem, Status
from benchmark.core.progress import ProgressBar, progress_wanted
from benchmark.core.quality import assess
from benchmark.core.resume import JOURNAL_NAME, finished_run, journal_header, read_checkpoint, run_fingerprint
from benchmark.core.review import found_short, review
from benchmark.core.tables import table_size_limit
from benchmark.core.threads import one_blas_thread

#: The checkpoint of a run in progress (see :class:`benchmark.core.problem.EvaluationJournal`);
#: removed once ``result.json`` is written.
#: Config keys that do not change a run's trajectory (left out of its fingerprint).

RECORDED_PACKAGES = ("numpy", "scipy", "numba", "pandas", "hydra-core", "deap", "pygad", "nlopt", "cma",
                     "imbench")


@dataclass
class RunOutcome:
    problem: Problem
    result: OptimizeResult
    record: dict


def resolved(cfg: DictConfig) -> dict:
    """The run configuration as a plain, resolved mapping: what the problem hooks receive."""
    return OmegaConf.to_container(cfg, resolve=True)


def load_dataset(cfg: DictConfig, with_truth: bool = True):
    """The run's data set and truth document (None for measured data): the data folder
    ``data.path`` through the problem's ``load`` and ``truth`` hooks, else synthetic data from
    its ``make`` hook. A folder of the other problem's kind is refused with the right option.
    ``with_truth=False`` (the diagnosis) never opens a folder's truth.yaml and drops the
    synthetic truth at once."""
    run = resolved(cfg)
    path = (run.get("data") or {}).get("path")
    if path is None:
        dataset, truth = instantiate(cfg.problem.make)(run)
        return dataset, truth if with_truth else None
    check_data_kind(Path(path), str(cfg.problem.name), str(cfg.problem.get("data_kind", cfg.problem.name)))
    return instantiate(cfg.problem.load)(path), instantiate(cfg.problem.truth)(path) if with_truth else None


def check_data_kind(folder: Path, problem: str, expected: str) -> None:
    """A ConfigError when ``folder/meta.yaml`` declares a ``kind`` another problem reads."""
    meta = folder / "meta.yaml"
    if not meta.is_file():
        return
    try:
        doc = yaml.safe_load(meta.read_text(encoding="utf-8-sig"))
    except (yaml.YAMLError, UnicodeDecodeError, ValueError, RecursionError):
        return  # the loader reports a malformed meta.yaml with file and line
    kind = doc.get("kind") if isinstance(doc, dict) else None
    if isinstance(kind, str) and kind != expected and DATA_KIND_PROBLEM.get(kind, problem) != problem:
        raise ConfigError(f"data.path: {folder} holds kind: {kind}, which problem={problem} does not read; "
                          f"use problem={DATA_KIND_PROBLEM[kind]}")


#: Which problem reads a data folder of each ``kind`` (meta.yaml).
DATA_KIND_PROBLEM = {"startup": "timedomain", "admittance": "admittance", "loadtest": "admittance"}


def build_problem(cfg: DictConfig) -> Problem:
    """The problem of a run, through the problem's hooks: typed settings from the resolved
    configuration, the data set (folder or synthetic), then ``setup(settings, data, truth)``."""
    settings = instantiate(cfg.problem.settings)(resolved(cfg))
    dataset, truth_doc = load_dataset(cfg)
    return instantiate(cfg.problem.setup)(settings, dataset, truth_doc)


@one_blas_thread
def run_diagnosis(cfg: DictConfig, outdir: Path, progress=None) -> dict:
    """Diagnose the configured data set into ``outdir`` through the problem's ``diagnose`` hook
    (the truth of synthetic data is discarded here); returns the diagnosis document."""
    dataset, _ = load_dataset(cfg, with_truth=False)
    return instantiate(cfg.problem.diagnose)(resolved(cfg), dataset, outdir, base_identify(cfg), progress)


def base_identify(cfg: DictConfig):
    """``identify(problem, seed=...)`` with a diagnosis run's optimiser, budgets and polish: how
    the diagnosis identifies its base model (``concurrent_runs`` set from the plugin)."""
    plugin = instantiate(cfg.optimizer.plugin)
    base = functools.partial(identify, plugin=plugin, budget=int(cfg.budget),
                             seed=int(cfg.seed), name=str(cfg.optimizer.name),
                             polish_budget=int(cfg.polish_budget))
    base.concurrent_runs = concurrent_runs(plugin)
    return base


def concurrent_runs(plugin) -> bool:
    """Whether the plugin says its runs may go side by side in one process (``concurrent_runs =
    True`` on its function, also behind a configured partial; docs/plugins.md)."""
    return bool(getattr(plugin, "concurrent_runs", getattr(getattr(plugin, "func", None), "concurrent_runs", False)))


def evaluations_text(record: dict) -> str:
    """``N evaluations`` of a result record, with the optimiser's, the polish's and the nuisance's
    shares when there is more than the optimiser's (a run's total can exceed its budget)."""
    parts = [(record.get("evaluations_optimizer"), f"by {record.get('optimizer')}"),
             ((record.get("polish") or {}).get("evaluations"), "by the polish"),
             ((record.get("nuisance") or {}).get("evaluations"), "for the nuisance")]
    shares = [f"{n} {what}" for n, what in parts if n]
    total = f"{record.get('evaluations')} evaluations"
    return total if len(shares) < 2 else f"{total} ({', '.join(shares)})"


def package_versions() -> dict[str, str]:
    """Python's and the recorded packages' versions; run from a git checkout, also its commit (with
    ``-dirty`` when files differ from it: a locally edited plugin)."""
    out = {"python": platform.python_version()}
    for name in RECORDED_PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            pass
    commit = source_commit()
    if commit:
        out["imbench_git"] = commit
    return out


@functools.cache
def source_commit() -> str | None:
    """``git describe --always --dirty`` of the checkout this package runs from, or None (an installed
    wheel, no git)."""
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        return None
    try:
        out = subprocess.run(["git", "-C", str(root), "describe", "--always", "--dirty", "--abbrev=12"],
                             capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return (out.stdout.strip() or None) if out.returncode == 0 else None


def score(estimate: dict[str, float], truth: dict[str, float] | None) -> dict[str, float] | None:
    """Signed relative error of each estimated parameter with a known, non-zero truth."""
    if truth is None:
        return None
    out = {}
    for k, v in estimate.items():
        if k in truth and truth[k] != 0:
            out[k] = (v - truth[k]) / abs(truth[k])
    return out


@one_blas_thread
def run(cfg: DictConfig, outdir: Path, overrides: list[str] | None = None) -> RunOutcome:
    """One identification run, written to ``outdir``; ``overrides`` are what the user asked for
    (the API's keyword arguments; None: the command line's), from which suggested commands are built.

    Checkpoints (``checkpoint``, default true): every evaluated batch is journaled to
    ``outdir/journal.bin`` as it happens. With ``resume=true`` and the same ``outdir``
    (``hydra.run.dir=...``), the plugin starts again from scratch with the same seed and the
    journal is replayed: batches identical bit for bit to the journaled ones get the journaled
    costs without simulating, then the run goes on live, so a deterministic plugin finishes
    exactly as an uninterrupted run would. A run whose ``result.json`` is already written is
    not run again on resume (a resumed sweep skips its finished jobs).
    """
    outdir = Path(outdir)
    validate_config(cfg)
    budget = resolve_budget(cfg)
    seed = int(cfg.seed)
    name = str(cfg.optimizer.get("name", "optimizer"))
    try:
        plugin = instantiate(cfg.optimizer.plugin)
    except Exception as exc:  # hydra's InstantiationException: a bad _target_ or option
        raise ConfigError(f"optimizer.plugin: cannot build the plugin: {exc}") from None

    t_start = time.perf_counter()
    mib = (cfg.get("data") or {}).get("max_file_mib")
    caught: list = []
    try:
        with warnings.catch_warnings(record=True) as caught, \
                table_size_limit(None if mib is None else int(float(mib) * 2**20)):
            warnings.simplefilter("always")
            problem: Problem = build_problem(cfg)
    finally:  # shown once, after set-up, also before a set-up error they may explain (one line each)
        for w in caught:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    run_warnings = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    setup_time = time.perf_counter() - t_start

    fingerprint = run_fingerprint(resolved(cfg), problem)
    journal, replay, resume_info = None, None, None
    if cfg.get("resume"):
        done = finished_run(outdir, fingerprint)
        if done is not None:
            return RunOutcome(problem=problem, result=_result_from_record(done), record=done)
        replay, resume_info = read_checkpoint(outdir, fingerprint, problem, resolved(cfg))
        if resume_info.get("note"):
            warnings.warn(f"resume: {resume_info['note']}", ResumeWarning, stacklevel=2)
            run_warnings.append(f"resume: {resume_info['note']}")
    if cfg.get("checkpoint", True):
        path = outdir / JOURNAL_NAME
        if replay is not None:
            journal = EvaluationJournal.reopen(path, replay)  # the cut-off tail is dropped here
        else:
            journal = EvaluationJournal.create(path, journal_header(resolved(cfg), problem, budget, fingerprint))

    budgeted = BudgetedProblem(problem, budget, journal=journal, replay=replay.records if replay else None)
    if replay is not None:
        try:
            budgeted.verify_replay()
        except ResumeError:
            journal.close()
            raise
    bar = None
    if progress_wanted(cfg.get("progress", "auto")):
        bar = ProgressBar(budget, f"{problem.name}/{name}")
        budgeted.on_evaluate = bar
    try:
        result = run_plugin(plugin, budgeted, seed=seed, name=name, time_limit_s=cfg.get("time_limit_s"),
                            record_failures=True)
    finally:
        if bar is not None:
            budgeted.on_evaluate = None
            bar.close(budgeted)
        if journal is not None:
            journal.close()
    if resume_info is not None:
        resume_info.update(replayed_batches=budgeted.replayed_batches,
                           replayed_evaluations=budgeted.replayed_evaluations,
                           mismatch=budgeted.replay_mismatch)
        if budgeted.replaying:
            resume_info["unreplayed_batches"] = len(budgeted._replay)
        if budgeted.replay_mismatch:
            run_warnings.append(f"resume: {budgeted.replay_mismatch['message']}")

    polish_budget = int(cfg.polish_budget) if cfg.get("polish") else None
    ident = polish_and_keep_better(problem, result, budgeted, polish_budget)
    # did the optimiser stop short; does the problem want the result from another set-up (core/review.py)
    rev = review(problem, ident, seed=seed, polish_budget=int(cfg.polish_budget),
                 identify=functools.partial(identify, plugin=plugin, budget=budget, name=name,
                                            polish_budget=polish_budget, time_limit_s=cfg.get("time_limit_s")))
    problem, ident, result = rev.problem, rev.ident, rev.ident.result
    run_warnings += rev.warnings
    history, polish_info, x_best, f_best = ident.history, ident.polish, ident.x, ident.cost
    nuisance = refine_nuisance(problem, x_best, f_best)
    if nuisance is not None and nuisance.accepted:
        x_best, f_best = nuisance.x, nuisance.cost
    rev.explain(x_best, int(cfg.polish_budget))
    wall = time.perf_counter() - t_start

    asked = run_overrides(cfg) if overrides is None else overrides
    assessment = assess(problem, x_best, status=ident.status, budget=budget, overrides=asked,
                        shortfall=rev.shortfall)
    estimate = problem.estimate(x_best) if x_best is not None else None
    truth = problem.truth
    rel_error = score(estimate, truth) if estimate is not None else None
    write_table_atomic(outdir / "history.csv", {
        "evaluations": np.array([h[0] for h in history], dtype=int),
        "best_cost": np.array([h[1] for h in history], dtype=float),
        "phase": np.array([h[2] for h in history], dtype=object),
    }, float_format="%.17g")
    record = {
        "problem": problem.name,
        "optimizer": name,
        "seed": seed,
        "status": ident.status,
        "status_optimizer": result.status.value,
        "message": result.message,
        "parameter_names": list(problem.parameter_names),
        "searched": None if x_best is None else dict(zip(problem.parameter_names, map(float, x_best),
                                                         strict=True)),
        "estimate": estimate,
        "units": None if estimate is None else {k: problem.units.get(k, "") for k in estimate},
        "truth": truth,
        "rel_error": rel_error,
        # uncertainty of the searched parameters at the final point (benchmark.core.quality)
        "standard_error": assessment["standard_error"],
        "correlation": assessment["correlation"],
        "uncertainty": assessment["uncertainty"],
        "fit_quality": assessment["fit_quality"],
        "cost": _finite_or_none(f_best),
        "cost_optimizer": _finite_or_none(result.fun),
        "evaluations": result.nfev + (polish_info or {}).get("evaluations", 0)
        + (nuisance.evaluations if nuisance is not None else 0),
        "evaluations_optimizer": result.nfev,
        "budget": budget,
        "nit": result.nit,
        "polish": polish_info,
        # record quantities estimated with the parameters (benchmark.core.nuisance), or None
        "nuisance": None if nuisance is None else nuisance.record(),
        "time_limit_s": cfg.get("time_limit_s"),
        "wall_time_s": wall,
        "wall_time_optimizer_s": result.wall_time_s,
        "setup_time_s": setup_time,
        "history": "history.csv",
        "bounds": {n: [float(lo), float(hi)] for n, lo, hi in zip(problem.parameter_names, problem.lower,
                                                                 problem.upper, strict=True)},
        "problem_info": problem.describe(),
        "review": rev.record(),  # stopped short? a stop record set aside? a prior's weight? (core/review.py)
        "notes": rev.notes,  # what the reader should know that is no warning (e.g. what a prior cost)
        # what the user must know before trusting the estimate (empty when all is well): the
        # data and set-up's own, then the verdict on the fit (benchmark.core.quality)
        "warnings": run_warnings + assessment["warnings"],
        "resume": resume_info,
        "fingerprint": fingerprint,
        "config": OmegaConf.to_container(cfg, resolve=True),
        "versions": package_versions(),
        "command": typed_command(sys.argv),
    }
    if result.traceback:
        record["traceback"] = result.traceback
    write_text_atomic(outdir / "result.json", json.dumps(record, indent=2, default=_json_default) + "\n")
    if journal is not None:  # the result is safe: the checkpoint has served its purpose
        with contextlib.suppress(OSError):
            (outdir / JOURNAL_NAME).unlink()
    if cfg.get("figures", True):
        add_figures(outdir, problem, record, x_best)
    return RunOutcome(problem=problem, result=result, record=record)


# -- figures and progress ----------------------------------------------------------------------
def add_figures(outdir: Path, problem: Problem, record: dict, x) -> None:
    """Figures and ``report.md`` beside ``result.json`` (:mod:`benchmark.core.plotting`), listed in
    ``record["figures"]``. The result is already on disk: whatever goes wrong here becomes a
    warning in ``result.json`` and the run goes on."""
    with warnings.catch_warnings(record=True):  # a plotting library's warnings are not the run's
        warnings.simplefilter("always")
        try:
            from benchmark.core.plotting import write_run_figures

            info = write_run_figures(problem, record, x, outdir)
        except Exception as exc:
            info = {"report": None, "files": [], "errors": [f"{type(exc).__name__}: {exc}"]}
    record["figures"] = info
    record["warnings"] += [f"figure not made ({e}); the result is unaffected" for e in info.get("errors", [])]
    with contextlib.suppress(Exception):
        write_text_atomic(outdir / "result.json", json.dumps(record, indent=2, default=_json_default) + "\n")


def _result_from_record(record: dict) -> OptimizeResult:
    searched = record.get("searched")
    return OptimizeResult(
        x=None if searched is None else np.array(list(searched.values()), dtype=float),
        fun=record["cost_optimizer"] if record.get("cost_optimizer") is not None else math.inf,
        nfev=int(record["evaluations_optimizer"]), nit=int(record["nit"]), status=Status(record["status"]),
        message=str(record["message"]), optimizer=str(record["optimizer"]), seed=int(record["seed"]),
        wall_time_s=float(record.get("wall_time_optimizer_s") or math.nan), traceback=record.get("traceback"),
    )


def _finite_or_none(x):
    return float(x) if x is not None and math.isfinite(x) else None


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    return str(o)


def format_table(record: dict) -> str:
    """The short table printed after a run: parameter, unit, estimate, truth, error, standard error."""
    est, truth, err = record["estimate"] or {}, record["truth"] or {}, record["rel_error"] or {}
    se, units = record.get("standard_error") or {}, record.get("units") or {}
    lines = [f"{'parameter':<10}{'unit':<11}{'estimate':>12}{'truth':>14}{'error':>10}{'std err':>12}"]
    for k, v in est.items():
        t = f"{truth[k]:14.6g}" if k in truth else f"{'-':>14}"
        e = f"{100 * err[k]:+9.3f}%" if k in err else f"{'-':>10}"
        s = f"{se[k]:12.3g}" if se.get(k) is not None else f"{'-':>12}"
        lines.append(f"{k:<10}{units.get(k) or '-':<11}{v:12.6g}{t}{e}{s}")
    cost = record["cost"]
    lines.append(
        f"{record['problem']} / {record['optimizer']} seed {record['seed']}: status {record['status']}"
        + (" (the optimiser's own stop; the review finds it stopped short: see the warnings)"
           if record["status"] == Status.CONVERGED.value and found_short(record) else "")
        + f", cost {cost if cost is None else f'{cost:.6g}'}, {evaluations_text(record)}, "
        f"{record['wall_time_s']:.2f} s"
    )
    if record["status"] in (Status.FAILED.value, Status.TIMEOUT.value):
        lines.append(f"{record['status']}: {record['message']}")
    fq = {k: v for k, v in (record.get("fit_quality") or {}).items() if isinstance(v, dict)}
    if fq:
        lines.append("fit quality (RMS misfit / noise): " + ", ".join(
            f"{k} {v['ratio']:.3g}{'' if v['at_noise_level'] else ' (!)' if v['ratio'] > v['threshold'] else ''}"
            for k, v in fq.items()))
    lines += [f"note: {n}" for n in record.get("notes") or []]
    warns = record.get("warnings") or []
    lines.append(f"warnings: {len(warns)}" if warns else "warnings: none")
    lines += [f"  - {w}" for w in warns]
    return "\n".join(lines)
