"""``python -m benchmark.diagnose``: where the identified model misses the data, and why.

Thin entry point over :func:`benchmark.api.diagnose`'s path: composes ``conf/diagnose.yaml``,
loads the data set through the problem's hooks (a data folder, or synthetic data with
``effects=[...]``; the truth is discarded here and never reaches the diagnosis), and hands it to
the problem's ``diagnose`` hook together with the base identification to use (the configured
optimiser, then polish).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import hydra
import numpy as np
from hydra.core.hydra_config import HydraConfig

from benchmark.api import diagnosis_of
from benchmark.core.cli import run_hydra_main, user_errors
from benchmark.core.config_files import CONFIG_DIR

TITLE = ("imbench diagnosis: where the identified model misses the data, which unmodelled effects\n"
         "(conf/effect/: double_cage, main_saturation, load_torque, ...) explain the gap, how much of it,\n"
         "and what stays unexplained. It never reads truth.yaml.")
USAGE = ("python -m benchmark.diagnose data.path=DIR                      a data folder (measured or foreign)",
         "python -m benchmark.diagnose 'effects=[double_cage]' noise=noisy  a synthetic plant with an effect",
         "python -m benchmark.diagnose data.path=DIR 'candidates=[double_cage,load_torque]'  fewer candidates")
FOOTER = ("", "Writes diagnosis.json, diagnosis.md and figures into the run folder (hydra.run.dir=...).",
          "How it decides: docs/diagnosis.md.")


@hydra.main(version_base="1.3", config_path=str(CONFIG_DIR), config_name="diagnose")
@user_errors
def main(cfg) -> None:
    outdir = Path(HydraConfig.get().runtime.output_dir)
    try:
        result = diagnosis_of(cfg, outdir, progress=lambda name: print(f"  fitting {name}", flush=True))
    except BaseException:
        remove_if_nothing_written(outdir)
        raise
    print(result)
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
    run_hydra_main(main, "diagnose", TITLE, USAGE, FOOTER)
