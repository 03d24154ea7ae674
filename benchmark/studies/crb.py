"""Accuracy against the physical limit: RMS errors over noise realisations vs the Cramer-Rao bound.

    python -m benchmark.studies.crb                      # 20 realisations, ~5-10 min on 2 cores
    python -m benchmark.studies.crb seeds=5 out=/tmp/crb.md rundir=/tmp/crb_runs

On the ``noisy`` preset (white current noise ``current_std``, speed noise ``speed_std`` then
quantised to ``speed_quantum``) the time-domain problem is identified over ``seeds``
realisations (``noise.seed = 0 .. seeds-1``) by one Hydra sweep (default joblib launcher)::

    python -m benchmark -m noise=noisy noise.seed='range(20)' optimizer=least_squares,scipy_de,cmaes
        polish=false,true budget=20000 problem.cost.exponent=2
        problem.cost.weights.i_alpha=1/sc^2 problem.cost.weights.i_beta=1/sc^2
        problem.cost.weights.speed=1/sw^2

with ``sc = current_std`` and ``sw^2 = speed_std^2 + speed_quantum^2/12`` (the quantisation
error of a step q is about uniform, variance q^2/12, at these levels). With eq. 14 and weights
1/sigma^2 the cost is -2 log-likelihood of Gaussian white noise up to a constant, so its
minimiser is the maximum-likelihood estimate and its errors can be compared with the bound.

The bounds (Fisher information of Gaussian white noise, sensitivities by central finite
differences of ``TimeDomainProblem.simulate`` at the truth; the identification model, not the
finer plant):

* **joint** (all 7 parameters, both records): start-up information on
  ``(Rs, Ls, Le, Rr, J, fv, fc)`` from ``d(i_alpha, i_beta, speed)/d theta``, plus the free stop's
  information on ``tau_m = J/fv`` and ``fc/J`` (closed-form free motion with its start speed
  ``w0`` as a nuisance parameter), summed, inverted. The limit for any unbiased estimator that
  uses both records; the two-stage estimator (stop fit first) is not obliged to reach it.
* **conditional** (the 5 searched parameters): ``fv = J/tau_m`` and ``fc = J fc/J`` are
  derived from the free stop, so the search is over ``Rs, Ls, Le, Rr, J`` only; this bound
  treats ``tau_m`` and ``fc/J`` as exactly known (start-up information only, through ``J``'s
  effect on all three). fv and fc then share J's relative bound. It is the bound of the
  start-up stage as posed; their real errors also carry the stop fit's error, which the joint
  bound accounts for.
* **start-up only** (all 7, no stop record): shows what the stop record adds.

Outputs: ``out`` (Markdown, default ``results/crb.md``) and the same numbers as JSON beside it.
Arguments (``key=value``): ``seeds`` (20), ``optimizers`` ([least_squares, scipy_de, cmaes]),
``budget`` (20000), ``rundir`` (``outputs/crb``), ``reuse`` (true: keep runs already in rundir,
run only the missing ones), ``out``; anything else is passed to every run as a Hydra override.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import yaml
from hydra import compose, initialize_config_dir
from scipy import stats

from benchmark.core.config_files import CONFIG_DIR
from benchmark.core.harness import build_problem, run
from benchmark.core.io import write_text_atomic
from benchmark.problems.timedomain.mechanical import fit_free_stop

CONF = str(CONFIG_DIR)
NAMES7 = ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")
NAMES5 = ("Rs", "Ls", "Le", "Rr", "J")
SUBDIR = "${hydra:runtime.choices.optimizer}_polish${polish}_noise${noise.seed}"


def compose_run_config(overrides):
    with initialize_config_dir(config_dir=CONF, version_base="1.3"):
        return compose("config", overrides=list(overrides))


def noise_levels(noise) -> tuple[float, float]:
    """(current sigma in A, speed sigma in rad/s) of a noise preset (the ``noise`` section of a run
    configuration), quantisation included."""
    n = noise
    sc = float(n.current_std)
    sw = math.sqrt(float(n.speed_std) ** 2 + float(n.speed_quantum) ** 2 / 12.0)
    return sc, sw


def ml_overrides(sc: float, sw: float) -> list[str]:
    return [
        "problem.cost.exponent=2",
        f"problem.cost.weights.i_alpha={1 / sc**2!r}",
        f"problem.cost.weights.i_beta={1 / sc**2!r}",
        f"problem.cost.weights.speed={1 / sw**2!r}",
    ]


# -- bounds --------------------------------------------------------------------------------------
def startup_fisher(problem, theta: np.ndarray, sc: float, sw: float, rel_step: float = 1e-5) -> np.ndarray:
    """Fisher information of the start-up records on the 7 physical parameters: sum over samples
    and channels of (d y/d theta)^T (d y/d theta) / sigma^2, central differences at ``theta``."""
    n = len(theta)
    h = rel_step * np.abs(theta)
    X = np.vstack([theta + np.diag(h), theta - np.diag(h)])
    F = np.zeros((n, n))
    inv_var = np.array([1 / sc**2, 1 / sc**2, 1 / sw**2])
    for sim in problem.simulate(X):  # one (2n, 3, N) array per start-up record
        S = (sim[:n] - sim[n:]) / (2 * h)[:, None, None]  # (n, 3, N)
        for c in range(3):
            F += inv_var[c] * S[:, c, :] @ S[:, c, :].T
    return F


def stop_fisher(t_free_motion: np.ndarray, w0: float, tau: float, b: float, sw: float) -> np.ndarray:
    """Fisher information of the free-motion samples on (w0, tau_m, fc/J), from the closed form
    w(t) = (w0 + tau b) exp(-t/tau) - tau b while w > 0 (after that the rotor rests: no
    information)."""
    t = np.asarray(t_free_motion, float)
    e = np.exp(-t / tau)
    w = (w0 + tau * b) * e - tau * b
    t, e = t[w > 0], e[w > 0]
    D = np.column_stack([e, b * e + (w0 + tau * b) * e * t / tau**2 - b, tau * e - tau])
    return D.T @ D / sw**2


def bounds(theta: np.ndarray, F7: np.ndarray, F_stop: np.ndarray) -> dict[str, np.ndarray]:
    """Standard deviations: joint (7, start-up + stop), conditional (5 searched, tau_m and fc/J
    known; fv, fc with J's relative bound), start-up only (7)."""
    Rs, Ls, Le, Rr, J, fv, fc = theta
    # (tau_m, fc/J, w0) as functions of (theta7, w0)
    G = np.zeros((3, 8))
    G[0, 4], G[0, 5] = 1 / fv, -J / fv**2
    G[1, 4], G[1, 6] = -fc / J**2, 1 / J
    G[2, 7] = 1.0
    P = F_stop[[1, 2, 0]][:, [1, 2, 0]]  # reorder (w0, tau, b) -> (tau, b, w0)
    F8 = np.zeros((8, 8))
    F8[:7, :7] = F7
    F8 += G.T @ P @ G
    joint = np.sqrt(np.diag(np.linalg.inv(F8))[:7])
    T = np.zeros((7, 5))
    T[:5, :5] = np.eye(5)
    T[5, 4], T[6, 4] = fv / J, fc / J
    cond5 = np.sqrt(np.diag(np.linalg.inv(T.T @ F7 @ T)))
    cond = np.concatenate([cond5, [cond5[4] * fv / J, cond5[4] * fc / J]])
    startup_only = np.sqrt(np.diag(np.linalg.inv(F7)))
    return {"joint": joint, "conditional": cond, "startup_only": startup_only}


def compute_bounds(extra: list[str]) -> dict:
    """Everything the bounds need, from the noise-free data of the ``noisy`` preset's motor."""
    noisy_config = compose_run_config(["noise=noisy", *extra])
    sc, sw = noise_levels(noisy_config.noise)
    # 7-parameter problem (no stop record: fv, fc searched) on noise-free data: only its
    # voltages and simulate() are used
    config7 = compose_run_config(["noise=none", "motor.record_stop=false", *ml_overrides(sc, sw), *extra])
    problem7 = build_problem(config7)
    if tuple(problem7.parameter_names) != NAMES7:
        raise RuntimeError(f"expected the 7-parameter problem, got {problem7.parameter_names}")
    theta = np.array([float(config7.motor.parameters[n]) for n in NAMES7])
    F7 = startup_fisher(problem7, theta, sc, sw)
    F7_check = startup_fisher(problem7, theta, sc, sw, rel_step=1e-4)
    # free stop of the noise-free data: where the free motion starts, and its start speed
    from synthetic.timedomain import make_dataset

    config0 = compose_run_config(["noise=none", *extra])
    ds, _ = make_dataset(config0)
    stop = ds.stops[0]
    mech = fit_free_stop(stop.t, stop.speed, case=int(config0.problem.get("friction_case", 2)))
    t_fm = stop.t[stop.t >= mech.t_free] - mech.t_free
    Rs, Ls, Le, Rr, J, fv, fc = theta
    tau, b = J / fv, fc / J
    Fs = stop_fisher(t_fm, mech.w0, tau, b, sw)
    out = bounds(theta, F7, Fs)
    step_change = np.max(np.abs(bounds(theta, F7_check, Fs)["joint"] / out["joint"] - 1))
    stop_only = np.sqrt(np.diag(np.linalg.inv(Fs)))  # (w0, tau, b)
    return {
        "theta": theta,
        "sc": sc,
        "sw": sw,
        "bounds": out,
        "fd_step_sensitivity": float(step_change),
        "tau": tau,
        "b": b,
        "stop_bound": {"tau_m": float(stop_only[1]), "fc_over_J": float(stop_only[2])},
        "stop_samples": int(np.sum((mech.w0 + tau * b) * np.exp(-t_fm / tau) - tau * b > 0)),
        "stop_sample_time": float(np.median(np.diff(stop.t))),
        "startup_samples": int(sum(len(r.t) for r in ds.startups)),
        "noise": {k: float(noisy_config.noise[k]) for k in ("current_std", "speed_std", "speed_quantum")},
    }


# -- runs ----------------------------------------------------------------------------------------
def sweep(opts: dict, sc: float, sw: float, extra: list[str]) -> tuple[str, float]:
    rundir = Path(opts["rundir"])
    cmd = [
        sys.executable,
        "-m",
        "benchmark",
        "-m",
        "noise=noisy",
        f"noise.seed=range({int(opts['seeds'])})",
        "optimizer=" + ",".join(opts["optimizers"]),
        "polish=false,true",
        f"budget={int(opts['budget'])}",
        *ml_overrides(sc, sw),
        f"hydra.sweep.dir={rundir}",
        f"hydra.sweep.subdir={SUBDIR}",
        "figures=false",
        *extra,
    ]
    shown = "python " + " ".join(cmd[1:])
    log = rundir / "sweep.json"
    n_runs = 2 * len(opts["optimizers"]) * int(opts["seeds"])
    if opts["reuse"] and len(list(rundir.glob("*/result.json"))) >= n_runs and log.is_file():
        return shown, float(json.loads(log.read_text())["wall_time_s"])
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL)
    if proc.returncode != 0:
        raise SystemExit(f"error: the sweep failed (exit {proc.returncode}): {shown}")
    wall = time.perf_counter() - t0
    log.write_text(json.dumps({"command": shown, "wall_time_s": round(wall, 1)}) + "\n")
    return shown, wall


