"""``python -m synthetic``: write a synthetic data set (docs/data_format.md) and its truth.yaml.

Examples::

    python -m synthetic out=data/paper                # the paper's noise-free start-up/stop
    python -m synthetic noise=noisy out=data/noisy
    python -m synthetic problem=admittance out=data/sweep
"""

from __future__ import annotations

from pathlib import Path

import hydra
from hydra.utils import instantiate

from benchmark.core.cli import run_hydra_main, user_errors
from benchmark.core.config_files import CONFIG_DIR

TITLE = ("imbench synthetic data: write a data set (meta.yaml, CSV tables, truth.yaml) from a motor preset,\n"
         "with noise and unmodelled effects injected; the format is docs/data_format.md.")
USAGE = ("python -m synthetic out=data/paper                      the paper's noise-free start-up and free stop",
         "python -m synthetic noise=noisy 'effects=[double_cage]' out=data/dc",
         "python -m synthetic problem=admittance out=data/sweep   a slip sweep (Lindsay and Barton)")
FOOTER = ("", "The independent plant (no code shared with benchmark/): python -m synthetic.independent --help.",)


@hydra.main(version_base="1.3", config_path=str(CONFIG_DIR), config_name="synthetic")
@user_errors
def main(cfg) -> None:
    folder = instantiate(cfg.problem.generator)(cfg, Path(cfg.out))
    print(f"wrote {folder}")


if __name__ == "__main__":
    run_hydra_main(main, "synthetic", TITLE, USAGE, FOOTER, sections=())
