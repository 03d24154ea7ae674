"""``python -m benchmark.blind source=own|plant|motulator n=... seed=...``: the time-domain
diagnosis evaluated blind, one data source at a time.

The sources, draws, loop and scores live in :mod:`benchmark.analysis.blind`; this entry point
composes the config (``conf/blind.yaml``), makes the typed settings once and runs one source.
"""

from __future__ import annotations

import sys

import hydra

from benchmark.analysis.blind import BlindSettings, run_source
from benchmark.core.cli import run_hydra_main, user_errors
from benchmark.core.config_files import CONFIG_DIR

TITLE = ("imbench blind evaluation: draw data sets from one source, move each truth.yaml aside, diagnose\n"
         "the folder and score the verdicts (effect sets named, false alarms, pairs) against the truth.")
USAGE = ("python -m benchmark.blind source=own|plant|motulator n=30 seed=S out=results/blind workdir=outputs/blind",)
FOOTER = ("", "Every key of python -m benchmark.diagnose --help applies too (budget, diagnosis.*, candidates).",
          "Scores: OUT/<source>/confusion.md; docs/diagnosis.md says how they are read.")


@hydra.main(version_base="1.3", config_path=str(CONFIG_DIR), config_name="blind")
@user_errors
def main(cfg) -> None:
    run_source(BlindSettings.from_run(cfg), ("python -m benchmark.blind " + " ".join(sys.argv[1:])).strip())


if __name__ == "__main__":
    run_hydra_main(main, "blind", TITLE, USAGE, FOOTER, sections=())
