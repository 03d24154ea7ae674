"""The harness: builds the problem and the optimiser from the Hydra config, runs one
identification, scores it against the truth when known, and writes ``result.json``.

Everything is wired through ``hydra.utils.instantiate``: ``cfg.problem.setup`` builds the
problem, ``cfg.optimizer.plugin`` the optimiser. The harness counts evaluations (through
:class:`benchmark.problem.BudgetedProblem`), so every plugin is held to the same budget.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import inspect
import json
import math
import os
import platform
import sys
import time
import warnings
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import numpy as np
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from benchmark.data.tables import table_size_limit, write_table_atomic, write_text_atomic
from benchmark.errors import ConfigError, ResumeError, ResumeWarning
from benchmark.polish import polish_least_squares
from benchmark.problem import (
    BudgetedProblem,
    EvaluationJournal,
    OptimizeResult,
    Problem,
    Status,
    run_plugin,
)

#: The checkpoint of a run in progress (see :class:`benchmark.problem.EvaluationJournal`);
#: removed once ``result.json`` is written.
JOURNAL_NAME = "journal.bin"
#: Config keys that do not change a run's trajectory (left out of its fingerprint).
VOLATILE_KEYS = ("resume", "checkpoint", "time_limit_s", "progress", "figures")

RECORDED_PACKAGES = ("numpy", "scipy", "numba", "pandas", "hydra-core", "deap", "pygad", "nlopt", "cma",
                     "imbench")


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
    """Catch configuration mistakes before any work starts (no data read, nothing simulated):
    groups present, seed, budget, polish, time limit, checkpoint keys, the shape of
    ``bounds``, the problem's own checks (``check_config`` in the module of its set-up
    function) and the optimiser plugin (importable, options it accepts)."""
    for key in ("problem", "optimizer", "motor"):
        if key not in cfg or cfg[key] is None:
            raise ConfigError(f"{key}: missing config group")
    if "plugin" not in cfg.optimizer or "_target_" not in cfg.optimizer.plugin:
        raise ConfigError("optimizer.plugin._target_: the optimiser config must name its plugin function")
    if "setup" not in cfg.problem or "_target_" not in cfg.problem.setup:
        raise ConfigError("problem.setup._target_: the problem config must name its set-up function")
    seed = cfg.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"seed: must be a non-negative integer, got {seed!r}")
    resolve_budget(cfg)
    if cfg.get("polish"):
        pb = cfg.get("polish_budget")
        if isinstance(pb, bool) or not isinstance(pb, int) or pb < 1:
            raise ConfigError(f"polish_budget: must be a positive whole number, got {pb!r}")
    limit = cfg.get("time_limit_s")
    if limit is not None and (isinstance(limit, bool) or not isinstance(limit, (int, float))
                              or not math.isfinite(limit) or limit <= 0):
        raise ConfigError(f"time_limit_s: must be a positive number of seconds or null, got {limit!r}")
    for key in ("resume", "checkpoint", "polish", "figures"):
        v = cfg.get(key)
        if v is not None and not isinstance(v, bool):
            raise ConfigError(f"{key}: must be true or false, got {v!r}")
    progress = cfg.get("progress", "auto")
    if not (isinstance(progress, bool) or progress == "auto"):
        raise ConfigError(f"progress: must be auto, true or false, got {progress!r}")
    if cfg.get("resume") and cfg.get("checkpoint") is False:
        raise ConfigError("resume: needs checkpoint=true (a run without checkpoints cannot be resumed)")
    data = cfg.get("data")
    mib = data.get("max_file_mib") if data is not None else None
    if mib is not None and (isinstance(mib, bool) or not isinstance(mib, (int, float)) or not mib > 0):
        raise ConfigError(f"data.max_file_mib: must be a positive number of MiB, got {mib!r}")
    bounds = cfg.get("bounds")
    if bounds is not None:
        if not OmegaConf.is_dict(bounds):
            raise ConfigError(f"bounds: expected a mapping {{name: [low, high]}}, e.g. bounds={{Rs:[1,10]}}, "
                              f"got {bounds!r}")
        for k, v in bounds.items():
            if not OmegaConf.is_list(v) or len(v) != 2:
                raise ConfigError(f"bounds.{k}: expected [low, high], got {v!r}")
    check = _problem_check(cfg)
    if check is not None:
        check(cfg)
    check_plugin(cfg)


def _problem_check(cfg):
    """The problem's ``check_config(cfg)``, if the module of its set-up function has one."""
    target = str(cfg.problem.setup._target_)
    module_name = target.rpartition(".")[0]
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ConfigError(f"problem.setup._target_: cannot import {module_name!r}: {exc}") from None
    return getattr(module, "check_config", None)


