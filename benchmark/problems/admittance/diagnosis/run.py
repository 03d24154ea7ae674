"""The slip-sweep diagnosis of one data set, written to a folder: the problem's diagnose hook."""

from __future__ import annotations

from pathlib import Path

from benchmark.core.effects import unit_suffix
from benchmark.problems.admittance.data import AdmittanceData
from benchmark.problems.admittance.diagnosis.figures import sweep_figures
from benchmark.problems.admittance.diagnosis.pipeline import AdmittanceDiagnosisSettings, diagnose_sweep

# ----------------------------------------------------------------------------- entry point


def settings_from_run(run) -> AdmittanceDiagnosisSettings:
    """The ``admittance_diagnosis`` block of the run configuration, checked."""
    from benchmark.core.errors import ConfigError

    block = dict(run.get("admittance_diagnosis") or {})
    known = set(AdmittanceDiagnosisSettings.__dataclass_fields__)
    unknown = sorted(set(block) - known)
    if unknown:
        raise ConfigError(f"admittance_diagnosis: unknown key(s) {unknown}; known: {sorted(known)}")
    return AdmittanceDiagnosisSettings(**block)


def run_diagnosis(run, data: AdmittanceData, outdir, identify=None, progress=None) -> dict:
    """The problem's ``diagnose`` hook: diagnose one sweep data set and write ``diagnosis.json``,
    ``diagnosis.md`` and the figures into ``outdir``. The sweep's base fit is its own
    (Lindsay-Barton regression then least squares), so ``identify`` is not used."""
    import json

    from benchmark.core.effects import load_effects
    from benchmark.core.io import write_text_atomic

    if data.loadtest is not None:
        from benchmark.core.errors import ConfigError

        raise ConfigError(f"data.path: {data.source} is a motor test report (kind: loadtest); the steady-state "
                          "diagnosis reads slip sweeps (kind: admittance) only. Identify the report with "
                          "python -m benchmark problem=admittance data.path=...; its warnings say what the data "
                          "cannot fix")
    outdir = Path(outdir)
    candidates = run.get("candidates")
    effects = load_effects("admittance", list(candidates) if candidates else None)
    settings = settings_from_run(run)
    doc = diagnose_sweep(data, effects, settings, progress=progress)
    models = doc.pop("_models")
    doc["data"] = (run.get("data") or {}).get("path") or "synthetic (in memory; truth kept away)"
    outdir.mkdir(parents=True, exist_ok=True)
    if run.get("figures", True):
        doc["figures"] = sweep_figures(models, doc, outdir)
    write_text_atomic(outdir / "diagnosis.json", json.dumps(doc, indent=2) + "\n")
    write_text_atomic(outdir / "diagnosis.md", render_sweep_markdown(doc))
    return doc


def render_sweep_markdown(doc: dict) -> str:
    loc = doc["localisation"]
    hs = doc["heldout_scheme"]
    lines = [
        f"# Diagnosis (slip sweep): **{doc['verdict']}** ({doc.get('status', '').replace('_', ' ')})",
        "",
        "Share of the excess held-out misfit (above the noise) explained: "
        f"{100 * doc.get('explained_share', 0.0):.0f} %; "
        f"at the noise level up to a held-out RMS over noise of {doc.get('noise_band', [0, float('nan')])[1]:.3f}.",
        "",
        f"Data: {doc['data']}",
        "",
        f"Base model: {doc['base']['model']}; "
        + ", ".join(f"{k} = {v:.5g}" for k, v in doc["base"]["estimate"].items())
        + " ohm.",
        "",
        f"Held-out misfit: each {hs['kind'].replace('_', ' ')} ({hs['folds']} folds) predicted from a fit to "
        "the others.",
        "",
        f"Held-out gap (RMS residual over noise): {doc['gap_before']['heldout_rms_over_noise']:.3f} before, "
        f"{doc['gap_after']['heldout_rms_over_noise']:.3f} after (1.0 = the noise level); base RMS misfit "
        f"{doc['gap_before']['rms_percent_of_full_scale']:.3f} % of full scale.",
        "",
        *_lenient_note(doc),
        "## Where the base model misses",
        "",
        f"chi^2 per residual (in sample): {loc['chi2_per_residual']:.3f}",
        "",
        "| slip region | share of residual energy | of it in G | in B "
        "| mean G residual / noise | mean B residual / noise |",
        "|---|---|---|---|---|---|",
    ]
    comp, mean = loc["by_slip_region_and_component"], loc["mean_residual_over_noise"]
    for k, v in loc["by_slip_region"].items():
        lines.append(
            f"| {k} | {100 * v:.1f} % | {100 * comp[k + '/G']:.1f} % | {100 * comp[k + '/B']:.1f} % "
            f"| {mean[k + '/G']:+.2f} | {mean[k + '/B']:+.2f} |"
        )
    lines += ["", "| component | share |", "|---|---|"]
    lines += [f"| {k} | {100 * v:.1f} % |" for k, v in loc["by_channel"].items()]
    lines += ["", "| voltage level | share |", "|---|---|"]
    lines += [f"| {k} | {100 * v:.1f} % |" for k, v in loc["by_voltage_level"].items()]
    if loc["by_sweep_direction"]:
        lines += ["", "| sweep direction | share |", "|---|---|"]
        lines += [f"| {k} | {100 * v:.1f} % |" for k, v in loc["by_sweep_direction"].items()]
    lines += [
        "",
        "## Candidates",
        "",
        "| effect | held-out reduction | in-sample reduction | criterion (< 0 earns its parameters) "
        "| extra parameters |",
        "|---|---|---|---|---|",
    ]
    for r in doc["ranking"]:
        units = r.get("extra_parameter_units") or {}
        extra = ", ".join(f"{k} = {v:.4g}{unit_suffix(units.get(k))}" for k, v in r["extra_parameters"].items())
        lines.append(
            f"| {r['effect']} | {100 * r['heldout_reduction']:.1f} % "
            f"| {100 * r['in_sample_reduction']:.1f} % | {r['criterion']:.1f} | {extra} |"
        )
    lines += ["", noise_sentence(doc["noise_level"]), ""]
    return "\n".join(lines)


def noise_sentence(nl: dict) -> str:
    """What the report says of the noise: given or estimated, its level, and how it grows with the reading."""
    if nl.get("source") == "given":
        return f"Noise given (admittance_diagnosis.noise): {nl['G_S']:.3g} S on G and on B."
    text = (
        f"Noise estimated from the data: G {nl['G_S']:.3g} S, B {nl['B_S']:.3g} S "
        f"({nl['percent_of_full_scale']:.4f} % of full scale, RMS over the readings)"
    )
    if nl.get("proportional_share", 0.0) > 0:
        text += (
            f"; it grows with the reading: {nl['constant_S']:.3g} S plus {100 * nl['reading_fraction']:.3g} % of "
            f"|Y| (in quadrature), {100 * nl['proportional_share']:.0f} % of its variance proportional"
        )
    return text + "."


def _lenient_note(doc: dict) -> list[str]:
    """Why a gap above the band is no gap: another noise shape the data allow puts the base at the noise."""
    upper = doc.get("noise_band", [0.0, float("inf")])[1]
    lenient = doc.get("lenient_heldout_rms_over_noise")
    if doc.get("status") != "no_gap" or lenient is None or doc["gap_before"]["heldout_rms_over_noise"] <= upper:
        return []
    return [f"No gap is claimed: under a noise shape the data allow as well (how the noise grows with the "
            f"reading), the held-out gap is {lenient:.3f}, within the band.", ""]

