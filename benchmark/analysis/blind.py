"""``python -m benchmark.analysis.blind``: the diagnosis evaluated blind.

Each data set gets an effect drawn at random (or none), a size drawn log-uniformly in the
effect's realistic range, a randomly varied form of the effect (so that the diagnosis is not
tuned to one plant formula), a motor whose parameters are spread around the preset, and
noise. The data folder holds only ``meta.yaml`` and the records; the truth goes to a separate
folder that the diagnosis is never given. The verdicts are then compared with the truth:
confusion matrix, correct rate, false-alarm rate on effect-free sets, and the held-out gap
shrinkage of correct verdicts, written to ``out``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from omegaconf import OmegaConf, open_dict

from benchmark.core.effects import load_effects
from benchmark.core.io import write_table_atomic, write_text_atomic, write_yaml_atomic

FORM_CHOICES = {
    "double_cage": lambda rng: {"ladder": bool(rng.integers(2)), "tau2": float(rng.uniform(0.002, 0.008))},
    "main_saturation": lambda rng: {"exponent": float(rng.choice([2.0, 4.0, 6.0]))},
    "leakage_saturation": lambda rng: {"exponent": float(rng.choice([1.5, 2.0, 3.0]))},
    "inverter_drop": lambda rng: {"smooth": float(rng.choice([0.0, 0.02, 0.05]))},
}


MOTOR_KEYS = ("Rs", "Ls", "Le", "Rr", "J", "fv")


def draw_sets(cfg, problem: str = "timedomain", motor_keys=MOTOR_KEYS, form_choices=None) -> list[dict]:
    """The n blind draws: effect (or none), size, form, motor spread and noise seed.

    Each set has its own random stream (spawned from ``cfg.seed``), so a set's draw does not
    depend on how many sets come before it."""
    form_choices = FORM_CHOICES if form_choices is None else form_choices
    effects = load_effects(problem)
    names = sorted(effects)
    outcomes = names + ["none"]
    weights = np.array([1.0] * len(names) + [float(cfg.none_weight)])
    seeds = np.random.SeedSequence(int(cfg.seed)).spawn(int(cfg.n))
    draws = []
    for i, ss in enumerate(seeds):
        rng = np.random.default_rng(ss)
        effect = str(rng.choice(outcomes, p=weights / weights.sum()))
        d = {"index": i, "effect": effect, "noise_seed": int(rng.integers(2**31 - 1))}
        spread = float(cfg.vary_motor)
        d["motor_scale"] = {k: float(np.exp(rng.uniform(-spread, spread))) for k in motor_keys}
        if effect != "none":
            lo, hi = effects[effect].realistic
            d["size"] = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
            d["form"] = form_choices[effect](rng) if (cfg.vary_form and effect in form_choices) else {}
        draws.append(d)
    return draws


def set_config(cfg, d: dict):
    """The synthetic configuration of one draw (a copy of cfg)."""
    c = OmegaConf.create(OmegaConf.to_container(cfg, resolve=True))
    with open_dict(c):
        for k, s in d["motor_scale"].items():
            c.motor.parameters[k] = float(c.motor.parameters[k]) * s
        c.noise.seed = d["noise_seed"]
        c.effects = [] if d["effect"] == "none" else [d["effect"]]
        c.effect_size = {} if d["effect"] == "none" else {d["effect"]: d["size"]}
        c.effect_form = {} if d["effect"] == "none" else {d["effect"]: d.get("form", {})}
        c.data.path = None
    return c


def summarise(rows: list[dict], labels: list[str]) -> dict:
    idx = {k: i for i, k in enumerate(labels)}
    cm = np.zeros((len(labels), len(labels)), dtype=int)
    for r in rows:
        cm[idx[r["truth"]], idx[r["verdict"]]] += 1
    correct = sum(r["truth"] == r["verdict"] for r in rows)
    none_rows = [r for r in rows if r["truth"] == "none"]
    false_alarms = sum(r["verdict"] != "none" for r in none_rows)
    shrink = [1.0 - r["gap_after"] / r["gap_before"] for r in rows
              if r["truth"] == r["verdict"] and r["truth"] != "none" and r["gap_before"] > 0]
    # the noise floor of the held-out RMS: what effect-free sets leave (the estimated noise
    # levels are only good to ~10 %, so it is not exactly 1)
    floor = float(np.median([r["gap_after"] for r in none_rows])) if none_rows else 1.0
    removed = [(r["gap_before"] ** 2 - r["gap_after"] ** 2) / (r["gap_before"] ** 2 - floor**2) for r in rows
               if r["truth"] == r["verdict"] and r["truth"] != "none" and r["gap_before"] > floor]
    return {
        "n": len(rows),
        "correct": int(correct),
        "correct_rate": correct / len(rows) if rows else math.nan,
        "effect_free_sets": len(none_rows),
        "false_alarms": int(false_alarms),
        "false_alarm_rate": false_alarms / len(none_rows) if none_rows else math.nan,
        "median_heldout_gap_shrinkage_correct": float(np.median(shrink)) if shrink else math.nan,
        "heldout_noise_floor": floor,
        "median_excess_misfit_removed_correct": float(np.median(removed)) if removed else math.nan,
        "labels": labels,
        "confusion": cm.tolist(),
    }


def render(summary: dict, rows: list[dict], cmd: str) -> str:
    labels = summary["labels"]
    cm = np.array(summary["confusion"])
    lines = ["# Blind evaluation of the sim-to-real diagnosis", "", f"Command: `{cmd}`", "",
             f"{summary['n']} data sets; **{summary['correct']} correct verdicts "
             f"({100 * summary['correct_rate']:.0f} %)**; false alarms on effect-free sets: "
             f"{summary['false_alarms']} of {summary['effect_free_sets']} "
             f"({100 * summary['false_alarm_rate']:.0f} %); median held-out gap shrinkage "
             f"(1 - RMS after / RMS before, over noise) for correct verdicts: "
             f"{100 * summary['median_heldout_gap_shrinkage_correct']:.0f} %; the held-out RMS over noise falls to "
             f"the effect-free sets' floor ({summary['heldout_noise_floor']:.3f}): median share of the excess "
             f"held-out misfit (chi^2 above that floor) removed "
             f"{100 * summary['median_excess_misfit_removed_correct']:.0f} %.",
             "",
             "Rows: the effect injected; columns: the verdict.", "",
             "| truth \\ verdict | " + " | ".join(labels) + " |", "|---|" + "---|" * len(labels)]
    for i, lab in enumerate(labels):
        lines.append(f"| {lab} | " + " | ".join(str(v) if v else "." for v in cm[i]) + " |")
    lines += ["", "| set | truth | size | form | verdict | held-out gap before | after |",
              "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['index']} | {r['truth']} | {r.get('size', '')} | {r.get('form', '')} | {r['verdict']} "
                     f"| {r['gap_before']:.3f} | {r['gap_after']:.3f} |")
    return "\n".join(lines) + "\n"


def run_blind(cfg, problem: str, draws: list[dict], set_config, generate, title: str, command: str) -> dict:
    """Make, hide the truth of, and diagnose every drawn set; write the confusion matrix and
    statistics to ``cfg.out``. Shared by the time-domain and slip-sweep evaluations."""
    from benchmark.core.harness import run_diagnosis

    work = Path(cfg.workdir)
    out = Path(cfg.out)
    rows = []
    for d in draws:
        sc = set_config(cfg, d)
        folder = work / "sets" / f"set_{d['index']:03d}"
        generate(sc, folder)
        # the truth leaves the data folder before the diagnosis sees it
        (work / "truth").mkdir(parents=True, exist_ok=True)
        (folder / "truth.yaml").replace(work / "truth" / f"set_{d['index']:03d}.yaml")
        with open_dict(sc):
            sc.data.path = str(folder)
            sc.effects, sc.effect_size, sc.effect_form = [], {}, {}
            sc.figures = False
        doc = run_diagnosis(sc, work / "diagnoses" / f"set_{d['index']:03d}")
        row = {"index": d["index"], "truth": d["effect"], "verdict": doc["verdict"],
               "gap_before": doc["gap_before"]["heldout_rms_over_noise"],
               "gap_after": doc["gap_after"]["heldout_rms_over_noise"],
               "ranking": [{k: r[k] for k in ("effect", "heldout_reduction", "criterion")} for r in doc["ranking"][:3]]}
        if "size" in d:
            row["size"] = round(d["size"], 4)
            row["form"] = d.get("form", {})
        rows.append(row)
        print(f"set {d['index']:3d}: truth {d['effect']:<20} verdict {doc['verdict']:<20} "
              f"gap {row['gap_before']:.2f} -> {row['gap_after']:.2f}", flush=True)
    labels = sorted(load_effects(problem)) + ["none"]
    summary = summarise(rows, labels)
    out.mkdir(parents=True, exist_ok=True)
    text = render(summary, [{k: v for k, v in r.items() if k != "ranking"} for r in rows], command)
    text = text.replace("# Blind evaluation of the sim-to-real diagnosis", title)
    write_text_atomic(out / "confusion.md", text)
    write_text_atomic(out / "blind.json", json.dumps({"summary": summary, "sets": rows}, indent=1) + "\n")
    write_table_atomic(out / "confusion.csv", {"truth": np.array(labels, dtype=object),
                                               **{v: np.array(summary["confusion"])[:, j]
                                                  for j, v in enumerate(labels)}})
    write_yaml_atomic(out / "config.yaml", OmegaConf.to_container(cfg, resolve=True))
    print(text)
    return summary
