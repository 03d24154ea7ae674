"""Shared fixtures: the paper's motor and its synthetic records (computed once per session)."""

from __future__ import annotations

import os
from pathlib import Path

import numba
import pytest
from hydra import compose, initialize_config_dir
from hypothesis import settings

from benchmark.problems.timedomain.motor import InductionMotor
from benchmark.problems.timedomain.protocol import StartupStopTest, run_startup_stop

# Property tests draw their examples from a fixed seed: CI is reproducible, and a failure found
# by a longer local session (HYPOTHESIS_PROFILE=explore) can be replayed from its printout.
settings.register_profile("ci", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

# pyproject's addopts run the tests on one pytest-xdist worker per core, each a process of its
# own: there the compiled kernels and the fitting pools (sized by numba.get_num_threads()) get one
# thread each, so that two workers do not run four threads on two cores. A test that sets its own
# thread count (numba.set_num_threads) still can, up to NUMBA_NUM_THREADS.
if os.environ.get("PYTEST_XDIST_WORKER"):
    numba.set_num_threads(1)

#: The test files that take longest (CPU seconds on the CI's two cores, measured with
#: ``--durations``), longest first: they start first, so that the two workers finish together
#: instead of one running a five-minute file alone at the end. The rest keep their order.
LONGEST_FILES = (
    "problems/timedomain/test_diagnosis.py",  # ~120 s over its tests
    "cli/test_readme.py",  # ~120 s: every quick fenced command of the README and docs
    "problems/timedomain/test_braking_stop.py",  # ~60 s
    "cli/test_suggested_commands.py",
    "studies/test_suite.py",
    "analysis/test_sweep.py",
    "core/test_resume.py",
    "core/test_failures.py",
    "problems/timedomain/test_noise_unsettled.py",
    "problems/timedomain/test_switch_on_flux.py",
    "problems/timedomain/test_tachometer_above_synchronous.py",
)
_TESTS = Path(__file__).resolve().parent


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(LONGEST_FILES)}
    items.sort(key=lambda item: rank.get(item.path.relative_to(_TESTS).as_posix(), len(rank)))  # stable


CONF = str(Path(__file__).resolve().parents[1] / "conf")
PAPER_MOTOR = InductionMotor(Rs=4.96434, Ls=0.1075, Le=0.01098, Rr=1.55618, J=0.00642, fv=0.00033, fc=0.04297, p=1)


def compose_config(overrides=(), name: str = "config"):
    with initialize_config_dir(config_dir=CONF, version_base="1.3"):
        return compose(name, overrides=list(overrides))


#: Data sets stored with the tests (``tests/data/<name>``: ``meta.yaml`` and gzipped records),
#: each made once by the call its ``README.md`` line gives: records a simulator takes minutes to
#: make (motulator's ten-second free stops), which CI would otherwise remake on every run.
STORED_SETS = _TESTS / "data"


def stored_set(name: str, folder: Path) -> Path:
    """The stored data set ``name`` written to ``folder`` as a bench folder holds it (its
    records unzipped, no truth file); returns ``folder``."""
    import gzip
    import shutil

    source = STORED_SETS / name
    folder.mkdir(parents=True)
    shutil.copy(source / "meta.yaml", folder / "meta.yaml")
    for packed in sorted(source.glob("*.csv.gz")):
        with gzip.open(packed, "rb") as fin, open(folder / packed.stem, "wb") as fout:
            shutil.copyfileobj(fin, fout)
    return folder


def remade_blind_set(spec: dict, folder: Path):
    """An independent-plant blind set remade from the ``spec`` of its truth file, written to
    ``folder`` without its truth (as a bench folder holds none); returns (dataset, folder)."""
    from synthetic.independent import make_dataset, write_dataset

    made = make_dataset(spec)
    folder = write_dataset(made, folder)
    (folder / "truth.yaml").unlink(missing_ok=True)
    return made, folder


def diagnose_with(folder: Path, outdir: Path, candidates, *overrides: str) -> dict:
    """The default diagnosis of ``folder`` (``python -m benchmark.diagnose``) with only the
    effects ``candidates``, no figures (and further config ``overrides``); returns the diagnosis
    document."""
    from benchmark.core.harness import run_diagnosis

    cfg = compose_config([f"data.path={folder}", f"candidates=[{','.join(candidates)}]", "figures=false",
                          *overrides], name="diagnose")
    return run_diagnosis(cfg, outdir)


def identify_folder(folder, outdir) -> dict:
    """The default identification (``python -m benchmark data.path=folder``, no figures, no
    checkpoint, no progress bar) of a data folder, its warnings silenced; returns the result record."""
    import warnings

    from benchmark.core.harness import run

    cfg = compose_config([f"data.path={folder}", "figures=false", "checkpoint=false", "progress=false"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run(cfg, outdir).record


@pytest.fixture(scope="session")
def paper_motor():
    return PAPER_MOTOR


@pytest.fixture(scope="session")
def paper_records():
    return run_startup_stop(PAPER_MOTOR, StartupStopTest())


def with_meta_key(folder: Path, key: str, value):
    """Set ``key`` of ``folder/meta.yaml`` to ``value`` (the other keys as they are) and load the
    data set again (:func:`load_startup_dataset`)."""
    import yaml

    from benchmark.problems.timedomain.data import load_startup_dataset

    meta = Path(folder) / "meta.yaml"
    doc = yaml.safe_load(meta.read_text())
    doc[key] = value
    meta.write_text(yaml.safe_dump(doc))
    return load_startup_dataset(folder)
