"""The measured cost of a suite (``stage=cost``): CPU seconds per run on a sample of its
instances, extrapolated to every run of the suite. Clearly an extrapolation: the sample's runs
are run, the others are not.

For ``sample`` instances spread evenly over the suite's list (time domain and admittance in
proportion), every optimiser label of the suite (polish off and on, the variants) runs once
(seed 0) through the harness in this process, timed with ``time.process_time`` (with
``NUMBA_NUM_THREADS=1``, as in a sweep's worker). One of them also runs as its own process,
``python -m benchmark``, as a SLURM task does: the difference is a task's start-up cost (imports,
compiled-code cache, configuration). The estimate per problem is the sample's mean CPU per run
times the suite's runs of that problem, plus, on SLURM (one process per run), the start-up cost
per run. Written to ``OUT/cost.json`` and ``OUT/cost.md``.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from omegaconf import open_dict

from benchmark.core.io import write_text_atomic
from benchmark.studies.suite.fstar import compose_run
from benchmark.studies.suite.jobs import Job, jobs_for, write_job


def sample_instances(instances: list, k: int) -> list:
    """``k`` instances (``InstanceSpec``) spread evenly over each problem's list, in proportion to
    its size."""
    out = []
    for prob in sorted({i.problem for i in instances}):
        mine = [i for i in instances if i.problem == prob]
        n = max(1, round(k * len(mine) / len(instances)))
        idx = np.unique(np.linspace(0, len(mine) - 1, min(n, len(mine))).round().astype(int))
        out += [mine[i] for i in idx]
    return out


def run_in_process(job: Job, cfg: dict, suite, outdir: Path) -> float:
    """CPU seconds of one run through the harness in this process."""
    from benchmark.core.harness import run

    ov = [f"optimizer={job.optimizer}", f"seed={job.seed}", f"polish={str(job.polish).lower()}",
          f"budget={suite.budget}", f"polish_budget={suite.polish_budget}"]
    conf = compose_run(cfg, ov)
    if job.options is not None:
        with open_dict(conf):
            conf.optimizer.name = job.label
            for k, v in job.options.items():
                conf.optimizer.plugin[k] = v
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run(conf, outdir)
    return time.process_time() - t0


def startup_cost(job: Job, cfg: dict, suite, cache: Path, in_process_cpu: float) -> float:
    """CPU seconds a run costs more as its own ``python -m benchmark`` process than in a worker."""
    folder = cache / "cost" / "launch"
    (folder / "suite_job").mkdir(parents=True, exist_ok=True)
    write_job(folder / "suite_job", job, cfg, suite)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-m", "benchmark", "--config-dir", str(folder), f"+suite_job={job.id}",
                    f"hydra.run.dir={cache / 'cost' / 'process_run'}"], stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, env={**os.environ, "NUMBA_NUM_THREADS": "1"}, check=False)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime) - in_process_cpu


def measure_cost(suite, chosen: list, cache: Path, out: Path) -> str:
    """``chosen``: the sampled instances' (document, harness config) (module docstring)."""
    cpu: dict[str, list[float]] = {}
    per_label: dict[str, list[float]] = {}
    first = None
    for doc, cfg in chosen:
        for job in jobs_for(suite, [doc]):
            if job.seed != 0:
                continue
            c = run_in_process(job, cfg, suite, cache / "cost" / "runs" / job.id)
            cpu.setdefault(doc["problem"], []).append(c)
            per_label.setdefault(job.label, []).append(c)
            print(f"  {job.id}: {c:.2f} CPU s", flush=True)
            if first is None:
                first = (job, cfg, c)
    startup = startup_cost(first[0], first[1], suite, cache, first[2]) if first else 0.0
    everything = [{"name": i.name, "problem": i.problem} for i in suite.instances]
    n_runs = {p: len(jobs_for(suite, [d for d in everything if d["problem"] == p])) for p in cpu}
    est = {p: {"runs": n_runs[p], "sampled_runs": len(v), "cpu_per_run_s": float(np.mean(v)),
               "core_hours": n_runs[p] * float(np.mean(v)) / 3600} for p, v in cpu.items()}
    total = sum(e["core_hours"] for e in est.values())
    slurm = total + sum(n_runs.values()) * startup / 3600
    doc = {"suite": suite.name, "instances": len(suite.instances), "sampled_instances": [d["name"] for d, _ in chosen],
           "seeds": suite.seeds, "budget": suite.budget, "per_problem": est,
           "cpu_per_run_by_optimizer_s": {k: float(np.mean(v)) for k, v in sorted(per_label.items())},
           "startup_cpu_per_process_s": startup, "core_hours_workers": total, "core_hours_slurm": slurm,
           "note": "EXTRAPOLATED from the sampled runs (seed 0 of every optimiser on the sampled instances)"}
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "cost.json", json.dumps(doc, indent=1) + "\n")
    lines = [f"# Measured cost of the `{suite.name}` suite (extrapolated)", "",
             f"{len(chosen)} of {len(suite.instances)} instances sampled; every optimiser once (seed 0), budget "
             f"{suite.budget}, one core each (`NUMBA_NUM_THREADS=1`).", "",
             "| problem | runs in the suite | sampled runs | CPU s per run (mean) | core-hours (extrapolated) |",
             "|---|---|---|---|---|"]
    lines += [f"| {p} | {e['runs']} | {e['sampled_runs']} | {e['cpu_per_run_s']:.2f} | {e['core_hours']:.1f} |"
              for p, e in est.items()]
    lines += ["", f"Total: **{total:.1f} core-hours** in workers that run many runs each (joblib); "
              f"**{slurm:.1f} core-hours** on SLURM, where each run is its own process "
              f"(start-up measured at {startup:.1f} CPU s per process).", ""]
    write_text_atomic(out / "cost.md", "\n".join(lines))
    return f"extrapolated cost: {total:.1f} core-hours (workers), {slurm:.1f} on SLURM -> {out / 'cost.md'}"


