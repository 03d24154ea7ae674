"""``python -m benchmark.diagnose``: where the identified model misses the data, which
unmodelled effect causes it, and how far the gap shrinks once it is added.

    python -m benchmark.diagnose data.path=DIR
    python -m benchmark.diagnose 'effects=[double_cage]' noise=noisy     # synthetic plant

Writes ``diagnosis.json`` (verdict, ranking, localisation, gap_before, gap_after),
``diagnosis.md`` and figures into the run folder. Never reads ``truth.yaml``.
"""

from __future__ import annotations

import json
from pathlib import Path

import hydra
import numpy as np
from hydra.core.hydra_config import HydraConfig
from hydra.utils import instantiate
from omegaconf import open_dict

from benchmark.cli import run_hydra_main, user_errors
from benchmark.costs.timedomain import problem_from_dataset
from benchmark.data.startup import StartupDataset, load_startup_dataset
from benchmark.data.tables import write_text_atomic
from benchmark.diagnosis.pipeline import DiagnosisSettings, diagnose
from benchmark.effects import load_effects
from benchmark.errors import ConfigError
from benchmark.polish import polish_least_squares
from benchmark.problem import BudgetedProblem, run_plugin


def load_data(cfg) -> StartupDataset:
    if cfg.data.path is not None:
        return load_startup_dataset(cfg.data.path)
    from synthetic.startup import make_dataset

    ds, _truth_kept_away = make_dataset(cfg)
    return ds


def identify_base(cfg, ds: StartupDataset) -> dict[str, float]:
    """Base identification with the configured optimiser then polish, bounds from the data."""
    with open_dict(cfg):
        cfg.problem.friction_case = int(cfg.diagnosis.base_case)
    problem = problem_from_dataset(cfg, ds, truth=None, preset_bounds=None)
    plugin = instantiate(cfg.optimizer.plugin)
    budget = int(cfg.budget)
    bp = BudgetedProblem(problem, budget)
    res = run_plugin(plugin, bp, seed=int(cfg.seed), name=str(cfg.optimizer.name))
    if res.x is None:
        raise ConfigError(f"optimizer: the base identification failed ({res.message})")
    pol = polish_least_squares(problem, res.x, int(cfg.polish_budget))
    x = pol.best_x if pol.best_x is not None and pol.best_cost <= res.fun else res.x
    est = problem.estimate(x)
    if int(cfg.diagnosis.base_case) == 1:
        est["fc"] = 0.0
    return est


def run_diagnosis(cfg, outdir: Path, progress=None) -> dict:
    if cfg.problem.name == "admittance":  # the slip sweep has its own pipeline
        from benchmark.diagnosis.admittance import run_admittance_diagnosis

        return run_admittance_diagnosis(cfg, outdir, progress)
    ds = load_data(cfg)
    names = list(cfg.candidates) if cfg.get("candidates") else None
    effects = load_effects("timedomain", names)
    settings = DiagnosisSettings(**dict(cfg.diagnosis))
    if settings.base_case not in (1, 2):
        raise ConfigError(f"diagnosis.base_case: must be 1 or 2, got {settings.base_case}")
    base = identify_base(cfg, ds)
    doc = diagnose(ds, base, effects, settings, progress=progress)
    models = doc.pop("_models")
    doc["data"] = cfg.data.path or "synthetic (in memory; truth kept away)"
    outdir.mkdir(parents=True, exist_ok=True)
    write_text_atomic(outdir / "diagnosis.json", json.dumps(doc, indent=2) + "\n")
    write_text_atomic(outdir / "diagnosis.md", render_markdown(doc))
    if cfg.get("figures", True):
        from benchmark.diagnosis.figures import diagnosis_figures

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


@hydra.main(version_base="1.3", config_path="../conf", config_name="diagnose")
@user_errors
def main(cfg) -> None:
    outdir = Path(HydraConfig.get().runtime.output_dir)
    doc = run_diagnosis(cfg, outdir, progress=lambda name: print(f"  fitting {name}", flush=True))
    print(render_markdown(doc))
    print(f"written: {outdir / 'diagnosis.json'}")


if __name__ == "__main__":
    np.seterr(all="ignore")
    run_hydra_main(main)
