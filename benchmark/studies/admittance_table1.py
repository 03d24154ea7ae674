"""Lindsay and Barton's Table I on synthetic data: mean admittance error and parameter errors after
5 conjugate-gradient searches, initial models A and E, 6- vs 8-parameter model, over noise seeds.

Command (writes ``results/admittance_table1.md``; about a minute on 2 cores)::

    python -m benchmark.studies.admittance_table1

(options: ``--seeds 20 --workers 2 --out results/admittance_table1.md``).

Each run is what ``python -m benchmark problem=admittance optimizer=lindsay_barton noise=noisy
noise.seed=K problem.model=M optimizer.plugin.initial_model=I`` does: the composed Hydra config, the
problem's ``setup_problem``, the plugin instantiated from ``conf/optimizer/lindsay_barton.yaml`` and
run through the counting :class:`benchmark.core.problem.BudgetedProblem` with the YAML's default budget.
The data: model F of the paper as truth, its test (43 readings, -1800..+2400 rpm, 30.2 V), noise
0.3 % of full scale on G and B, the windings warming about 5 C during the sweep, temperature
compensation on. Beside each run, the minimum of the same cost found by SciPy least squares from the
truth shows how far 5 searches are from the attainable minimum.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from scipy.optimize import least_squares

from benchmark.core.budget import BudgetedProblem, run_plugin
from benchmark.core.config_files import CONFIG_DIR
from benchmark.core.harness import build_problem
from benchmark.problems.admittance.circuit import input_admittance

CONF = str(CONFIG_DIR)
ORDER8 = ("R1_total", "R2", "R2sigma", "R0", "X1", "X2", "X3", "X0")  # the paper's Table II order
ORDER6 = ("R1_total", "R2", "R0", "X1", "X2", "X0")
LABEL = {"R1_total": "R1+R1sigma"}

# Lindsay and Barton (1972), Table I (mean error %, initial and after 5 searches) and Table II
# (parameters after 5 searches, ohm); the 6-parameter model has no row E in their tables.
PAPER_TABLE1 = {
    (8, "A"): (12.75, 1.28),
    (8, "E"): (3.88, 1.06),
    (6, "A"): (13.12, 1.88),
    (6, "E"): (None, None),
}
PAPER_TABLE2 = {
    (8, "A"): dict(zip(ORDER8, (0.2015, 0.2956, 0.0599, 1.051, 0.5527, 0.6055, 0.0396, 16.11), strict=True)),
    (8, "E"): dict(zip(ORDER8, (0.1907, 0.3001, 0.0449, 1.059, 0.5562, 0.5558, 0.0078, 16.10), strict=True)),
    (6, "A"): dict(zip(ORDER6, (0.2004, 0.3274, 1.051, 0.5362, 0.5353, 16.11), strict=True)),
}
VARIANTS = [
    (8, "A", False),
    (8, "E", False),
    (6, "A", False),
    (6, "E", False),
    (8, "E", True),
    (6, "E", True),
]


def compose_run_config(model: int, initial: str, tie: bool, seed: int):
    overrides = [
        "problem=admittance",
        "optimizer=lindsay_barton",
        "noise=noisy",
        f"noise.seed={seed}",
        f"seed={seed}",
        f"problem.model={model}",
        f"problem.tie_x1_x2={str(tie).lower()}",
        f"optimizer.plugin.initial_model={initial}",
        "optimizer.plugin.searches=5",
    ]
    with initialize_config_dir(config_dir=CONF, version_base="1.3"):
        return compose("config", overrides=overrides)


def true_curve_error(problem, x) -> float:
    """RMS distance (% of full scale, G and B) between the fitted and the true circuit's admittance
    at the readings' slips, both at the reference temperature."""
    t = problem.truth
    est = problem.estimate(x)
    s = problem.data.slip

    def y(p):
        return input_admittance(
            s,
            p["R1_total"],
            p["X1"],
            p["R2"],
            p["X2"],
            p["R0"],
            p["X0"],
            p.get("R2sigma", 0.0),
            p.get("X3", 0.0),
        )

    truth_doc = problem.truth_document["parameters"]
    full = {k: float(v) for k, v in truth_doc.items()} | {"R1_total": t["R1_total"]}
    d = (y(est) - y(full)) / problem.full_scale_admittance
    return float(100 * np.sqrt(np.mean(np.concatenate([d.real, d.imag]) ** 2)))


def least_squares_minimum(problem, x0) -> np.ndarray:
    lo, hi = problem.lower, problem.upper
    sol = least_squares(
        lambda u: problem.residuals(lo + u * (hi - lo)),
        np.clip((x0 - lo) / (hi - lo), 0, 1),
        bounds=(0, 1),
        xtol=1e-14,
        ftol=1e-14,
        gtol=1e-14,
        x_scale="jac",
    )
    return lo + sol.x * (hi - lo)


