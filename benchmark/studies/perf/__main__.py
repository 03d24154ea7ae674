"""Performance benchmark of the simulation and the identification (issue 6).

::

    python -m benchmark.studies.perf                 # full run, writes results/perf.md (a few minutes)
    python -m benchmark.studies.perf quick=true      # fewer repeats, shorter references (about a minute)
    python -m benchmark.studies.perf out=/tmp/p.md   # write the report elsewhere
    python -m benchmark.studies.perf reference=DIR   # the diagnoses against an earlier checkout too

What it measures, all in one run (so ratios compare like with like on a shared machine):

1. **Start-up cost throughput**: evaluations per second of the paper's Table 1 problem (1 s
   start-up at 12 kHz of ``conf/motor/alonge_1kw.yaml``, eq. 15, ka = kb = 1, kw = 0.5, through
   ``TimeDomainProblem.evaluate``) on 1 and 2 threads (``numba.set_num_threads``) for populations
   of 1, 100 and 1000 drawn uniformly within the preset's bounds.
2. **References**, written here independently of :mod:`benchmark.problems.timedomain.simulation`:

   * ``scipy.integrate.solve_ivp`` (RK45, ``rtol = 1e-6``, ``atol = 1e-8``) of the same model,
     one candidate at a time. The inverter voltage is piecewise constant (zero-order hold), so
     the record is cut into its runs of equal voltage samples (300 for the six-step start-up:
     the voltage changes every 40 samples) and each run is one ``solve_ivp`` call from the
     state at its start, with ``t_eval`` at the sample instants inside it: the integrator never
     steps across a voltage jump and no interpolation of the input is involved. Coulomb
     friction: ``fc sign(w)`` while turning, stiction at ``w = 0`` while ``|T| <= fc``.
   * a plain NumPy RK4 vectorised over the population (the same fixed-step scheme as the
     compiled kernel, every operation an array operation over the candidates).

   Both are timed in this run; the ratios are compiled-kernel evaluations per second over
   theirs. The agreement of the costs is printed too.
3. **Scaling** with record length (0.25, 0.5, 1, 2 s at 12 kHz) and sample rate (6, 12, 24 kHz
   for 1 s): time per evaluation and per sample; "linear" when every time per sample is within
   10 % of their median.
4. **Admittance cost** (``benchmark.problems.admittance.problem``, if present): evaluations per second of
   ``AdmittanceProblem.evaluate`` for a 100-point slip sweep.
5. **Compile time** of the simulation kernels in a fresh interpreter with an empty
   ``NUMBA_CACHE_DIR`` (cold), then again with that cache filled (warm).
6. **Identification end to end**: ``benchmark.core.harness.run`` with ``+experiment=table1`` (60000
   GENESIS trials) in a fresh interpreter, wall time from process start to exit, cold cache
   (compile included) and warm cache, on 2 threads (and warm on 1 thread).
7. **Diagnosis**: ``python -m benchmark.diagnose data.path=DIR`` of the fourteen records of
   :mod:`.diagnosis_records` (three sources; DOL, six-step and PWM starts; with and without a
   stop record; 1 to 7.5 kW, 2 to 6 poles; the last two a load the catalogue has no form for),
   each in a fresh interpreter with a warm cache; with ``reference=DIR`` (an earlier checkout)
   the reference diagnoses each record right before, and the report checks the verdicts against
   it (:mod:`.diagnosis_report`).

Timings are the best of several repeats, interleaved across the configurations so that load
from other processes spreads over all of them; the load average is recorded.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numba
import numpy as np

from benchmark.core.harness import build_problem
from benchmark.studies.perf.common import (
    CONF,
    ROOT,
    best_times,
    compose,
    machine,
)
from benchmark.studies.perf.references import eq15_cost, numpy_rk4_cost, solve_ivp_outputs
from benchmark.studies.perf.report import report


def parse_args(argv: list[str]) -> dict:
    opts = {"quick": False, "out": str(ROOT / "results" / "perf.md"), "reference": None}
    for a in argv:
        if "=" not in a:
            raise SystemExit(f"benchmark.studies.perf: expected key=value arguments (quick=true, out=PATH), got {a!r}")
        k, v = a.split("=", 1)
        if k == "quick":
            opts["quick"] = v.lower() in ("1", "true", "yes")
        elif k == "out":
            opts["out"] = v
        elif k == "reference":
            opts["reference"] = v
        else:
            raise SystemExit(f"benchmark.studies.perf: unknown key {k!r}; known: quick, out, reference")
    return opts



# -- the sections -------------------------------------------------------------------------------
def paper_problem():
    from benchmark.core.harness import build_problem

    return build_problem(compose(["+experiment=table1"]))


def population(problem, n: int, seed: int = 12345) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return problem.lower + (problem.upper - problem.lower) * rng.random((n, problem.n_var))


def section_throughput(problem, X, quick: bool) -> dict:
    thread_counts = [t for t in (1, 2) if t <= numba.config.NUMBA_NUM_THREADS]
    pops = (1, 100, 1000)
    problem.evaluate(X[:3])  # compile or load from cache
    jobs = {}
    for nt in thread_counts:
        for n in pops:
            jobs[(nt, n)] = (lambda nt=nt: numba.set_num_threads(nt), lambda n=n: problem.evaluate(X[:n]))
    rounds = 3 if quick else 7
    cpu: dict = {}
    best = best_times(jobs, rounds, cpu)
    # pop 1 calls are short: repeat them more
    small = {k: v for k, v in jobs.items() if k[1] == 1}
    for k, v in best_times(small, 20 if quick else 60, cpu).items():
        best[k] = min(best[k], v)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    return {
        "rates": {k: k[1] / t for k, t in best.items()},
        "cpu_rates": {k: k[1] / t for k, t in cpu.items()},
        "threads": thread_counts,
        "pops": pops,
    }


def section_references(problem, X, quick: bool) -> dict:
    from benchmark.problems.timedomain.motor import coefficients
    from benchmark.problems.timedomain.simulation import startup_cost_batch, startup_outputs_batch

    ds = problem.dataset
    rec = ds.startups[0]
    p = float(ds.pole_pairs)
    h = ds.sample_time
    meas = np.stack([rec.i_alpha, rec.i_beta, rec.speed])
    theta = problem.full_parameters(X)
    w, e = problem.weights, problem.exponent
    if ds.input_hold != "zoh":
        raise RuntimeError("the references implement the zero-order hold (the paper's six-step start-up)")

    def kernel(th):
        return startup_cost_batch(
            coefficients(th, ds.pole_pairs),
            rec.v_alpha,
            rec.v_beta,
            False,
            h,
            rec.i_alpha,
            rec.i_beta,
            rec.speed,
            p,
            w,
            e,
        )

    # solve_ivp: one candidate at a time
    n_ivp = 1 if quick else 2
    ivp_times, ivp_costs, traj_err = [], [], []
    for m in range(n_ivp):
        t0 = time.perf_counter()
        sim = solve_ivp_outputs(theta[m], p, rec.t, rec.v_alpha, rec.v_beta)
        ivp_times.append(time.perf_counter() - t0)
        ivp_costs.append(eq15_cost(sim, meas, w, e))
        rk4 = startup_outputs_batch(
            coefficients(theta[m : m + 1], ds.pole_pairs), rec.v_alpha, rec.v_beta, False, h, p
        )[0]
        traj_err.append(float(np.max(np.abs(rk4[:2] - sim[:2])) / np.max(np.abs(sim[:2]))))
    kern_costs = kernel(theta[:n_ivp])
    ivp_rate = n_ivp / sum(ivp_times)

    # numpy RK4 over the population
    np_pops = (100,) if quick else (100, 1000)
    np_rate, np_agree = {}, 0.0
    for n in np_pops:
        t0 = time.perf_counter()
        c_np = numpy_rk4_cost(theta[:n], p, rec.v_alpha, rec.v_beta, h, meas, w, e)
        np_rate[n] = n / (time.perf_counter() - t0)
        c_k = kernel(theta[:n])
        fin = np.isfinite(c_k)
        if not np.array_equal(np.isfinite(c_np), fin):
            np_agree = math.inf
        else:
            np_agree = max(np_agree, float(np.max(np.abs(c_np[fin] / c_k[fin] - 1.0), initial=0.0)))
    return {
        "ivp_rate": ivp_rate,
        "ivp_seconds": ivp_times,
        "ivp_cost_rel": [abs(a / b - 1) for a, b in zip(ivp_costs, kern_costs, strict=True)],
        "ivp_traj_rel": traj_err,
        "np_rate": np_rate,
        "np_agree": np_agree,
    }


def section_scaling(problem, X, quick: bool) -> dict:
    from benchmark.problems.timedomain.motor import coefficients
    from benchmark.problems.timedomain.protocol import StartupStopTest
    from benchmark.problems.timedomain.simulation import simulate_states, startup_cost_batch

    motor_p = problem.dataset.pole_pairs
    truth = problem.full_parameters(np.array([[problem.truth[n] for n in problem.parameter_names]]))
    c_truth = coefficients(truth, motor_p)[0]
    n_pop = 200 if quick else 1000
    coef = coefficients(problem.full_parameters(X[:n_pop]), motor_p)
    weights, exponent, p = problem.weights, problem.exponent, float(motor_p)

    def record(rate_khz: float, seconds: float):
        ts = 1.0 / (rate_khz * 1000.0)
        spc = int(round(40 * rate_khz / 12.0))  # samples per six-step state: 50 Hz at every rate
        cycles = int(math.ceil(seconds * 50.0))
        _, v_a, v_b = StartupStopTest(sample_time=ts, samples_per_state=spc, cycles=cycles).startup_voltages()
        n = int(round(seconds / ts))
        v_a, v_b = v_a[:n].copy(), v_b[:n].copy()
        x = simulate_states(c_truth, v_a, v_b, False, ts, 4, np.zeros(5))
        return (v_a, v_b, False, ts, x[:, 0].copy(), x[:, 1].copy(), x[:, 4] / p)

    cases = {("length", s): record(12.0, s) for s in (0.25, 0.5, 1.0, 2.0)}
    cases.update({("rate", r): record(r, 1.0) for r in (6.0, 24.0)})
    cases[("rate", 12.0)] = cases[("length", 1.0)]
    jobs = {k: (lambda: None, lambda a=a: startup_cost_batch(coef, *a, p, weights, exponent)) for k, a in cases.items()}
    cpu: dict = {}
    best = best_times(jobs, 3 if quick else 7, cpu)
    rows = {}
    for k, a in cases.items():
        n = len(a[0])
        rows[k] = {
            "samples": n,
            "per_eval_us": best[k] / n_pop * 1e6,
            "per_sample_ns": best[k] / n_pop / n * 1e9,
            "cpu_per_sample_ns": cpu[k] / n_pop / n * 1e9,
        }
    med = float(np.median([r["per_sample_ns"] for r in rows.values()]))
    med_cpu = float(np.median([r["cpu_per_sample_ns"] for r in rows.values()]))
    dev = max(abs(r["per_sample_ns"] / med - 1) for r in rows.values())
    dev_cpu = max(abs(r["cpu_per_sample_ns"] / med_cpu - 1) for r in rows.values())
    # affine fit of the CPU time per evaluation against the number of samples
    N = np.array([r["samples"] for r in rows.values()], float)
    T = np.array([r["cpu_per_sample_ns"] * r["samples"] for r in rows.values()])
    slope, intercept = np.polyfit(N, T, 1)
    return {
        "rows": rows,
        "median_ns": med,
        "median_cpu_ns": med_cpu,
        "max_dev": dev,
        "max_dev_cpu": dev_cpu,
        "intercept_us": intercept / 1e3,
        "slope_ns": slope,
        "linear": dev_cpu <= 0.10,
        "n_pop": n_pop,
        "threads": numba.get_num_threads(),
    }


def section_admittance(quick: bool) -> dict:
    try:
        run_config = compose(["problem=admittance", f"motor.test.speed_step_rpm={4200.0 / 99.0!r}"])
        problem = build_problem(run_config)
        n_points = len(problem.data.slip)
        X = population(problem, 1000)
        problem.evaluate(X[:2])
        jobs = {n: (lambda: None, lambda n=n: problem.evaluate(X[:n])) for n in (1, 100, 1000)}
        best = best_times(jobs, 5 if quick else 15)
        return {
            "available": True,
            "n_points": n_points,
            "rates": {n: n / t for n, t in best.items()},
            "finite": int(np.isfinite(problem.evaluate(X)).sum()),
        }
    except Exception as exc:  # the admittance cost is written concurrently; report, do not fail
        return {"available": False, "reason": f"{type(exc).__name__}: {exc}"}


def _run_probe(probe: str, args: list[str], cache_dir: str, threads: int | None = None) -> tuple[dict, float]:
    """Run ``python -m benchmark.studies.perf.probes PROBE ARGS`` in a fresh interpreter with its
    own numba cache; returns its JSON line and the process's wall time (s)."""
    env = dict(
        os.environ,
        NUMBA_CACHE_DIR=cache_dir,
        PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
    )
    if threads is not None:
        env["NUMBA_NUM_THREADS"] = str(threads)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "benchmark.studies.perf.probes", probe, *args], env=env,
                          cwd=str(ROOT), capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"probe failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1]), wall


