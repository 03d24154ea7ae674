"""``python -m benchmark.blind``: the time-domain diagnosis evaluated blind.

The draws, the loop and the summary live in :mod:`benchmark.analysis.blind`; this entry point
composes the config (``conf/blind.yaml``) and hands over the time-domain data generator.
"""

from __future__ import annotations

import sys

import hydra

from benchmark.analysis.blind import draw_sets, run_blind, set_config
from benchmark.core.cli import run_hydra_main, user_errors


@hydra.main(version_base="1.3", config_path="../conf", config_name="blind")
@user_errors
def main(cfg) -> None:
    from synthetic.timedomain import generate

    run_blind(cfg, "timedomain", draw_sets(cfg), set_config, generate,
              "# Blind evaluation of the sim-to-real diagnosis",
              ("python -m benchmark.blind " + " ".join(sys.argv[1:])).strip())


if __name__ == "__main__":
    run_hydra_main(main)
