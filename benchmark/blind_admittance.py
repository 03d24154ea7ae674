"""``python -m benchmark.blind_admittance``: the slip-sweep diagnosis evaluated blind.

Each data set gets an effect of the sweep catalogue drawn at random (or none), a size drawn
log-uniformly in the effect's realistic range, a randomly varied form of the effect (two cages,
a rectangular deep bar or L&B's quadratic law; saturation exponents and core-loss placement;
slip- or current-driven leakage saturation; ...), a machine whose parameters are spread around
the preset's bare 6-parameter circuit, and noise. The generator writes the data folder; its
``truth.yaml`` is moved to a separate folder before the diagnosis is given the data folder. The
verdicts are compared with the truth afterwards: confusion matrix, correct rate, false-alarm
rate on effect-free sets, median explained share of correct verdicts, with Wilson intervals
(:func:`benchmark.analysis.blind.summarise`, :func:`benchmark.analysis.blind.render`), written to ``out``.
"""

from __future__ import annotations

import sys

import hydra
from omegaconf import OmegaConf, open_dict

from benchmark.analysis import blind
from benchmark.core.cli import run_hydra_main, user_errors

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
        c.effects = list(d["effects"]) or ["none"]
        c.effect_size = dict(d["size"])
        c.effect_form = {k: dict(v) for k, v in d["form"].items()}
        c.data.path = None
    return c


@hydra.main(version_base="1.3", config_path="../conf", config_name="blind_admittance")
@user_errors
def main(cfg) -> None:
    from synthetic.admittance import generate

    blind.run_blind(cfg, "admittance", draw_sets(cfg), set_config, generate,
                    "# Blind evaluation: slip-sweep diagnosis",
                    ("python -m benchmark.blind_admittance " + " ".join(sys.argv[1:])).strip())


if __name__ == "__main__":
    run_hydra_main(main)