def section_compile() -> dict:
    with tempfile.TemporaryDirectory(prefix="imbench-numba-cache-") as d:
        cold, cold_wall = _run_probe("compile", [], d)
        warm, warm_wall = _run_probe("compile", [], d)
    return {"cold": cold, "warm": warm, "cold_wall": cold_wall, "warm_wall": warm_wall}


def section_identification(quick: bool) -> dict:
    budget = "6000" if quick else "60000"
    runs = {}
    with tempfile.TemporaryDirectory(prefix="imbench-numba-cache-") as d:
        runs["cold cache, 2 threads"] = _run_probe("identify", [CONF, budget], d, threads=2)
        runs["warm cache, 2 threads"] = _run_probe("identify", [CONF, budget], d, threads=2)
        runs["warm cache, 2 threads, figures=false"] = _run_probe(
            "identify", [CONF, budget, "figures=false"], d, threads=2
        )
        if not quick:
            runs["warm cache, 1 thread"] = _run_probe("identify", [CONF, budget], d, threads=1)
    return {"budget": int(budget), "runs": runs}


def section_diagnosis(reference: str | None = None, say=print) -> dict:
    """The diagnosis of each record of :mod:`.diagnosis_records` (fresh interpreters, warm caches;
    with ``reference``, a checkout diagnosed right before on each record): :mod:`.diagnosis_runs`."""
    from benchmark.studies.perf.diagnosis_records import make_records
    from benchmark.studies.perf.diagnosis_runs import run_all

    with tempfile.TemporaryDirectory(prefix="imbench-perf-records-") as d:
        records = make_records(Path(d) / "records")
        runs = run_all(records, ROOT, Path(d) / "runs", Path(reference).resolve() if reference else None, say=say)
    return {"runs": runs, "reference": reference}


