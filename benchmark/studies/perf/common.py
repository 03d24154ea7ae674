"""Helpers of the performance benchmark: the paper's problem, best-of-n timing, the machine's
description, and table formatting."""

from __future__ import annotations

import math
import os
import platform
import resource
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

import numba
import numpy as np

from benchmark.core.config_files import CONFIG_DIR

ROOT = Path(__file__).resolve().parents[3]
CONF = str(CONFIG_DIR)


# -- small helpers ---------------------------------------------------------------------------
def compose(overrides):
    from hydra import compose as hydra_compose
    from hydra import initialize_config_dir

    with initialize_config_dir(config_dir=CONF, version_base="1.3"):
        return hydra_compose("config", overrides=list(overrides))


def run_timed(code: Path, module: str, args: list[str]) -> tuple[float, float, subprocess.CompletedProcess]:
    """(wall s, CPU s of the process and its threads, the finished process) of ``python -m module
    args`` in a fresh interpreter whose ``PYTHONPATH`` is the checkout ``code`` (its output captured)."""
    env = dict(os.environ, PYTHONPATH=str(code), MPLBACKEND="Agg")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", module, *args], cwd=str(code), env=env, capture_output=True,
                          text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), proc


def best_times(jobs: dict, rounds: int, cpu: dict | None = None) -> dict:
    """Best wall time of each job over ``rounds`` rounds, the jobs interleaved in each round.
    A job is ``(setup, fn)``: ``setup()`` runs untimed before each call of ``fn()``. With
    ``cpu`` (a dict), the best process CPU time of each job is stored there too."""
    best = {k: math.inf for k in jobs}
    for _ in range(rounds):
        for k, (setup, fn) in jobs.items():
            setup()
            c = time.process_time()
            t = time.perf_counter()
            fn()
            best[k] = min(best[k], time.perf_counter() - t)
            if cpu is not None:
                cpu[k] = min(cpu.get(k, math.inf), time.process_time() - c)
    return best


def fmt_rate(x: float) -> str:
    if not math.isfinite(x):
        return "-"
    if x >= 100:
        return f"{x:,.0f}"
    if x >= 1:
        return f"{x:.1f}"
    return f"{x:.3g}"


def md_table(header: list[str], rows: list[list]) -> str:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def machine() -> dict:
    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    flags = ""
    try:
        text = Path("/proc/cpuinfo").read_text()
        fl = next((ln for ln in text.splitlines() if ln.startswith("flags")), "")
        flags = " ".join(f for f in ("avx2", "fma", "avx512f") if f" {f}" in fl)
        fam = next((ln.split(":")[1].strip() for ln in text.splitlines() if ln.startswith("cpu family")), "?")
        mod = next((ln.split(":")[1].strip() for ln in text.splitlines() if ln.startswith("model\t")), "?")
        cpu = f"{cpu} (family {fam}, model {mod})"
    except (OSError, StopIteration):
        pass
    import llvmlite
    import llvmlite.binding as llvm
    import scipy

    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count()
    return {
        "cpu": cpu,
        "llvm_cpu": llvm.get_host_cpu_name(),
        "simd": flags,
        "logical_cpus": os.cpu_count(),
        "usable_cpus": affinity,
        "numba_threads": numba.config.NUMBA_NUM_THREADS,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "llvmlite": llvmlite.__version__,
        "os": platform.platform(),
        "imbench": _version("imbench"),
    }


def _version(name):
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return "-"
