"""``python -m benchmark.suite``: instances -> f* -> runs -> measures (the stages, in order).

Arguments (``key=value``):

``suite``     ``small`` (default), ``full``, or a suite YAML (``conf/suite_<name>.yaml``)
``user``      a YAML listing data folders of your own (:mod:`benchmark.studies.suite.user`):
              the same runs and measures, targets relative to the best cost any run found
``stage``     ``all`` (default), ``instances``, ``fstar`` (f* from the truth), ``runs`` (f*, then the runs),
              ``report`` (f* from the runs, then the measures), ``cost`` (per-run CPU on a
              sample of the instances, extrapolated to the whole suite)
``cache``     data and runs (default ``data/suite/<suite>``: ``data/``, ``runs/``, ``launch/``)
``out``       the results (default ``results/suite`` for ``small``, else ``CACHE/results``)
``launcher``  ``joblib`` (default: ``imbench_joblib`` with ``jobs`` workers), ``slurm``
              (``imbench_slurm``; give ``hydra.launcher.partition=NAME``), ``submitit_local``
``jobs``      joblib workers (default 2); ``chunk``: runs per sweep (default 1000)
``only``      globs of instance names, comma-separated; ``sample``: instances the ``cost`` stage measures (12)
``hydra.*``   passed to every sweep (``hydra.launcher.partition=NAME``, ``hydra.launcher.timeout_min=30``)
"""

from __future__ import annotations

import fnmatch
import json
import os
import platform
import resource
import sys
import time
from pathlib import Path

from benchmark.core.errors import ConfigError
from benchmark.core.io import write_text_atomic
from benchmark.core.spelling import did_you_mean
from benchmark.studies.suite import fstar as fs
from benchmark.studies.suite.instances import build_instance, data_folder, harness_config, read_instance
from benchmark.studies.suite.jobs import jobs_for, launch, pending
from benchmark.studies.suite.spec import load_suite

DEFAULTS = {"suite": "small", "user": None, "stage": "all", "cache": None, "out": None, "launcher": "joblib",
            "jobs": 2, "chunk": 1000, "only": None, "sample": 12}
LAUNCHERS = {"joblib": "imbench_joblib", "slurm": "imbench_slurm", "submitit_local": "submitit_local"}
STAGES = ("all", "instances", "fstar", "runs", "report", "cost")


def parse(argv: list[str]) -> tuple[dict, list[str]]:
    opts, passthrough = dict(DEFAULTS), []
    for a in argv:
        key, eq, val = a.partition("=")
        if key.startswith("hydra.") and eq:
            passthrough.append(a)
        elif key in DEFAULTS and eq:
            opts[key] = int(val) if key in ("jobs", "chunk", "sample") else val
        else:
            raise ConfigError(f"{a}: unknown argument{did_you_mean(key.lstrip('+'), list(DEFAULTS))}; "
                              f"valid: {', '.join(DEFAULTS)} and hydra.*=... (see --help)")
    if opts["stage"] not in STAGES:
        raise ConfigError(f"stage: one of {list(STAGES)}, got {opts['stage']!r}")
    if opts["launcher"] not in LAUNCHERS:
        raise ConfigError(f"launcher: one of {list(LAUNCHERS)}, got {opts['launcher']!r}")
    return opts, passthrough


def launcher_args(opts: dict, passthrough: list[str]) -> list[str]:
    args = [f"hydra/launcher={LAUNCHERS[opts['launcher']]}"]
    if opts["launcher"] == "joblib":
        args.append(f"hydra.launcher.n_jobs={int(opts['jobs'])}")
    return args + passthrough


def _cpu_self() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


class Timer:
    """Wall and CPU seconds of a stage run in this process (``cpu_self``) or its children."""

    def __init__(self, log: dict, name: str):
        self.log, self.name = log, name

    def __enter__(self):
        self.t0, self.c0 = time.perf_counter(), _cpu_self()
        return self

    def __exit__(self, *exc):
        self.log[self.name] = {"wall_time_s": round(time.perf_counter() - self.t0, 1),
                               "cpu_time_s": round(_cpu_self() - self.c0, 1)}


def suite_instances(opts: dict, cache: Path):
    """(suite, [(instance document, harness config)]), building the suite's data sets."""
    if opts["user"]:
        from benchmark.studies.suite.user import load_user

        return load_user(opts["user"])
    suite = load_suite(opts["suite"])
    globs = str(opts["only"]).split(",") if opts["only"] else []
    insts = [i for i in suite.instances if not globs or any(fnmatch.fnmatch(i.name, g) for g in globs)]
    if opts["stage"] == "cost":
        from benchmark.studies.suite.cost import sample_instances

        insts = sample_instances(insts, int(opts["sample"]))
    out = []
    for k, inst in enumerate(insts):
        folder = data_folder(cache, inst.name)
        if not (folder / "instance.yaml").is_file():
            print(f"  data {k + 1}/{len(insts)}: {inst.name}", flush=True)
        build_instance(inst, cache, suite.records)
        doc = read_instance(folder)
        out.append((doc, harness_config(doc, folder)))
    return suite, out


