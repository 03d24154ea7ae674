"""Probes the performance benchmark runs in a fresh interpreter (so that imports, compilation
and the process exit are timed as a user meets them)::

    python -m benchmark.studies.perf.probes compile
    python -m benchmark.studies.perf.probes identify CONF_DIR BUDGET [OVERRIDE ...]

Each prints one JSON line. ``compile``: seconds to import the simulation and to compile each
kernel. ``identify``: the Table 1 identification through the harness, with the time spent in
``TimeDomainProblem.evaluate`` measured by wrapping it.
"""

import time

T0 = time.perf_counter()

import json  # noqa: E402
import sys  # noqa: E402


def compile_probe() -> dict:
    import numpy as np

    from benchmark.problems.timedomain import simulation as S
    from benchmark.problems.timedomain.motor import coefficients

    t1 = time.perf_counter()
    coef = coefficients(np.array([[4.96434, 0.1075, 0.01098, 1.55618, 0.00642, 0.00033, 0.04297]] * 20), 1)
    z = np.zeros(500)
    S.startup_cost_batch(coef, z, z, False, 1 / 12000, z, z, z, 1.0, np.array([1.0, 1.0, 0.5]), 1)
    t2 = time.perf_counter()
    S.startup_outputs_batch(coef, z, z, False, 1 / 12000, 1.0)
    t3 = time.perf_counter()
    S.simulate_states(coef[0], z, z, False, 1 / 12000, 4, np.zeros(5))
    t4 = time.perf_counter()
    return {"import": t1 - T0, "startup_cost_batch": t2 - t1, "startup_outputs_batch": t3 - t2,
            "simulate_states": t4 - t3}


def identify_probe(conf_dir: str, budget: str, overrides: list[str]) -> dict:
    import tempfile
    from pathlib import Path

    from hydra import compose, initialize_config_dir

    from benchmark.core.harness import run
    from benchmark.problems.timedomain.problem import TimeDomainProblem

    t_imports = time.perf_counter() - T0
    sim = {"total": 0.0, "first": None}
    evaluate = TimeDomainProblem.evaluate

    def timed_evaluate(self, X):
        t = time.perf_counter()
        try:
            return evaluate(self, X)
        finally:
            dt = time.perf_counter() - t
            sim["total"] += dt
            if sim["first"] is None:
                sim["first"] = dt

    TimeDomainProblem.evaluate = timed_evaluate
    with initialize_config_dir(config_dir=conf_dir, version_base="1.3"):
        run_config = compose("config", overrides=["+experiment=table1", "seed=0", "budget=" + budget, *overrides])
    t_composed = time.perf_counter() - T0
    rec = run(run_config, Path(tempfile.mkdtemp(prefix="imbench-perf-"))).record
    out = {k: rec[k] for k in ("evaluations", "cost", "wall_time_s", "wall_time_optimizer_s", "setup_time_s",
                               "rel_error", "status")}
    out.update(imports_s=t_imports, composed_s=t_composed, evaluate_s=sim["total"], first_evaluate_s=sim["first"],
               cpu_s=time.process_time(), inside_s=time.perf_counter() - T0)
    return out


if __name__ == "__main__":
    if sys.argv[1] == "compile":
        print(json.dumps(compile_probe()))
    else:
        print(json.dumps(identify_probe(sys.argv[2], sys.argv[3], sys.argv[4:])))
