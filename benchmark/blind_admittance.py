"""``python -m benchmark.blind_admittance``: the slip-sweep diagnosis evaluated blind.

Each data set gets an effect of the sweep catalogue drawn at random (or none), a size drawn
log-uniformly in the effect's realistic range, a randomly varied form of the effect (two cages,
a rectangular deep bar or L&B's quadratic law; saturation exponents and core-loss placement;
slip- or current-driven leakage saturation; ...), a machine whose parameters are spread around
the preset's bare 6-parameter circuit, and noise. The generator writes the data folder; its
``truth.yaml`` is moved to a separate folder before the diagnosis is given the data folder. The
verdicts are compared with the truth afterwards: confusion matrix, correct rate, false-alarm
rate on effect-free sets, median held-out gap shrinkage of correct verdicts
(:func:`benchmark.blind.summarise`, :func:`benchmark.blind.render`), written to ``out``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import hydra
import numpy as np
from omegaconf import OmegaConf, open_dict

from benchmark import blind
from benchmark.blind import render, summarise
from benchmark.cli import run_hydra_main, user_errors
from benchmark.data.tables import write_table_atomic, write_text_atomic, write_yaml_atomic
from benchmark.effects import load_effects

FORM_CHOICES = {
    "double_cage": lambda rng: [
        {"kind": "double_cage", "corner": float(rng.uniform(0.15, 0.5))},
        {"kind": "deep_bar", "bar_share": float(rng.uniform(0.6, 0.95))},
        {"kind": "quadratic"},
    ][int(rng.integers(3))],
    "main_saturation": lambda rng: {
        "exponent": float(rng.choice([1.0, 2.0, 4.0, 6.0])),
        "loss": str(rng.choice(["series", "parallel"])),
    },
    "iron_loss": lambda rng: {"kind": str(rng.choice(["power", "two_term"]))},
    "temperature_drift": lambda rng: {"cooling": bool(rng.integers(2))},
    "leakage_saturation": lambda rng: {
        "kind": str(rng.choice(["slip", "current"])),
        "exponent": float(rng.choice([1.5, 2.0, 3.0])),
    },
    "leakage_core_loss": lambda rng: {
        "r1_ratio": float(rng.uniform(0.0, 0.5)),
        "smooth": float(rng.choice([0.0, 0.02, 0.05])),
    },
}
MOTOR_KEYS = ("R1", "R2", "X", "R0", "X0")


def draw_sets(cfg) -> list[dict]:
    """The n blind draws: effect (or none), size, form, machine spread and noise seed."""
    return blind.draw_sets(cfg, problem="admittance", motor_keys=MOTOR_KEYS, form_choices=FORM_CHOICES)


def set_config(cfg, d: dict):
    """The synthetic configuration of one draw (a copy of cfg)."""
    c = OmegaConf.create(OmegaConf.to_container(cfg, resolve=True))
    with open_dict(c):
        par = c.motor.parameters
        for k, sc in d["motor_scale"].items():
            for name in ("X1", "X2") if k == "X" else (k,):
                par[name] = float(par[name]) * sc
        par.X2 = float(par.X1)  # the base model's tie holds in the plant
        c.noise.seed = d["noise_seed"]
        c.effects = ["none"] if d["effect"] == "none" else [d["effect"]]
        c.effect_size = {} if d["effect"] == "none" else {d["effect"]: d["size"]}
        c.effect_form = {} if d["effect"] == "none" else {d["effect"]: d.get("form", {})}
        c.data.path = None
    return c


@hydra.main(version_base="1.3", config_path="../conf", config_name="blind_admittance")
@user_errors
def main(cfg) -> None:
    from benchmark.diagnose import run_diagnosis
    from synthetic.admittance import generate

    work = Path(cfg.workdir)
    out = Path(cfg.out)
    rows = []
    for d in draw_sets(cfg):
        sc = set_config(cfg, d)
        folder = work / "sets" / f"set_{d['index']:03d}"
        generate(sc, folder)
        # the truth leaves the data folder before the diagnosis sees it
        (work / "truth").mkdir(parents=True, exist_ok=True)
        (folder / "truth.yaml").replace(work / "truth" / f"set_{d['index']:03d}.yaml")
        with open_dict(sc):
            sc.data.path = str(folder)
            sc.effects, sc.effect_size, sc.effect_form = [], {}, {}
        doc = run_diagnosis(sc, work / "diagnoses" / f"set_{d['index']:03d}")
        row = {
            "index": d["index"],
            "truth": d["effect"],
            "verdict": doc["verdict"],
            "gap_before": doc["gap_before"]["heldout_rms_over_noise"],
            "gap_after": doc["gap_after"]["heldout_rms_over_noise"],
            "ranking": [{k: r[k] for k in ("effect", "heldout_reduction", "criterion")} for r in doc["ranking"][:3]],
        }
        if "size" in d:
            row["size"] = round(d["size"], 4)
            row["form"] = d.get("form", {})
        rows.append(row)
        print(
            f"set {d['index']:3d}: truth {d['effect']:<20} verdict {doc['verdict']:<20} "
            f"gap {row['gap_before']:.2f} -> {row['gap_after']:.2f}",
            flush=True,
        )
    labels = sorted(load_effects("admittance")) + ["none"]
    summary = summarise(rows, labels)
    cmd = ("python -m benchmark.blind_admittance " + " ".join(sys.argv[1:])).strip()
    out.mkdir(parents=True, exist_ok=True)
    text = render(summary, [{k: v for k, v in r.items() if k != "ranking"} for r in rows], cmd)
    text = text.replace("# Blind evaluation of the sim-to-real diagnosis", "# Blind evaluation: slip-sweep diagnosis")
    write_text_atomic(out / "confusion.md", text)
    write_text_atomic(out / "blind.json", json.dumps({"summary": summary, "sets": rows}, indent=1) + "\n")
    write_table_atomic(
        out / "confusion.csv",
        {
            "truth": np.array(labels, dtype=object),
            **{v: np.array(summary["confusion"])[:, j] for j, v in enumerate(labels)},
        },
    )
    write_yaml_atomic(out / "config.yaml", OmegaConf.to_container(cfg, resolve=True))
    print(text)


if __name__ == "__main__":
    run_hydra_main(main)
