"""The Python API of imbench: load a data set, identify the motor, diagnose what the model
misses, simulate a parameter set, export the model. The command line (``python -m benchmark``,
``python -m benchmark.diagnose``) is built on these functions and gives the same numbers.

Configuration is passed as keyword arguments with the names of the command line's keys
(``python -m benchmark --help`` lists them): ``optimizer="scipy_de"`` chooses a config group's
option, ``budget=2000`` or ``seed=3`` sets a key, and a **double underscore** stands for the dot
of a nested key: ``problem__stator_resistance="prior"`` is ``problem.stator_resistance=prior``.
A misspelt key raises :class:`benchmark.core.errors.ConfigError` naming it and the nearest one.

Example
-------
>>> from benchmark import api
>>> result = api.identify(budget=3000, seed=0)          # the paper's synthetic start-up
>>> result.status, round(result.estimate["Rs"], 3)       # stator resistance, ohm
('converged', 4.964)
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pandas as pd

from benchmark._api.dataset import DataSet, as_folder, read_folder
from benchmark._api.export import MotulatorModel
from benchmark._api.overrides import to_overrides
from benchmark._api.results import Diagnosis, Identification
from benchmark.core.config_files import compose_config, config_groups
from benchmark.core.config_help import chosen

__all__ = ["DataSet", "Diagnosis", "Identification", "MotulatorModel", "diagnose", "identify", "load", "simulate"]


def load(path, *, check: bool = True) -> DataSet:
    """Read a data folder into a :class:`DataSet`: ``meta.yaml`` as a mapping, each record as a
    pandas DataFrame, as the files hold them (conditioning happens when it is identified or
    diagnosed).

    With ``check`` (the default) the folder is also read as an identification reads it, so a
    mistake is refused here, not later: a missing or misspelt key, a missing column, a
    non-numeric cell, phase labels swapped, currents in mA, ... raise
    :class:`benchmark.core.errors.DataError` naming the file, column and row or the key, and data
    that only look wrong give a :class:`benchmark.core.errors.DataWarning`. ``check=False`` reads
    the tables alone (a folder being repaired in memory).

    Example
    -------
    >>> from benchmark import api
    >>> data = api.load("examples/data/bench_1kw")
    >>> data.kind, list(data.tables), data.meta["pole_pairs"]
    ('startup', ['startup', 'stop'], 1)
    """
    data = read_folder(path)
    if check:
        from benchmark.core.harness import load_dataset

        load_dataset(compose_config("config", _overrides("config", data, Path(path), {})), with_truth=False)
    return data


def identify(data=None, *, outdir=None, **overrides) -> Identification:
    """Identify the motor parameters of a data set (``python -m benchmark data.path=...``).

    Parameters
    ----------
    data
        a data folder (path), a :class:`DataSet`, or None for the synthetic data of the
        motor preset (the paper's noise-free start-up by default).
    outdir
        folder for ``result.json``, ``history.csv`` and, with ``figures=True``, the figures
        and ``report.md``; None keeps nothing on disk (figures are then drawn on demand with
        :meth:`Identification.figures`).
    **overrides
        configuration keys, e.g. ``optimizer="scipy_de"``, ``budget=5000``, ``seed=1``,
        ``polish=True``, ``problem__stator_resistance="prior"``, ``bounds={"Rs": [1, 10]}``.

    Returns
    -------
    Identification
        estimate (SI units), standard errors, correlation, fit quality, warnings.

    Example
    -------
    >>> from benchmark import api
    >>> r = api.identify(optimizer="least_squares", budget=300)
    >>> print(r)                                          # doctest: +SKIP
    parameter  unit            estimate         truth     error     std err
    Rs         ohm              4.96434       4.96434   +0.000%    1.01e-07
    ...
    """
    from benchmark.core.harness import run

    with _run_folder(outdir) as folder, _data_path(data) as path:
        if outdir is None:
            overrides.setdefault("figures", False)
            overrides.setdefault("checkpoint", False)
        asked = _overrides("config", data, path, overrides)
        cfg = compose_config("config", asked)
        return identification_of(run(cfg, folder, overrides=asked), folder if outdir is not None else None)


def identification_of(outcome, outdir: Path | None) -> Identification:
    """The :class:`Identification` of a harness run (:func:`benchmark.core.harness.run`)."""
    searched = outcome.record.get("searched")
    x = None if searched is None else np.array(list(searched.values()), dtype=float)
    return Identification.from_record(outcome.record, outdir, outcome.problem, x)


def diagnose(data=None, *, outdir=None, progress: Callable[[str], None] | None = None, **overrides) -> Diagnosis:
    """Diagnose why the identified model misses the data (``python -m benchmark.diagnose``).

    The base model is identified first (the default pipeline from two seeds), then candidate
    effects of the catalogue are added in a forward selection on held-out folds. The data's
    ``truth.yaml`` is never read. A diagnosis takes seconds on a short record with few
    candidates (``candidates=["double_cage"]``) and minutes with the whole catalogue.

    Parameters
    ----------
    data
        a data folder, a :class:`DataSet`, or None for the synthetic plant of the motor
        preset with ``effects=[...]`` injected.
    outdir
        folder for ``diagnosis.json``, ``diagnosis.md`` and the figures; None keeps nothing.
    progress
        called with each candidate's name as it is fitted (e.g. ``print``).
    **overrides
        keys of ``python -m benchmark.diagnose --help``: ``candidates=[...]``,
        ``budget=...``, ``diagnosis__max_effects=2``, ``effects=["double_cage"]`` (synthetic), ...

    Example
    -------
    >>> from benchmark import api
    >>> d = api.diagnose(effects=["double_cage"], noise="noisy", candidates=["double_cage"])  # doctest: +SKIP
    >>> d.status, d.effects                                                             # doctest: +SKIP
    ('explained', ['double_cage'])
    """
    with _run_folder(outdir) as folder, _data_path(data) as path:
        if outdir is None:
            overrides.setdefault("figures", False)
        cfg = compose_config("diagnose", _overrides("diagnose", data, path, overrides))
        return diagnosis_of(cfg, folder, progress, keep=outdir is not None)


def diagnosis_of(cfg, outdir: Path, progress=None, keep: bool = True) -> Diagnosis:
    """The :class:`Diagnosis` of a composed ``diagnose`` configuration, written into ``outdir``
    (:func:`benchmark.core.harness.run_diagnosis`)."""
    from benchmark.core.harness import run_diagnosis

    doc = run_diagnosis(cfg, outdir, progress)
    return Diagnosis.from_document(doc, (Path(outdir) / "diagnosis.md").read_text(encoding="utf-8"),
                                   Path(outdir) if keep else None)


def simulate(params: dict, data=None, **overrides) -> pd.DataFrame:
    """The model's response to the data's inputs for a parameter set, beside the measurement.

    Parameters
    ----------
    params
        the model's parameters in SI units, e.g. ``Identification.estimate``: for the
        time-domain model ``Rs`` (ohm), ``Ls``, ``Le`` (H), ``Rr`` (ohm), ``J`` (kg m^2), ``fv``
        (N m s/rad), ``fc`` (N m); for the slip sweep the circuit's ``R1_total, X1, R2, X2, R0,
        X0`` (ohm; ``R2sigma``, ``X3`` with the 8-parameter model).
    data
        a data folder, a :class:`DataSet`, or None (the motor preset's synthetic data). The
        record is conditioned on load, as for an identification.
    **overrides
        configuration keys, as for :func:`identify` (``problem=...``, ``motor=...``).

    Returns
    -------
    DataFrame
        time domain: ``record`` (index of the start-up record), ``t`` (s), the simulated
        ``i_alpha``, ``i_beta`` (A), ``speed`` (mechanical rad/s) and the measured
        ``i_alpha_measured``, ... (the model starts from rest); slip sweep: ``slip``, the model's
        ``G``, ``B`` (S per phase) and the measured ``G_measured``, ``B_measured``.

    Example
    -------
    >>> from benchmark import api
    >>> paper = {"Rs": 4.96434, "Ls": 0.1075, "Le": 0.01098, "Rr": 1.55618, "J": 0.00642,
    ...          "fv": 0.00033, "fc": 0.04297}
    >>> sim = api.simulate(paper)
    >>> float(abs(sim.i_alpha - sim.i_alpha_measured).max()) < 1e-3   # A; noise-free data of this model
    True
    """
    from hydra.utils import instantiate

    from benchmark.core.harness import build_problem

    with _data_path(data) as path:
        cfg = compose_config("config", _overrides("config", data, path, overrides))
        problem = build_problem(cfg)
        return instantiate(cfg.problem.predict)(problem, dict(params))


# -- plumbing -----------------------------------------------------------------------------------
@contextmanager
def _run_folder(outdir) -> Iterator[Path]:
    if outdir is not None:
        Path(outdir).mkdir(parents=True, exist_ok=True)
        yield Path(outdir)
        return
    with tempfile.TemporaryDirectory(prefix="imbench-run-") as tmp:
        yield Path(tmp)


@contextmanager
def _data_path(data) -> Iterator[Path | None]:
    if data is None or isinstance(data, str | Path):
        yield None if data is None else Path(data)
        return
    if not isinstance(data, DataSet):
        raise TypeError(f"data: a folder, a benchmark.api.DataSet or None, got {type(data).__name__}")
    with as_folder(data) as folder:
        yield folder


def _overrides(name: str, data, path: Path | None, overrides: dict) -> list[str]:
    """The keyword arguments as override strings, with ``data.path`` and, for a data set of
    another kind than the default problem's, the ``problem`` that reads it."""
    overrides = dict(overrides)
    if path is not None:
        overrides["data__path"] = str(path)
    present = chosen(name)
    if path is not None and "problem" not in overrides:
        kind = data.problem if isinstance(data, DataSet) else _folder_problem(path)
        if kind is not None and kind != present.get("problem"):
            overrides["problem"] = kind
    return to_overrides(overrides, added_groups=[g for g in config_groups() if g not in present])


def _folder_problem(path: Path) -> str | None:
    from benchmark.core.harness import DATA_KIND_PROBLEM
    from benchmark.core.meta_file import read_yaml

    try:
        meta = read_yaml(path / "meta.yaml")
    except Exception:  # the problem's loader reports what is wrong with the folder, file and row
        return None
    return DATA_KIND_PROBLEM.get(meta.get("kind", "startup")) if isinstance(meta, dict) else None
