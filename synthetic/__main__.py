"""``python -m synthetic``: write a synthetic data set (the README's Data sets) and its truth.yaml.

Examples::

    python -m synthetic out=data/paper                # the paper's noise-free start-up/stop
    python -m synthetic noise=noisy out=data/noisy
    python -m synthetic problem=admittance out=data/sweep
"""

from __future__ import annotations

from pathlib import Path

import hydra
from hydra.utils import instantiate

from benchmark.core.cli import user_errors


@hydra.main(version_base="1.3", config_path="../conf", config_name="synthetic")
@user_errors
def main(cfg) -> None:
    folder = instantiate(cfg.problem.generator)(cfg, Path(cfg.out))
    print(f"wrote {folder}")


if __name__ == "__main__":
    main()