def fstar_from_truth(items, cache: Path) -> None:
    for k, (doc, cfg) in enumerate(items):
        folder = data_folder(cache, doc["name"])
        if fs.read_fstar(folder) is None:
            print(f"  f* from the truth {k + 1}/{len(items)}: {doc['name']}", flush=True)
            fs.write_fstar(folder, {"from_truth": fs.fstar_from_truth(cfg)})


def fstar_from_runs(items, cache: Path, runs: Path) -> dict:
    """Candidates 4-5 of :mod:`benchmark.studies.suite.fstar` for every instance; f* documents by name."""
    from benchmark.analysis.runs import load_runs
    from benchmark.studies.suite.measures import data_path_of

    best: dict[str, tuple[float, dict | None, str]] = {}
    for r in load_runs(runs):
        if not len(r.best):
            continue
        key, c = data_path_of(r.rec), float(r.best.min())
        if key not in best or c < best[key][0]:
            best[key] = (c, r.rec.get("searched"), r.path.parent.name)
    out = {}
    for doc, cfg in items:
        folder = data_folder(cache, doc["name"])
        prior = fs.read_fstar(folder) or {}
        base = prior.get("from_truth") or {"candidates": {}}
        b = best.get(str(Path(cfg["data"]["path"]).resolve()))
        if b is None:
            continue
        doc_f = fs.add_best_run(base, cfg, b[0], b[1], b[2])
        fs.write_fstar(folder, {**prior, "from_truth": base, **doc_f})
        out[doc["name"]] = doc_f
    return out


def main(argv: list[str]) -> int:
    opts, passthrough = parse(argv)
    name = Path(opts["user"]).stem if opts["user"] else Path(opts["suite"]).stem
    cache = Path(opts["cache"] or f"data/suite/{name}")
    runs = cache / "runs"
    out = Path(opts["out"] or ("results/suite" if name == "small" and not opts["user"] else cache / "results"))
    log: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                             "platform": platform.platform()}, "command": "python -m benchmark.suite " + " ".join(argv)}
    stage = opts["stage"]
    with Timer(log, "instances"):
        suite, items = suite_instances(opts, cache)
    if stage == "instances":
        return _done(log, cache, f"{len(items)} instances in {cache / 'data'}")
    if stage == "cost":
        from benchmark.studies.suite.cost import measure_cost

        return _done(log, cache, measure_cost(suite, items, cache, out))
    if stage in ("all", "fstar", "runs") and not opts["user"]:
        with Timer(log, "fstar_from_truth"):
            fstar_from_truth(items, cache)
        if stage == "fstar":
            return _done(log, cache, f"f* from the truth for {len(items)} instances")
    if stage in ("all", "runs"):
        jobs = jobs_for(suite, [d for d, _ in items])
        todo = pending(jobs, runs)
        print(f"{len(jobs)} runs in the suite, {len(todo)} to do", flush=True)
        configs = {d["name"]: c for d, c in items}
        with Timer(log, "runs_launcher"):
            log["sweeps"] = launch(todo, configs, suite, cache, runs, launcher_args(opts, passthrough),
                                   int(opts["chunk"]))
        log["runs"] = {"count": len(todo), "cpu_time_s": round(sum(s["cpu_time_s"] for s in log["sweeps"]), 1),
                       "wall_time_s": round(sum(s["wall_time_s"] for s in log["sweeps"]), 1)}
        if stage == "runs":
            return _done(log, cache, f"runs in {runs}")
    with Timer(log, "fstar_from_runs"):
        fstars = {} if opts["user"] else fstar_from_runs(items, cache, runs)
    with Timer(log, "report"):
        from benchmark.studies.suite.figures import write_figures
        from benchmark.studies.suite.measures import collect
        from benchmark.studies.suite.report import write_report

        docs = {str(Path(c["data"]["path"]).resolve()): d for d, c in items}
        results = collect(runs, docs, fstars)
        if not results:
            raise ConfigError(f"no runs under {runs}: run the suite first (stage=runs)")
        figures = write_figures(results, out, list(suite.optimizers) + list(
            {o for v in suite.problem_optimizers.values() for o in v}))
        write_report(results, fstars, out, figures, {"suite": suite.name, "command": log["command"]},
                     defaults=("multistart", *suite.variants))
    return _done(log, cache, f"{len(results)} instances -> {out / 'summary.md'}", out)


def _done(log: dict, cache: Path, message, out: Path | None = None) -> int:
    cache.mkdir(parents=True, exist_ok=True)
    prev = cache / "suite_log.json"
    history = json.loads(prev.read_text()) if prev.is_file() else []
    history.append(log)
    write_text_atomic(prev, json.dumps(history, indent=1) + "\n")
    if out is not None:
        write_text_atomic(out / "suite_log.json", json.dumps(log, indent=1) + "\n")
    print(message)
    return 0


def run(argv: list[str]) -> int:
    if any(a in ("-h", "--help", "help") for a in argv):
        print(__doc__)
        return 0
    try:
        return main(argv)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
