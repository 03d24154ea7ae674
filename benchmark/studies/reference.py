"""The reference table: every optimiser on each problem, then ``python -m benchmark.report``.

    python -m benchmark.studies.reference                  # ~15 min on 2 cores
    python -m benchmark.studies.reference seeds=3 budget=5000 out=/tmp/ref problems=[timedomain]

For each problem this runs one Hydra sweep through the default launcher (joblib, 2 jobs)::

    python -m benchmark -m problem=P optimizer=genesis,deap,pygad,nlopt_crs,scipy_de,cmaes,least_squares \\
        seed='range(10)' budget=20000 polish=false,true hydra.sweep.dir=OUT/runs/P \\
        hydra.sweep.subdir='${hydra:runtime.choices.optimizer}_polish${polish}_seed${seed}'

and then ``python -m benchmark.report OUT/runs out=OUT budgets=[1000,5000,20000]``. Arguments
(``key=value``): ``seeds`` (default 10), ``budget`` (20000), ``problems``
(``[timedomain,admittance]``), ``optimizers`` (the seven above), ``out`` (``results/reference``),
``budgets`` (fixed budgets of the report, default ``[1000,5000,20000]``); anything else is
passed to every run as a Hydra override. ``sweep.json`` in OUT records the commands and their
wall times.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import yaml

from benchmark.analysis import aggregate as report

OPTIMIZERS = ["genesis", "deap", "pygad", "nlopt_crs", "scipy_de", "cmaes", "least_squares"]
SUBDIR = "${hydra:runtime.choices.optimizer}_polish${polish}_seed${seed}"


def main(argv: list[str]) -> None:
    opts = {
        "seeds": 10,
        "budget": 20000,
        "problems": ["timedomain", "admittance"],
        "optimizers": OPTIMIZERS,
        "out": "results/reference",
        "budgets": [1000, 5000, 20000],
    }
    extra = []
    for a in argv:
        key, _, val = a.partition("=")
        if key in opts and val:
            opts[key] = val if key == "out" else yaml.safe_load(val)
        else:
            extra.append(a)
    out = Path(opts["out"])
    log = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "platform": platform.platform(),
        },
        "sweeps": [],
    }
    t_all = time.perf_counter()
    for problem in opts["problems"]:
        cmd = [
            sys.executable,
            "-m",
            "benchmark",
            "-m",
            f"problem={problem}",
            "optimizer=" + ",".join(opts["optimizers"]),
            f"seed=range({int(opts['seeds'])})",
            f"budget={int(opts['budget'])}",
            "polish=false,true",
            f"hydra.sweep.dir={out / 'runs' / problem}",
            f"hydra.sweep.subdir={SUBDIR}",
            "figures=false",  # the numbers only: figures would add 1-4 s to each of the 280 runs
            *extra,
        ]
        print("+", " ".join(cmd[1:]), flush=True)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, stdout=subprocess.DEVNULL)
        wall = time.perf_counter() - t0
        print(f"  {problem}: exit {proc.returncode}, {wall:.0f} s", flush=True)
        log["sweeps"].append(
            {
                "problem": problem,
                "command": "python " + " ".join(cmd[1:]),
                "exit_status": proc.returncode,
                "wall_time_s": round(wall, 1),
            }
        )
    log["wall_time_s"] = round(time.perf_counter() - t_all, 1)
    out.mkdir(parents=True, exist_ok=True)
    (out / "sweep.json").write_text(json.dumps(log, indent=1) + "\n")
    report.main([str(out / "runs"), f"out={out}", f"budgets={list(opts['budgets'])}".replace(" ", "")])


if __name__ == "__main__":
    main(sys.argv[1:])