def one_run(task):
    model, initial, tie, seed = task
    run_config = compose_run_config(model, initial, tie, seed)
    problem = build_problem(run_config)
    x0 = problem.initial_guess(initial)
    bp = BudgetedProblem(problem, int(run_config.optimizer.default_budget))
    res = run_plugin(instantiate(run_config.optimizer.plugin), bp, seed=seed, name=str(run_config.optimizer.name))
    x_true = np.array([problem.truth[n] for n in problem.parameter_names])
    x_ls = least_squares_minimum(problem, x_true)
    est = problem.estimate(res.x)
    truth_full = {k: float(v) for k, v in problem.truth_document["parameters"].items()}
    truth_full["R1_total"] = truth_full["R1"] + truth_full["R1sigma"]
    return {
        "model": model,
        "initial": initial,
        "tie": tie,
        "seed": seed,
        "initial_error": problem.rms_error_percent(x0),
        "final_error": problem.rms_error_percent(res.x),
        "ls_error": problem.rms_error_percent(x_ls),
        "true_curve_error": true_curve_error(problem, res.x),
        "nfev": res.nfev,
        "nit": res.nit,
        "status": res.status.value,
        "estimate": est,
        "estimate_ls": problem.estimate(x_ls),
        "truth": truth_full,
        "mapping": getattr(problem, "last_mapping", None) if initial == "E" else None,
    }


def ms(values, fmt="{:.2f}") -> str:
    v = np.asarray(values, float)
    return f"{fmt.format(v.mean())} ± {fmt.format(v.std(ddof=1) if len(v) > 1 else 0.0)}"


def table_row(label: str, cells) -> str:
    """One Markdown table row: the label, then the cells."""
    return f"| {label} | " + " | ".join(cells) + " |"