def check_plugin(cfg: DictConfig):
    """Import the plugin function and check its options against its signature; returns it."""
    pcfg = cfg.optimizer.plugin
    target = str(pcfg._target_)
    module_name, _, attr = target.rpartition(".")
    try:
        fn = getattr(importlib.import_module(module_name), attr)
    except ImportError as exc:
        raise ConfigError(f"optimizer.plugin._target_: cannot import {module_name!r} for optimizer "
                          f"{cfg.optimizer.get('name')!r}: {exc}") from None
    except AttributeError:
        raise ConfigError(f"optimizer.plugin._target_: {module_name!r} has no function {attr!r}") from None
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return fn
    params = sig.parameters
    if any(p.kind == inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return fn
    valid = [n for n, p in params.items() if n not in ("problem", "seed")
             and p.kind in (inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)]
    for key in pcfg:
        if str(key).startswith("_"):
            continue
        if key not in valid:
            raise ConfigError(f"optimizer.plugin.{key}: not an option of {target}; valid: {valid}")
    return fn


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
    """One identification run, written to ``outdir``.

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
    with warnings.catch_warnings(record=True) as caught, \
            table_size_limit(None if mib is None else int(float(mib) * 2**20)):
        warnings.simplefilter("always")
        problem: Problem = instantiate(cfg.problem.setup)(cfg)
    run_warnings = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    for w in caught:  # shown once, after set-up (the command line prints them one line each)
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    setup_time = time.perf_counter() - t_start

    fingerprint = run_fingerprint(cfg, problem)
    journal, replay, resume_info = None, None, None
    if cfg.get("resume"):
        done = _finished_run(outdir, fingerprint)
        if done is not None:
            return RunOutcome(problem=problem, result=_result_from_record(done), record=done)
        replay, resume_info = _read_checkpoint(outdir, fingerprint, problem, cfg)
        if resume_info.get("note"):
            warnings.warn(f"resume: {resume_info['note']}", ResumeWarning, stacklevel=2)
            run_warnings.append(f"resume: {resume_info['note']}")
    if cfg.get("checkpoint", True):
        path = outdir / JOURNAL_NAME
        if replay is not None:
            journal = EvaluationJournal.reopen(path, replay)  # the cut-off tail is dropped here
        else:
            journal = EvaluationJournal.create(path, _journal_header(cfg, problem, budget, fingerprint))

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
    }, float_format="%.17g")
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
        "time_limit_s": cfg.get("time_limit_s"),
        "wall_time_s": wall,
        "wall_time_optimizer_s": result.wall_time_s,
        "setup_time_s": setup_time,
        "history": "history.csv",
        "bounds": {n: [float(lo), float(hi)] for n, lo, hi in zip(problem.parameter_names, problem.lower,
                                                                 problem.upper, strict=True)},
        "problem_info": problem.describe(),
        "warnings": run_warnings,
        "resume": resume_info,
        "fingerprint": fingerprint,
        "config": OmegaConf.to_container(cfg, resolve=True),
        "versions": package_versions(),
        "command": " ".join(sys.argv),
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
    """Figures and ``report.md`` beside ``result.json`` (:mod:`benchmark.figures`), listed in
    ``record["figures"]``. The result is already on disk: whatever goes wrong here becomes a
    warning in ``result.json`` and the run goes on."""
    with warnings.catch_warnings(record=True):  # a plotting library's warnings are not the run's
        warnings.simplefilter("always")
        try:
            from benchmark.figures import write_run_figures

            info = write_run_figures(problem, record, x, outdir)
        except Exception as exc:
            info = {"report": None, "files": [], "errors": [f"{type(exc).__name__}: {exc}"]}
    record["figures"] = info
    record["warnings"] += [f"figure not made ({e}); the result is unaffected" for e in info.get("errors", [])]
    with contextlib.suppress(Exception):
        write_text_atomic(outdir / "result.json", json.dumps(record, indent=2, default=_json_default) + "\n")


def progress_wanted(setting, *, stream=None, environ=None, multirun: bool | None = None) -> bool:
    """Whether a run shows its progress bar: ``progress=true`` forces it and ``false`` turns it
    off; ``auto`` shows it only where someone watches: on a terminal (``stream``, default
    stderr, is a tty), outside CI (no ``CI`` environment variable) and outside a sweep (Hydra's
    multirun mode)."""
    if setting is True or setting is False:
        return setting
    environ = os.environ if environ is None else environ
    if environ.get("CI"):
        return False
    stream = sys.stderr if stream is None else stream
    try:
        if not stream.isatty():
            return False
    except (AttributeError, ValueError, OSError):
        return False
    return not (_in_multirun() if multirun is None else multirun)


def _in_multirun() -> bool:
    try:
        from hydra.core.hydra_config import HydraConfig
        from hydra.types import RunMode

        return HydraConfig.initialized() and HydraConfig.get().mode == RunMode.MULTIRUN
    except Exception:
        return False


class ProgressBar:
    """A tqdm bar of one run on stderr: evaluations against the budget, the best cost and the
    estimated time left. Set as :attr:`BudgetedProblem.on_evaluate`; it redraws at most every
    :attr:`interval` seconds, so the evaluation loop pays one clock read per batch. A bar that
    cannot be drawn (stderr closed) goes quiet instead of failing the run."""

    interval = 0.1

    def __init__(self, budget: int, desc: str, file=None):
        from tqdm import tqdm

        file = file if file is not None else sys.stderr
        try:
            columns = os.get_terminal_size(file.fileno()).columns
        except (AttributeError, ValueError, OSError):
            columns = 0
        # a terminal that reports no size (a bare pty) would hide the bar: give it one
        width = {"dynamic_ncols": True} if columns > 0 else {"ncols": 100, "nrows": 24}
        self._last = -math.inf
        try:
            self._bar = tqdm(total=int(budget), desc=desc, unit="eval", file=file, leave=False, mininterval=0.0,
                             miniters=1, smoothing=0.1, **width)
        except Exception:
            self._bar = None

    def __call__(self, budgeted: BudgetedProblem) -> None:
        now = time.monotonic()
        if now - self._last >= self.interval:
            self._last = now
            self._show(budgeted)

    def _show(self, budgeted: BudgetedProblem) -> None:
        if self._bar is None:
            return
        try:
            self._bar.set_postfix_str(f"best {budgeted.best_cost:.5g}", refresh=False)
            self._bar.update(min(budgeted.nfev, budgeted.budget) - self._bar.n)
        except Exception:
            self._bar = None

    def close(self, budgeted: BudgetedProblem) -> None:
        self._show(budgeted)
        if self._bar is not None:
            with contextlib.suppress(Exception):
                self._bar.close()
            self._bar = None


# -- checkpoints -------------------------------------------------------------------------------
def run_fingerprint(cfg: DictConfig, problem: Problem) -> str:
    """SHA-256 of what determines a run's trajectory: the resolved config (less
    :data:`VOLATILE_KEYS` and ``data.max_file_mib``), the searched names and bounds, and the
    contents of the data folder's tables and YAML files."""
    return hashlib.sha256(json.dumps(_fingerprint_doc(cfg, problem), sort_keys=True, default=str).encode()
                          ).hexdigest()


