"""The suite's runs: one harness run per (instance, optimiser, polish, seed), launched as Hydra
sweeps through the project's launchers (joblib here, SLURM through ``imbench_slurm``).

Each run is a small config file of a ``suite_job`` group, ``# @package _global_``, that sets
the instance (problem, data folder, bounds), the optimiser, ``seed``, ``polish`` and
``budget``. The runs still to do (no ``result.json`` in their folder yet) are written in
batches of at most ``chunk`` into ``CACHE/launch/PID-batchNNN/suite_job/`` and each batch is one
sweep::

    python -m benchmark -m --config-dir CACHE/launch/PID-batch000 '+suite_job=glob(*)' \\
        hydra.sweep.dir=CACHE/runs 'hydra.sweep.subdir=${hydra:runtime.choices.suite_job}' [launcher]

so every run writes the harness's ``result.json``, ``history.csv`` and journal in
``CACHE/runs/<job>/``, and a stopped suite resumes by launching what is missing (the harness's
own ``resume`` replays an interrupted run's journal when asked: ``resume=true`` in ``extra``).
A batch of at most 1000 fits a SLURM array on most clusters (``MaxArraySize``).
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import yaml

from benchmark.studies.suite.spec import SuiteSpec

HEADER = "# @package _global_\n# one run of the suite (benchmark/studies/suite/jobs.py)\n"
SUBDIR = "${hydra:runtime.choices.suite_job}"


@dataclass(frozen=True)
class Job:
    """One run: ``label`` is the optimiser as the measures name it (``cmaes+polish``, a variant's
    name), ``optimizer`` the config of ``conf/optimizer/``, ``options`` a variant's plugin options."""

    instance: str
    label: str
    optimizer: str
    polish: bool
    seed: int
    options: dict | None = None

    @property
    def id(self) -> str:
        return f"{self.instance}__{self.label.replace('+', '-')}__s{self.seed}"


def jobs_for(suite: SuiteSpec, instances: list[dict]) -> list[Job]:
    """Every run of the suite on ``instances`` (``instance.yaml`` documents)."""
    out = []
    for doc in instances:
        for seed in range(suite.seeds):
            for opt in suite.optimizers_for(doc["problem"]):
                for polish in (False, True):
                    out.append(Job(doc["name"], opt + ("+polish" if polish else ""), opt, polish, seed))
            for label, v in suite.variants.items():
                out.append(Job(doc["name"], label, str(v["optimizer"]), False, seed, dict(v.get("plugin") or {})))
    return out


def job_config(job: Job, harness_cfg: dict, suite: SuiteSpec) -> dict:
    defaults = []
    if harness_cfg["problem"] != "timedomain":
        defaults.append({"override /problem": harness_cfg["problem"]})
    defaults.append({"override /optimizer": job.optimizer})
    doc: dict = {"defaults": defaults, "data": {"path": harness_cfg["data"]["path"]}, "seed": job.seed,
                 "polish": job.polish, "budget": suite.budget, "polish_budget": suite.polish_budget,
                 "figures": False, "progress": False}
    if "bounds" in harness_cfg:
        doc["bounds"] = harness_cfg["bounds"]
    if harness_cfg.get("problem_options"):
        doc["problem"] = dict(harness_cfg["problem_options"])
    if job.options is not None:
        doc["optimizer"] = {"name": job.label, "plugin": job.options}
    return doc


def write_job(group: Path, job: Job, harness_cfg: dict, suite: SuiteSpec) -> Path:
    """The run's config file ``group/<job id>.yaml`` (a ``suite_job`` group option)."""
    path = Path(group) / f"{job.id}.yaml"
    path.write_text(HEADER + yaml.safe_dump(job_config(job, harness_cfg, suite), sort_keys=False))
    return path


def pending(jobs: list[Job], runs: Path) -> list[Job]:
    return [j for j in jobs if not (Path(runs) / j.id / "result.json").is_file()]


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def launch(jobs: list[Job], configs: dict[str, dict], suite: SuiteSpec, cache: Path, runs: Path,
           launcher: list[str], chunk: int = 1000) -> list[dict]:
    """Run ``jobs`` (their configs by instance name: ``instances.harness_config``) in sweeps of at
    most ``chunk``; returns per sweep its command, exit status, wall and CPU seconds (CPU: the
    sweep's processes and their workers, from the kernel's accounting of reaped children)."""
    log = []
    runs = Path(runs).resolve()
    for k in range(0, len(jobs), chunk):
        batch = jobs[k:k + chunk]
        # one folder per launching process: two suite processes on one cache (say, one per
        # problem) must not delete each other's job files, which a sweep's jobs read when they start
        folder = Path(cache).resolve() / "launch" / f"{os.getpid()}-batch{k // chunk:03d}"
        group = folder / "suite_job"
        group.mkdir(parents=True, exist_ok=True)
        for old in group.glob("*.yaml"):
            old.unlink()
        for j in batch:
            write_job(group, j, configs[j.instance], suite)
        cmd = [sys.executable, "-m", "benchmark", "-m", "--config-dir", str(folder), "+suite_job=glob(*)",
               f"hydra.sweep.dir={runs}", f"hydra.sweep.subdir={SUBDIR}", *launcher]
        print(f"+ sweep {k // chunk + 1}: {len(batch)} runs: python " + " ".join(cmd[1:]), flush=True)
        t0, c0 = time.perf_counter(), _children_cpu()
        with (folder / "sweep.log").open("w") as fh:
            proc = subprocess.run(cmd, stdout=fh, stderr=subprocess.STDOUT)
        entry = {"runs": len(batch), "command": "python " + " ".join(cmd[1:]), "exit_status": proc.returncode,
                 "wall_time_s": round(time.perf_counter() - t0, 1), "cpu_time_s": round(_children_cpu() - c0, 1)}
        print(f"  exit {proc.returncode}, {entry['wall_time_s']} s wall, {entry['cpu_time_s']} s CPU", flush=True)
        log.append(entry)
        (folder / "sweep.json").write_text(json.dumps(entry, indent=1) + "\n")
    return log