def render(rows, seeds: int, wall: float, command: str) -> str:
    def groups():
        """(model, initial, tie, the rows of that variant) of every variant with rows."""
        for model, initial, tie in VARIANTS:
            g = [r for r in rows if (r["model"], r["initial"], r["tie"]) == (model, initial, tie)]
            if g:
                yield model, initial, tie, g

    out = [
        "# Lindsay-Barton Table I on synthetic data (admittance problem)",
        "",
        f"Regenerate: `{command}` ({seeds} noise seeds, {wall:.0f} s wall time on this machine).",
        "",
        "Data: the paper's 8-parameter model F as truth (R1 = 0.2045, R1sigma = 0.0061, X1 = 0.5580, "
        "R2 = 0.2941, R2sigma = 0.0340, X2 = 0.5579, X3 = 0.0093, R0 = 1.0592, X0 = 16.0998 ohm at 60 Hz, "
        "50 C), the paper's test (43 readings every 100 rpm from -1800 to +2400 rpm, 30.2 V per phase, "
        "4 poles, 60 Hz), white noise of 0.3 % of the 1 S full scale on G and B (`noise=noisy`), the "
        "windings "
        "warming about 5 C during the sweep (thermal model), temperature compensation from the DC stator "
        "resistance before/after (default `problem.temperature_compensation: auto`). Optimiser: "
        "`optimizer=lindsay_barton` with 5 searches (one search = n_var CG iterations), budget 5000 "
        "evaluations; each noise seed is one data set.",
        "",
        "Mean error = 100 * sqrt(S^2), S^2 the mean square misfit of G and B as a fraction of full scale "
        "(the paper's error function). The paper's figures are for its measured data (model error plus "
        "its instrument noise), ours for 0.3 % noise with no model error in the 8-parameter rows; compare "
        "the pattern, not the digits.",
        "",
        "## Table I: mean error (% of full scale), mean ± standard deviation over seeds",
        "",
        "| model | initial model | initial error | after 5 searches | least-squares minimum "
        "| fitted vs true curve "
        "| evaluations | L&B initial | L&B after 5 searches |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for model, initial, tie, g in groups():
        pi, pf = PAPER_TABLE1.get((model, initial), (None, None)) if not tie else (None, None)
        name = f"{model}-parameter" + (", X1 = X2 tied" if tie else "")
        out.append(
            f"| {name} | {initial} | {ms([r['initial_error'] for r in g])} "
            f"| {ms([r['final_error'] for r in g])} "
            f"| {ms([r['ls_error'] for r in g])} | {ms([r['true_curve_error'] for r in g], '{:.3f}')} "
            f"| {ms([r['nfev'] for r in g], '{:.0f}')} | {pi if pi is not None else '-'} "
            f"| {pf if pf is not None else '-'} |"
        )
    out += [
        "",
        '"least-squares minimum": the same cost minimised to convergence (SciPy least squares from the '
        'truth); "fitted vs true curve": RMS distance between the fitted and the true admittance at the '
        "readings (both at 50 C), which noise alone would put near 0.3 % * sqrt(n_var/n) = 0.09 % (8 "
        "parameters) for an unbiased fit.",
        "",
        "## Table II: parameters after 5 searches (ohm), mean ± standard deviation over seeds, and signed "
        "error of the mean",
        "",
        "The least-squares rows are the minimum of the same cost on the same data: their spread is what the "
        "data determine (identifiability at this noise); the difference between them and the rows above is "
        "what 5 searches leave undone.",
        "",
    ]
    for model, initial, tie, g in groups():
        order = ORDER8 if model == 8 else ORDER6
        name = f"{model}-parameter, initial model {initial}" + (", X1 = X2 tied" if tie else "")
        truth = g[0]["truth"]
        paper = PAPER_TABLE2.get((model, initial)) if not tie else None
        out += [
            f"### {name}",
            "",
            "| | " + " | ".join(LABEL.get(n, n) for n in order) + " |",
            "|---|" + "---|" * len(order),
        ]
        vals = {n: np.array([r["estimate"][n] for r in g]) for n in order}
        ls = {n: np.array([r["estimate_ls"][n] for r in g]) for n in order}
        out += [
            table_row("truth (model F)", (f"{truth[n]:.4f}" for n in order)),
            table_row("estimate", (f"{vals[n].mean():.4f} ± {vals[n].std(ddof=1):.4f}" for n in order)),
            table_row("error of the mean", (f"{100 * (vals[n].mean() / truth[n] - 1):+.1f} %" for n in order)),
            table_row("spread (sd/truth)", (f"{100 * vals[n].std(ddof=1) / truth[n]:.1f} %" for n in order)),
            table_row("least-squares minimum", (f"{ls[n].mean():.4f} ± {ls[n].std(ddof=1):.4f}" for n in order)),
            table_row("its error of the mean, spread",
                      (f"{100 * (ls[n].mean() / truth[n] - 1):+.1f} %, {100 * ls[n].std(ddof=1) / truth[n]:.1f} %"
                       for n in order)),
        ]
        if paper is not None:
            out.append(table_row("L&B Table II", (f"{paper[n]:.4f}" for n in order)))
        r1s = np.array([r["estimate"].get("R1sigma", np.nan) for r in g])
        out += [
            "",
            f"R1sigma = R1_total - R1 (R1 from the DC resistance): {r1s.mean():.4f} ± {r1s.std(ddof=1):.4f} "
            f"ohm (truth {truth['R1sigma'] if model == 8 else 0.0:.4f}).",
            "",
        ]
        maps = [r["mapping"] for r in g if r["mapping"]]
        if maps and not tie:
            free = sum(m == "free" for m in maps)
            out += [
                f"Model E mapping: X1, X2 free in {free} of {len(maps)} seeds, tied (X1 = X2) in the rest "
                "(the free mapping fell outside the bounds).",
                "",
            ]
    out += [
        "## What the data determine (identifiability, honestly)",
        "",
        "* **R1 vs R1sigma**: one frequency and temperature show only their sum. The DC stator resistance "
        "gives R1, so R1sigma = R1_total - R1 carries the full error of R1_total: with R1sigma 3 % of "
        "R1_total, a 1 % error in R1_total is a 35 % error in R1sigma.",
        "* **X1 vs X2 (free split)**: separated only through the small R0 and the sign change of R2sigma at "
        "s = 0. At 0.3 % noise their spread over seeds is tens of per cent (8-parameter) while their sum is "
        "within a fraction of a per cent; a start with X1 = X2 (model A, or E's tied mapping) mostly stays "
        "near X1 = X2 after 5 searches, consistent with the paper's Table II, where X1 and X2 stay close "
        "except in its model A. The tied "
        "rows (`problem.tie_x1_x2=true`) remove this direction.",
        "* **R0**: weakly determined at 30.2 V (the magnetising branch carries little loss current): its "
        "spread is about 25 % at the least-squares minimum and larger after 5 searches, which barely move "
        "it from the start. R2sigma and X3, the second-order terms, spread by 10-20 %.",
        "* **Model E's cost**: its regression (and, for 8 parameters, the outer search over two warp "
        "ratios) runs on the data outside the evaluation budget, as a data reduction step like the "
        "paper's; the evaluations column counts only the cost evaluations of the searches.",
        "* **6-parameter model on 8-parameter data**: the missing R2sigma*sign(s) and X3 are absorbed by "
        "R1_total (about +10 %) and R0, and the misfit cannot fall below about 0.45 % of full scale; "
        "with X1, X2 free the split runs to a bound. The paper's 6-parameter error after 5 searches "
        "(1.26-1.88 %, 0.59 % for D) also sat well above its 8-parameter errors.",
        "",
    ]
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="results/admittance_table1.md")
    args = ap.parse_args(argv)
    tasks = [(m, i, t, s) for m, i, t in VARIANTS for s in range(args.seeds)]
    t0 = time.perf_counter()
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:
            rows = list(pool.map(one_run, tasks, chunksize=4))
    else:
        rows = [one_run(t) for t in tasks]
    wall = time.perf_counter() - t0
    command = "python -m benchmark.studies.admittance_table1" + (
        f" --seeds {args.seeds}" if args.seeds != 20 else ""
    )
    text = render(rows, args.seeds, wall, command)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text, encoding="utf-8")
    print(text)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