def _fingerprint_doc(cfg: DictConfig, problem: Problem) -> dict:
    conf = OmegaConf.to_container(cfg, resolve=True)
    for k in VOLATILE_KEYS:
        conf.pop(k, None)
    if isinstance(conf.get("data"), dict):
        conf["data"].pop("max_file_mib", None)
    return {
        "config": conf,
        "parameter_names": list(problem.parameter_names),
        "lower": [float(v).hex() for v in np.asarray(problem.lower, float)],
        "upper": [float(v).hex() for v in np.asarray(problem.upper, float)],
        "data": _data_digest((cfg.get("data") or {}).get("path")),
    }


def _data_digest(path) -> str | None:
    if path is None:
        return None
    folder = Path(str(path))
    h = hashlib.sha256()
    for f in sorted(folder.iterdir()) if folder.is_dir() else []:
        if f.is_file() and f.suffix.lower() in (".csv", ".mat", ".yaml", ".yml"):
            h.update(f.name.encode() + b"\0")
            with open(f, "rb") as fh:
                for chunk in iter(lambda fh=fh: fh.read(1 << 20), b""):
                    h.update(chunk)
    return h.hexdigest()


def _journal_header(cfg: DictConfig, problem: Problem, budget: int, fingerprint: str) -> dict:
    return {"fingerprint": fingerprint, "n_var": problem.n_var,
            "parameter_names": list(problem.parameter_names), "budget": budget,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
            "config": _fingerprint_doc(cfg, problem)["config"]}


