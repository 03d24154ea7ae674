"""``python -m benchmark.blind_admittance``: the slip-sweep diagnosis evaluated blind.

Each data set gets an effect of the sweep catalogue drawn at random (or none), a size drawn
log-uniformly in the effect's realistic range, a randomly varied form of the effect (each
effect's own ``random_form``: two cages, a rectangular deep bar or L&B's quadratic law;
saturation exponents and core-loss placement; slip- or current-driven leakage saturation; ...),
a machine whose parameters are spread around the preset's bare 6-parameter circuit, and noise.
The generator writes the data folder; its ``truth.yaml`` is moved to a separate folder before
the diagnosis is given the data folder. The verdicts are compared with the truth afterwards:
confusion matrix, correct rate, false-alarm rate on effect-free sets, median explained share of
correct verdicts, with Wilson intervals (:func:`benchmark.analysis.blind.summarise`,
:func:`benchmark.analysis.blind.render`), written to ``out``.
"""

from __future__ import annotations

import sys

import hydra

from benchmark.analysis import blind
from benchmark.core.cli import run_hydra_main, user_errors
from benchmark.core.config_files import CONFIG_DIR

MOTOR_KEYS = ("R1", "R2", "X", "R0", "X0")


def draw_sets(settings: blind.BlindSettings) -> list[dict]:
    """The n blind draws: effect (or none), size, form, machine spread and noise seed."""
    return blind.draw_sets(settings, problem="admittance", motor_keys=MOTOR_KEYS)


def _scale_machine(par, scale: dict) -> None:
    for k, sc in scale.items():
        for name in ("X1", "X2") if k == "X" else (k,):
            par[name] = float(par[name]) * sc
    par.X2 = float(par.X1)  # the base model's tie holds in the plant


def set_config(settings: blind.BlindSettings, d: dict):
    """The synthetic generator's configuration of one draw (X scales X1 and X2; ``none``: no effect)."""
    return blind.generator_config(settings, d, scale_motor=_scale_machine, no_effect=["none"])


TITLE = ("imbench blind evaluation of the slip-sweep diagnosis: sweeps with a drawn effect (or none), their\n"
         "truth kept apart, each diagnosed from its data folder alone, the verdicts scored.")
USAGE = ("python -m benchmark.blind_admittance n=60 seed=2024 out=results/blind_admittance",)


@hydra.main(version_base="1.3", config_path=str(CONFIG_DIR), config_name="blind_admittance")
@user_errors
def main(cfg) -> None:
    from synthetic.admittance import generate

    settings = blind.BlindSettings.from_run(cfg)
    blind.run_blind(settings, draw_sets(settings), set_config, generate, "# Blind evaluation: slip-sweep diagnosis",
                    ("python -m benchmark.blind_admittance " + " ".join(sys.argv[1:])).strip())


if __name__ == "__main__":
    run_hydra_main(main, "blind_admittance", TITLE, USAGE, sections=())
