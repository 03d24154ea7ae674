"""The time-domain diagnosis of one data set, written to a folder: the problem's ``diagnose`` hook.

The entry point (``python -m benchmark.diagnose``) hands over the data set (its truth already
discarded) and the base identification to use (the configured optimiser then polish); this
module builds the typed settings, identifies the base model, runs the pipeline
(:func:`benchmark.problems.timedomain.diagnosis.pipeline.diagnose`) and writes
``diagnosis.json``, ``diagnosis.md`` and the figures.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping
from pathlib import Path

from benchmark.core.effects import load_effects
from benchmark.core.errors import ConfigError
from benchmark.core.io import write_text_atomic
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings, diagnose
from benchmark.problems.timedomain.problem import problem_from_dataset
from benchmark.problems.timedomain.settings import TimeDomainSettings


def diagnosis_settings(run: Mapping) -> DiagnosisSettings:
    """The ``diagnosis`` block of the run configuration, checked."""
    block = dict(run.get("diagnosis") or {})
    known = {f.name for f in dataclasses.fields(DiagnosisSettings)}
    unknown = sorted(set(block) - known)
    if unknown:
        raise ConfigError(f"diagnosis: unknown key(s) {unknown}; known: {sorted(known)}")
    settings = DiagnosisSettings(**block)
    if settings.base_case not in (1, 2):
        raise ConfigError(f"diagnosis.base_case: must be 1 or 2, got {settings.base_case}")
    return settings


def identify_base(problem_settings: TimeDomainSettings, ds: StartupDataset, base_case: int,
                  identify: Callable) -> dict[str, float]:
    """The base model's parameters: ``identify(problem)`` (the configured optimiser then polish)
    on the record with the mechanical pre-identification of ``base_case``, bounds from the data."""
    settings = dataclasses.replace(problem_settings, friction_case=int(base_case), preset_bounds=None)
    problem = problem_from_dataset(settings, ds, truth=None)
    ident = identify(problem)
    if ident.x is None:
        raise ConfigError(f"optimizer: the base identification failed ({ident.result.message})")
    est = problem.estimate(ident.x)
    if int(base_case) == 1:
        est["fc"] = 0.0
    return est


def run_diagnosis(run: Mapping, dataset: StartupDataset, outdir: Path, identify: Callable,
                  progress: Callable[[str], None] | None = None) -> dict:
    """Diagnose ``dataset`` and write the results into ``outdir``; returns the document."""
    settings = diagnosis_settings(run)
    problem_settings = TimeDomainSettings.from_run(run)
    candidates = run.get("candidates")
    effects = load_effects("timedomain", list(candidates) if candidates else None)
    base = identify_base(problem_settings, dataset, settings.base_case, identify)
    doc = diagnose(dataset, base, effects, settings, progress=progress)
    models = doc.pop("_models")
    doc["data"] = (run.get("data") or {}).get("path") or "synthetic (in memory; truth kept away)"
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    write_text_atomic(outdir / "diagnosis.json", json.dumps(doc, indent=2) + "\n")
    write_text_atomic(outdir / "diagnosis.md", render_markdown(doc))
    if run.get("figures", True):
        from benchmark.problems.timedomain.diagnosis.figures import diagnosis_figures

        doc["figures"] = diagnosis_figures(models, doc, outdir)
        write_text_atomic(outdir / "diagnosis.json", json.dumps(doc, indent=2) + "\n")
    return doc


def render_markdown(doc: dict) -> str:
    loc = doc["localisation"]
    lines = [f"# Diagnosis: **{doc['verdict']}**", "",
             f"Data: {doc['data']}", "",
             f"Held-out gap (RMS residual over noise): {doc['gap_before']['heldout_rms_over_noise']:.3f} before, "
             f"{doc['gap_after']['heldout_rms_over_noise']:.3f} after "
             f"(1.0 = the noise level).", "",
             "## Where the base model misses", "",
             f"chi^2 per residual: {loc['chi2_per_residual']:.3f}", "",
             "| channel | share of residual energy |", "|---|---|"]
    lines += [f"| {k} | {100 * v:.1f} % |" for k, v in loc["by_channel"].items()]
    lines += ["", "| segment | share |", "|---|---|"]
    lines += [f"| {k} | {100 * v:.1f} % |" for k, v in loc["by_segment"].items()]
    if loc["current_residual_harmonics_A"]:
        lines += ["", "Current residual by harmonic order of the supply (A; negative = rotating backwards):", "",
                  "| order | " + " | ".join(loc["current_residual_harmonics_A"]) + " |",
                  "|---|" + "---|" * len(loc["current_residual_harmonics_A"]),
                  "| A | " + " | ".join(f"{v:.4f}" for v in loc["current_residual_harmonics_A"].values()) + " |"]
    lines += ["", "## Candidates", "",
              "| effect | held-out reduction | in-sample reduction | criterion (delta chi^2 + k ln n) "
              "| extra parameters |",
              "|---|---|---|---|---|"]
    for r in doc["ranking"]:
        extra = ", ".join(f"{k} = {v:.4g}" for k, v in r["extra_parameters"].items())
        lines.append(f"| {r['effect']} | {100 * r['heldout_reduction']:.1f} % | {100 * r['in_sample_reduction']:.1f} % "
                     f"| {r['criterion']:.1f} | {extra} |")
    lines += ["", "Noise levels estimated from the data: "
              + ", ".join(f"{k} {v:.3g}" for k, v in doc["noise_level"].items()), ""]
    return "\n".join(lines)
