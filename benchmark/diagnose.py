"""``python -m benchmark.diagnose``: where the identified model misses the data, and why.

Thin entry point: composes ``conf/diagnose.yaml``, loads the data set through the problem's
hooks (a data folder, or synthetic data with ``effects=[...]``; the truth is discarded here and
never reaches the diagnosis), and hands it to the problem's ``diagnose`` hook together with the
base identification to use (the configured optimiser, then polish).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import hydra
import numpy as np
from hydra.core.hydra_config import HydraConfig

from benchmark.core.cli import run_hydra_main, user_errors
from benchmark.core.harness import run_diagnosis


@hydra.main(version_base="1.3", config_path="../conf", config_name="diagnose")
@user_errors
def main(cfg) -> None:
    outdir = Path(HydraConfig.get().runtime.output_dir)
    try:
        run_diagnosis(cfg, outdir, progress=lambda name: print(f"  fitting {name}", flush=True))
    except BaseException:
        remove_if_nothing_written(outdir)
        raise
    print((outdir / "diagnosis.md").read_text(encoding="utf-8"))
    print(f"written: {outdir / 'diagnosis.json'}")


def remove_if_nothing_written(outdir: Path) -> None:
    """A diagnosis that failed before writing anything leaves no folder behind: the run folder
    is removed when it holds only Hydra's own files (.hydra/, the log)."""
    if not outdir.is_dir():
        return
    ours = [f for f in outdir.iterdir() if f.name != ".hydra" and f.suffix != ".log"]
    if not ours:
        shutil.rmtree(outdir, ignore_errors=True)


if __name__ == "__main__":
    np.seterr(all="ignore")
    run_hydra_main(main)