def main(argv=None) -> int:
    opts = parse_args(sys.argv[1:] if argv is None else argv)
    quick = opts["quick"]
    started = datetime.now(timezone.utc)
    t_start = time.perf_counter()
    load0 = os.getloadavg()[0]

    def say(msg):
        print(f"[perf {time.perf_counter() - t_start:6.1f}s] {msg}", flush=True)

    m = machine()
    say(f"machine: {m['cpu']}, {m['usable_cpus']} cpus, numba {m['numba']}")
    say("setting up the Table 1 problem (synthetic paper data)")
    problem = paper_problem()
    X = population(problem, 1000)
    say("start-up cost throughput")
    thr = section_throughput(problem, X, quick)
    for (t, n), r in sorted(thr["rates"].items()):
        say(f"  {t} thread(s), population {n}: {r:,.0f} evals/s")
    say("references: solve_ivp and NumPy RK4")
    ref = section_references(problem, X, quick)
    say(f"  solve_ivp {ref['ivp_rate']:.3g} evals/s, NumPy RK4 {ref['np_rate']}")
    say("scaling with record length and sample rate")
    scal = section_scaling(problem, X, quick)
    say(f"  max deviation of time per sample {100 * scal['max_dev']:.1f} %")
    say("admittance cost")
    adm = section_admittance(quick)
    say(f"  {adm.get('rates', adm.get('reason'))}")
    say("compile time (fresh interpreters)")
    comp = section_compile()
    say(f"  cold {comp['cold']}, warm {comp['warm']}")
    say("identification end to end (fresh interpreters)")
    ident = section_identification(quick)
    for name, (rec, wall) in ident["runs"].items():
        say(f"  {name}: {wall:.2f} s wall, {rec['evaluations']} evaluations")
    say("diagnoses of the perf records (fresh interpreters, warm caches)")
    diag = section_diagnosis(opts["reference"], say=lambda s: say("  " + s))
    load1 = os.getloadavg()[0]
    text = report(m, thr, ref, scal, adm, comp, ident, opts, started, load0, load1, time.perf_counter() - t_start,
                  diag)
    print()
    print(text)
    out = Path(opts["out"])
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    say(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