def collect(rundir: Path, seeds: int) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    for f in sorted(rundir.glob("*/result.json")):
        rec = json.loads(f.read_text())
        run_config = rec.get("config") or {}
        if int(run_config.get("noise", {}).get("seed", -1)) >= seeds:
            continue
        label = rec["optimizer"] + ("+polish" if run_config.get("polish") else "")
        out.setdefault(label, []).append(rec)
    return out


def noise_free_bias(sc: float, sw: float, extra: list[str], rundir: Path) -> dict[str, float]:
    """Relative error of least squares (then polish) on the noise-free record with the same
    ML cost: the bias floor of model discretisation (the plant integrates 4 RK4 steps per
    sample, the identification model 1) and of the optimiser's stop."""
    run_config = compose_run_config(
        [
            "noise=none",
            "optimizer=least_squares",
            "polish=true",
            "budget=20000",
            *ml_overrides(sc, sw),
            *extra,
        ]
    )
    # two levels down, so that collect() (rundir/*/result.json) does not take it for a noisy run
    rec = run(run_config, rundir / "noise_free" / "least_squares_polish").record
    return {k: float(v) for k, v in rec["rel_error"].items()}


# -- table -----------------------------------------------------------------------------------------
def render(info: dict, results: dict[str, list[dict]], bias: dict, command: str, wall: float, seeds: int) -> tuple:
    theta = info["theta"]
    B = info["bounds"]
    lo, hi = (math.sqrt(stats.chi2.ppf(q, seeds) / seeds) for q in (0.025, 0.975))
    sc, sw = info["sc"], info["sw"]
    nz = info["noise"]
    lines = [
        "# Accuracy against the physical limit (Cramer-Rao bound)",
        "",
        f"Command: `python -m benchmark.studies.crb` ({seeds} noise realisations; sweep: `{command}`).",
        "",
        "Data: the `noisy` preset on the paper's motor (synthetic start-up, "
        f"{info['startup_samples']} samples at 12 kHz, and free stop at "
        f"{1e3 * info['stop_sample_time']:g} ms): current noise {nz['current_std']:g} A, speed noise "
        f"{nz['speed_std']:g} rad/s quantised to {nz['speed_quantum']:g} rad/s, so sigma_i = {sc:g} A and "
        f"sigma_w = sqrt(speed_std^2 + q^2/12) = {sw:.4g} rad/s. `noise.seed` = 0..{seeds - 1}; "
        "optimiser seed 0.",
        "",
        f"Estimator: eq. 14 (squared errors) with weights 1/sigma^2 (ka = kb = {1 / sc**2:.6g}, "
        f"kw = {1 / sw**2:.6g}), i.e. -2 log-likelihood of Gaussian white noise up to a constant: "
        "the minimiser is the maximum-likelihood estimate of Rs, Ls, Le, Rr, J given the free-stop "
        "estimates of tau_m and fc/J (two stages, as in the paper: fv = J/tau_m, fc = J fc/J). "
        "Speed quantisation is treated as additional white noise of variance q^2/12.",
        "",
        "Bounds (standard deviations of an unbiased estimator; sensitivities "
        "d(i_alpha, i_beta, speed)/d theta by central differences of `TimeDomainProblem.simulate` "
        "at the truth, step 1e-5 relative; the bounds change by "
        f"{100 * info['fd_step_sensitivity']:.2g} % with step 1e-4):",
        "",
        "- **joint**: all 7 parameters from the start-up and the free stop together (stop information "
        "on tau_m = J/fv and fc/J from its closed-form free motion, start speed as a nuisance parameter);",
        "- **conditional**: the 5 searched parameters with tau_m and fc/J taken as exact (start-up "
        "information only); fv and fc share J's relative bound. This is the bound of the search as "
        "posed; fv and fc also inherit the stop fit's own error, which only the joint bound contains;",
        "- **start-up only**: all 7 from the start-up record alone (what the stop adds).",
        "",
        "| parameter | truth | joint bound | conditional bound | start-up only bound |",
        "|---|---|---|---|---|",
    ]
    for k, n in enumerate(NAMES7):
        lines.append(
            f"| {n} | {theta[k]:.6g} | {_pct(B['joint'][k] / theta[k])} | "
            f"{_pct(B['conditional'][k] / theta[k])} | {_pct(B['startup_only'][k] / theta[k])} |"
        )
    lines += [
        "",
        f"RMS error / bound is consistent with an efficient, unbiased estimator between {lo:.2f} and "
        f"{hi:.2f} (95 % range of sqrt(chi2_{seeds}/{seeds})). The RMS error includes the bias; the mean "
        "error is shown beside it. Noise-free bias: least squares + polish with the same cost on the "
        "noise-free record (model discretisation and optimiser stop).",
        "",
    ]
    data = {
        "seeds": seeds,
        "sigma_current": sc,
        "sigma_speed": sw,
        "truth": dict(zip(NAMES7, theta.tolist(), strict=True)),
        "bounds": {k: dict(zip(NAMES7, (v / theta).tolist(), strict=True)) for k, v in B.items()},
        "noise_free_bias": bias,
        "estimators": {},
    }
    stats_by_label = {}
    for label in sorted(results):
        recs = [r for r in results[label] if r.get("rel_error")]
        if not recs:
            continue
        E = np.array([[float(r["rel_error"][n]) for n in NAMES7] for r in recs])
        rms = np.sqrt(np.mean(E**2, axis=0))
        stats_by_label[label] = {
            "recs": recs,
            "rms": rms,
            "mean": E.mean(axis=0),
            "failed": sum(r["status"] == "failed" for r in results[label]),
            "est": {_noise_seed(r): np.array([r["estimate"][n] for n in NAMES7]) for r in recs},
        }
    ref = "least_squares" if "least_squares" in stats_by_label else next(iter(stats_by_label), None)
    n_res = 3 * info["startup_samples"]
    if ref is not None:
        S = stats_by_label[ref]
        bj_all = B["joint"] / theta
        ratios = S["rms"] / bj_all
        max_bias = max((abs(v) for v in bias.values()), default=math.nan)
        max_mean = float(np.max(np.abs(S["mean"]) / bj_all))
        lines += [
            f"## Result: {ref}, the maximum-likelihood estimate from the crude start",
            "",
            f"RMS error / joint bound is between {ratios.min():.2f} and {ratios.max():.2f} for the 7 "
            f"parameters over {len(S['recs'])} realisations"
            + (
                ": inside the range of an efficient estimator, so the errors are the noise's, not the optimiser's. "
                if lo <= ratios.min() and ratios.max() <= hi
                else f": outside the range {lo:.2f}-{hi:.2f} of an efficient estimator for some parameters. "
            )
            + f"Largest noise-free bias {_pct(max_bias)}; largest mean error {max_mean:.2f} of its joint bound. "
            f"Median cost {np.median([r['cost'] for r in S['recs']]):.6g} for {n_res} residuals: the "
            "weighted residuals have about the variance the noise model assumes (the ML cost at the "
            "optimum is a chi-square with n_residuals - 5 degrees of freedom when the model holds).",
            "",
            "| parameter | RMS error | mean error | noise-free bias | joint bound | RMS / joint | "
            "conditional bound | RMS / conditional |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for k, n in enumerate(NAMES7):
            bj, bc = B["joint"][k] / theta[k], B["conditional"][k] / theta[k]
            lines.append(
                f"| {n} | {_pct(S['rms'][k])} | {_spct(S['mean'][k])} | {_spct(bias.get(n, math.nan))} | "
                f"{_pct(bj)} | {S['rms'][k] / bj:.2f} | {_pct(bc)} | {S['rms'][k] / bc:.2f} |"
            )
        lines += [
            "",
            "fv and fc above their conditional bound (RMS / conditional > 1) is the stop fit's share: the "
            "conditional bound takes tau_m and fc/J as exact; against the joint bound they are in range.",
            "",
            "## Every estimator",
            "",
            f"Largest difference from {ref}'s estimate: over the 7 parameters and the realisations (same "
            "noise seed), relative to the truth.",
            "",
            "| estimator | realisations | failed | median cost | median evaluations | largest difference from "
            f"{ref} | RMS / joint bound (min-max) |",
            "|---|---|---|---|---|---|---|",
        ]
        for label, S2 in stats_by_label.items():
            common = sorted(set(S2["est"]) & set(S["est"]))
            diff = max((np.max(np.abs(S2["est"][k] - S["est"][k]) / theta) for k in common), default=math.nan)
            r2 = S2["rms"] / bj_all
            lines.append(
                f"| {label} | {len(S2['recs'])} | {S2['failed']} | {np.median([r['cost'] for r in S2['recs']]):.6g} | "
                f"{np.median([r['evaluations'] for r in S2['recs']]):.0f} | {_pct(diff)} | "
                f"{r2.min():.2f}-{r2.max():.2f} |"
            )
        lines.append("")
    for label, S2 in stats_by_label.items():
        data["estimators"][label] = {
            n: {
                "rms": S2["rms"][k],
                "mean": S2["mean"][k],
                "ratio_joint": S2["rms"][k] / (B["joint"][k] / theta[k]),
                "ratio_conditional": S2["rms"][k] / (B["conditional"][k] / theta[k]),
            }
            for k, n in enumerate(NAMES7)
        }
    # the stop fit against its own bound
    # every optimiser saw the same realisations, hence the same stop fits: take one label's
    first = results[sorted(results)[0]] if results else []
    mech = [r["problem_info"]["mechanical"] for r in first if (r.get("problem_info") or {}).get("mechanical")]
    if mech:
        tau = np.array([m["tau_m"] for m in mech])
        b = np.array([m["fc_over_J"] for m in mech])
        rt = np.sqrt(np.mean((tau / info["tau"] - 1) ** 2))
        rb = np.sqrt(np.mean((b / info["b"] - 1) ** 2))
        bt, bb = info["stop_bound"]["tau_m"] / info["tau"], info["stop_bound"]["fc_over_J"] / info["b"]
        lines += [
            "## The free-stop fit (first stage)",
            "",
            f"Over the same {len(mech)} realisations ({info['stop_samples']} free-motion samples each), "
            "the case-2 fit (zero-phase filter, then least squares on the closed form) against the bound "
            "of the stop record alone (w0, tau_m, fc/J unknown):",
            "",
            "| quantity | truth | RMS error | mean error | bound | RMS / bound |",
            "|---|---|---|---|---|---|",
            f"| tau_m = J/fv (s) | {info['tau']:.6g} | {_pct(rt)} | "
            f"{_spct(np.mean(tau / info['tau'] - 1))} | {_pct(bt)} | {rt / bt:.2f} |",
            f"| fc/J (rad/s^2) | {info['b']:.6g} | {_pct(rb)} | {_spct(np.mean(b / info['b'] - 1))} | "
            f"{_pct(bb)} | {rb / bb:.2f} |",
            "",
        ]
        data["stop_fit"] = {"tau_m": {"rms": rt, "bound": bt}, "fc_over_J": {"rms": rb, "bound": bb}}
    lines += [f"Wall time of the sweep ({len(results) * seeds} runs, 2 jobs on 2 cores): {wall:.0f} s.", ""]
    return "\n".join(lines), data


def _noise_seed(rec: dict) -> int:
    return int(((rec.get("config") or {}).get("noise") or {}).get("seed", -1))


def _pct(x) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{100 * x:.3g} %"


def _spct(x) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{100 * x:+.3g} %"


def main(argv: list[str]) -> str:
    opts = {
        "seeds": 20,
        "optimizers": ["least_squares", "scipy_de", "cmaes"],
        "budget": 20000,
        "rundir": "outputs/crb",
        "reuse": True,
        "out": "results/crb.md",
    }
    extra = []
    for a in argv:
        key, _, val = a.partition("=")
        if key in opts and val:
            opts[key] = val if key in ("rundir", "out") else yaml.safe_load(val)
        else:
            extra.append(a)
    info = compute_bounds(extra)
    command, wall = sweep(opts, info["sc"], info["sw"], extra)
    results = collect(Path(opts["rundir"]), int(opts["seeds"]))
    bias = noise_free_bias(info["sc"], info["sw"], extra, Path(opts["rundir"]))
    text, data = render(info, results, bias, command, wall, int(opts["seeds"]))
    out = Path(opts["out"])
    write_text_atomic(out, text)
    write_text_atomic(out.with_suffix(".json"), json.dumps(data, indent=1, default=float) + "\n")
    print(text)
    return text


if __name__ == "__main__":
    main(sys.argv[1:])