def _read_checkpoint(outdir: Path, fingerprint: str, problem: Problem, cfg: DictConfig):
    """(journal contents or None, resume info) for ``resume=true``; ResumeError if the journal
    belongs to another configuration."""
    path = outdir / JOURNAL_NAME
    contents = EvaluationJournal.read(path)
    info = {"journal": str(path), "replayed_batches": 0, "replayed_evaluations": 0, "ignored_bytes": 0}
    if contents is None:
        info["note"] = (f"no checkpoint in {outdir} (is hydra.run.dir the folder of the interrupted run?): "
                        "starting from the beginning")
        return None, info
    header = contents.header
    if header.get("fingerprint") != fingerprint:
        raise ResumeError(
            f"resume: the checkpoint {path} was written by a different run configuration or data "
            f"({_config_difference(header.get('config'), _fingerprint_doc(cfg, problem)['config'])}); "
            "resume with the same overrides "
            "as the interrupted run, or start afresh with resume=false"
        )
    if header.get("n_var") != problem.n_var:
        raise ResumeError(f"resume: the checkpoint {path} is for {header.get('n_var')} parameters, "
                          f"this problem has {problem.n_var}")
    info["ignored_bytes"] = contents.ignored_bytes
    info["journaled_batches"] = len(contents.records)
    if contents.ignored_bytes:
        info["note"] = (f"ignored {contents.ignored_bytes} bytes at the end of the checkpoint (a record cut "
                        "short when the run was killed)")
    return contents, info


def _config_difference(old, now) -> str:
    """'seed: 1 then, 2 now; ...' for the first differing config keys."""
    a, b = _flatten(old or {}), _flatten(now or {})
    keys = sorted(k for k in set(a) | set(b) if a.get(k, "<unset>") != b.get(k, "<unset>"))
    if not keys:
        return "same configuration, but the data files or the derived bounds differ"
    shown = "; ".join(f"{k}: {a.get(k, '<unset>')!r} then, {b.get(k, '<unset>')!r} now" for k in keys[:5])
    return shown + (f"; and {len(keys) - 5} more" if len(keys) > 5 else "")


def _flatten(d, prefix: str = "") -> dict:
    out = {}
    if isinstance(d, dict):
        for k, v in d.items():
            out.update(_flatten(v, f"{prefix}{k}."))
    else:
        out[prefix[:-1]] = d
    return out


def _finished_run(outdir: Path, fingerprint: str) -> dict | None:
    """The record of a run already finished in ``outdir`` with the same fingerprint, if its
    checkpoint is gone (the run completed)."""
    path = outdir / "result.json"
    if (outdir / JOURNAL_NAME).exists() or not path.is_file():
        return None
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("fingerprint") != fingerprint:
        return None
    return record


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
    if record["status"] in (Status.FAILED.value, Status.TIMEOUT.value):
        lines.append(f"{record['status']}: {record['message']}")
    return "\n".join(lines)