def record_samples(suite) -> dict[str, float]:
    """Samples of every time-domain instance's record (``instances.record_settings``), by name."""
    from benchmark.studies.suite.instances import record_settings
    from synthetic.zoo import get_motor

    return {i.name: float(np.prod(record_settings(get_motor(i.motor), i, suite.records)))
            for i in suite.instances if i.problem == "timedomain"}


def scaled_cost(measured_cpu: dict[str, float], measured_runs: dict[str, int], small, full,
                startup_s: float) -> dict:
    """Another suite's cost from a finished suite's measured CPU seconds per problem
    (``measured_cpu``, over ``measured_runs`` runs): CPU per run scaled by evaluations
    (budget + polish) and, on the time domain, by the mean record length in samples (an
    evaluation's cost is proportional to it; the run's fixed cost is scaled too, so the
    estimate errs high). On SLURM every run is its own process: ``startup_s`` CPU seconds more."""
    evals = (full.budget + full.polish_budget) / (small.budget + small.polish_budget)
    length = np.mean(list(record_samples(full).values())) / np.mean(list(record_samples(small).values()))
    everything = [{"name": i.name, "problem": i.problem} for i in full.instances]
    out = {}
    for prob, cpu in measured_cpu.items():
        per_run = cpu / measured_runs[prob] * evals * (length if prob == "timedomain" else 1.0)
        runs = len(jobs_for(full, [d for d in everything if d["problem"] == prob]))
        out[prob] = {"cpu_per_run_s": per_run, "runs": runs, "core_hours": runs * per_run / 3600}
    total = sum(v["core_hours"] for v in out.values())
    n = sum(v["runs"] for v in out.values())
    return {"per_problem": out, "evaluations_ratio": evals, "record_length_ratio": float(length),
            "core_hours_workers": total, "core_hours_slurm": total + n * startup_s / 3600}
