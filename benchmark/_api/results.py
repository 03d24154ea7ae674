"""The results the API returns: an identification and a diagnosis, each a small typed record
built from what the command line writes (``result.json``, ``diagnosis.json``)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from benchmark.core.harness import _json_default, format_table


class _Document:
    """``to_dict``/``to_json`` of a result whose whole record is the JSON document the command line writes."""

    def _document(self) -> dict:
        raise NotImplementedError

    def to_dict(self) -> dict:
        """The result as plain Python values (the ``result.json`` / ``diagnosis.json`` document)."""
        return json.loads(self.to_json())

    def to_json(self, path=None) -> str:
        """The result as JSON (written to ``path`` too, when given)."""
        text = json.dumps(self._document(), indent=2, default=_json_default) + "\n"
        if path is not None:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            Path(path).write_text(text, encoding="utf-8")
        return text


@dataclass
class Identification(_Document):
    """One identification: the estimate, how sure it is, and how well it fits.

    Attributes
    ----------
    problem, optimizer
        ``timedomain`` or ``admittance``; the optimiser plugin's name.
    seed
        the master seed (same seed, same result, bit for bit).
    status
        ``converged``, ``budget_spent``, ``failed`` or ``timeout``.
    estimate
        every model parameter, ``{name: value}`` in SI units (:attr:`units`).
    units
        ``{name: unit}`` of the parameters (``Rs``: ohm, ``Ls``: H, ``J``: kg m^2, ...).
    standard_error
        ``{name: value}`` of the searched parameters (HAC: honest for coloured
        residuals and model error), in their units; parameters fixed by the data have none.
    correlation
        correlation matrix of the searched parameters (a DataFrame), or None.
    fit_quality
        per channel, the RMS misfit over the noise estimated from the data, the band
        of the noise level and whether the fit is within it.
    warnings
        what the user must know before trusting the estimate (empty when all is well).
    truth, rel_error
        the true parameters and signed relative errors (synthetic data), or None.
    cost, evaluations, wall_time_s
        final cost, evaluations counted, seconds.
    outdir
        the folder ``result.json`` and its companions were written to, or None.
    record
        the whole ``result.json`` document.
    """

    problem: str
    optimizer: str
    seed: int
    status: str
    estimate: dict[str, float]
    units: dict[str, str]
    standard_error: dict[str, float | None]
    correlation: pd.DataFrame | None
    fit_quality: dict
    warnings: list[str]
    truth: dict[str, float] | None
    rel_error: dict[str, float] | None
    cost: float | None
    evaluations: int
    wall_time_s: float
    outdir: Path | None
    record: dict = field(repr=False)
    _problem: Any = field(default=None, repr=False, compare=False)
    _x: Any = field(default=None, repr=False, compare=False)

    @classmethod
    def from_record(cls, record: dict, outdir: Path | None = None, problem=None, x=None) -> Identification:
        """The result of a ``result.json`` document (with the problem and final point when in memory)."""
        names = record.get("parameter_names") or []
        corr = record.get("correlation")
        correlation = None
        if corr and len(corr) == len(names):
            correlation = pd.DataFrame([[math.nan if c is None else c for c in row] for row in corr],
                                       index=names, columns=names)
        est = record.get("estimate") or {}
        units = record.get("units") or getattr(problem, "units", None) or {}
        return cls(problem=record["problem"], optimizer=record["optimizer"], seed=int(record["seed"]),
                   status=record["status"], estimate=dict(est), units={k: units.get(k, "") for k in est},
                   standard_error=dict(record.get("standard_error") or {}), correlation=correlation,
                   fit_quality=dict(record.get("fit_quality") or {}), warnings=list(record.get("warnings") or []),
                   truth=record.get("truth"), rel_error=record.get("rel_error"), cost=record.get("cost"),
                   evaluations=int(record.get("evaluations") or 0), wall_time_s=float(record.get("wall_time_s") or 0),
                   outdir=None if outdir is None else Path(outdir), record=record, _problem=problem, _x=x)

    @classmethod
    def read(cls, path) -> Identification:
        """The result of a run folder (or its ``result.json``) written by ``python -m benchmark``."""
        path = Path(path)
        file = path / "result.json" if path.is_dir() else path
        return cls.from_record(json.loads(file.read_text(encoding="utf-8")), file.parent)

    def __str__(self) -> str:
        """The table the command line prints: parameter, unit, estimate, truth, error, standard error."""
        return format_table(self.record)

    def _document(self) -> dict:
        return self.record

    def figures(self) -> dict:
        """The run's figures, drawn now: ``{name: matplotlib Figure}`` (measured and simulated
        start-up, its first 100 ms, the free stop; or the admittance sweep). Needs the
        identification made in this session (not one read from a folder)."""
        from matplotlib.figure import Figure

        if self._problem is None:
            raise ValueError("figures need the identification made in this session; read the PNG files of "
                             f"{self.outdir} instead" if self.outdir else "figures need the identification in memory")
        out = {}
        with np.errstate(all="ignore"):
            for plot in self._problem.plots(self._x, self.record):
                fig = Figure(figsize=plot.size, layout="constrained")
                plot.draw(fig)
                out[plot.name] = fig
        return out

    def to_motulator(self):
        """The identified motor as motulator's model objects (:class:`MotulatorModel`): its
        Gamma-model parameter class ``InductionMachinePars``, the machine and a stiff mechanical
        system with the identified inertia and friction. Needs motulator (``pip install
        imbench[validation]``)."""
        from benchmark._api.export import motulator_model

        return motulator_model(self.estimate, self.pole_pairs, self.problem)

    def to_mat(self, path) -> Path:
        """Write the estimate to a MATLAB ``.mat`` file (:func:`benchmark._api.export.write_mat`)."""
        from benchmark._api.export import write_mat

        return write_mat(path, self)

    @property
    def pole_pairs(self) -> int | None:
        """Pole pairs of the identified motor (from its data set), or None when unknown."""
        for holder in (getattr(self._problem, "dataset", None), getattr(self._problem, "data", None)):
            if holder is not None and getattr(holder, "pole_pairs", None) is not None:
                return int(holder.pole_pairs)
        return (self.record.get("problem_info") or {}).get("pole_pairs")


@dataclass
class Diagnosis(_Document):
    """Why the identified model still misses the data.

    Attributes
    ----------
    status
        ``no_gap`` (the base model is at the noise level), ``explained``,
        ``partly_explained`` or ``unexplained``.
    verdict
        the effects named, joined by ``+`` (``none`` when there is no gap).
    effects
        the effects chosen, in order of selection.
    explained_share
        share of the excess held-out misfit (above the noise) they remove, 0-1.
    gap_before, gap_after
        held-out RMS residual over the noise (1 = the noise level) of the
        base model and of the final model.
    per_effect
        for each effect, its drop-one share, its share beside the others (and over the noise
        band: ``firm``, see :attr:`not_firm`) and fitted parameters (value, standard error).
    base
        the base model's parameters in the final model, with standard errors (SI units).
    document
        the whole ``diagnosis.json`` document.
    warnings
        what may make the verdict wrong, in words (a speed that reads as through a filter the
        record does not state).
    report
        the text of ``diagnosis.md`` (what ``str()`` prints).
    outdir
        the folder it was written to, or None.
    """

    status: str
    verdict: str
    effects: list[str]
    explained_share: float
    gap_before: float | None
    gap_after: float | None
    per_effect: list[dict]
    base: dict
    warnings: list[str]
    document: dict = field(repr=False)
    report: str = field(repr=False)
    outdir: Path | None = None

    @classmethod
    def from_document(cls, doc: dict, report: str, outdir: Path | None = None) -> Diagnosis:
        def gap(key):
            g = doc.get(key)
            return g.get("heldout_rms_over_noise") if isinstance(g, dict) else g

        return cls(status=doc["status"], verdict=str(doc.get("verdict", "")), effects=list(doc.get("effects") or []),
                   explained_share=float(doc.get("explained_share") or 0.0), gap_before=gap("gap_before"),
                   gap_after=gap("gap_after"), per_effect=list(doc.get("per_effect") or []),
                   base=dict(doc.get("base") or {}), warnings=list(doc.get("warnings") or []),
                   document=doc, report=report,
                   outdir=None if outdir is None else Path(outdir))

    @property
    def not_firm(self) -> list[str]:
        """The named effects that are not firm: they would not earn their place were the noise
        floor elsewhere in its band (a noise estimate a few per cent off); the data do not settle them."""
        from benchmark.problems.timedomain.diagnosis.named import not_firm_effects

        return not_firm_effects({"per_effect": self.per_effect})

    def __str__(self) -> str:
        return self.report

    def _document(self) -> dict:
        return self.document

