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
import math
import time
from collections.abc import Callable, Mapping
from pathlib import Path

from benchmark.core.effects import load_effects, unit_suffix
from benchmark.core.errors import ConfigError
from benchmark.core.io import write_text_atomic
from benchmark.core.nuisance import refine_nuisance
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.engine import side_by_side
from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings, diagnose
from benchmark.problems.timedomain.motor import PARAMETER_UNITS
from benchmark.problems.timedomain.problem import problem_from_dataset
from benchmark.problems.timedomain.settings import TimeDomainSettings
from benchmark.problems.timedomain.speed_filter import speed_misfit
from benchmark.problems.timedomain.stator_prior import (
    DEFAULT_TEMPERATURE_C,
    WINDING_TEMPERATURE_RANGE_C,
    copper_temperature,
)
from benchmark.problems.timedomain.stop_record import startup_alone, stop_record_check, stop_record_lines


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


#: The base identification runs from these seeds (offsets to the run's seed); the lower cost is kept.
BASE_SEED_OFFSETS = (0, 1)


def identify_base(problem_settings: TimeDomainSettings, ds: StartupDataset, base_case: int,
                  identify: Callable, seed: int = 0) -> tuple[dict[str, float], StartupDataset, dict]:
    """The base model's parameters: ``identify(problem, seed=...)`` (the configured optimiser
    then polish) on the record with the mechanical pre-identification of ``base_case``, bounds
    from the data, from each seed of :data:`BASE_SEED_OFFSETS`, the lower cost kept; then the
    record's nuisance (a measured switch-on's flux step, :mod:`benchmark.core.nuisance`)
    estimated with them; and whether its speed reads like the model's through a filter the record
    does not state (``unstated_speed_filter``: the filter's time constant, the speed's misfit
    without and with it, the identification's warning; or None), with the speed's misfit over
    its noise (``speed_misfit``, read through the stated filter; None without a speed).
    Everything after is a local fit about this point, so a wrong basin here is a wrong
    diagnosis: on an independent-plant 7.5 kW six-step start, 1 seed in 16 of the default
    pipeline ended with two local starts agreeing on J a ninth of the motor's at 8 times the
    cost. Returns the parameters, the data set with the nuisance applied (the one the
    diagnosis's models are fitted to) and what the runs ended at."""
    # the base keeps Rs free unless the run asks for a prior (problem.stator_resistance=prior)
    rs_mode = "free" if problem_settings.stator_resistance == "auto" else problem_settings.stator_resistance
    settings = dataclasses.replace(problem_settings, friction_case=int(base_case), preset_bounds=None,
                                   stator_resistance=rs_mode)
    problem = problem_from_dataset(settings, ds, truth=None)
    alone = startup_alone(settings, ds)
    jobs = [(problem, int(seed) + offset) for offset in BASE_SEED_OFFSETS]
    jobs += [(alone, int(seed))] if alone is not None else []
    # independent runs: side by side where the optimiser says its runs give there what they give alone
    run_jobs = side_by_side if getattr(identify, "concurrent_runs", False) else (lambda fn, xs: [fn(x) for x in xs])
    idents = run_jobs(lambda job: identify(job[0], seed=job[1]), jobs)
    n_base = len(BASE_SEED_OFFSETS)
    runs = [(ident.cost if ident.x is not None else math.inf, s, ident)
            for (_, s), ident in zip(jobs[:n_base], idents[:n_base], strict=True)]
    cost, kept_seed, ident = min(runs, key=lambda r: r[0])
    record = {"runs": [{"seed": s, "cost": c} for c, s, _ in runs], "kept_seed": kept_seed,
              "agree": bool(max(c for c, _, _ in runs) <= (1 + 1e-3) * cost)}
    if ident.x is None:
        raise ConfigError(f"optimizer: the base identification failed ({ident.result.message})")
    check = None if alone is None else stop_record_check(settings, ds, problem, ident, identify, int(seed),
                                                         (alone, idents[-1]))
    if check is not None:
        record["stop_record"], alone, ident_alone = check
        if not record["stop_record"]["used"]:
            problem, ident = alone, ident_alone
    x = ident.x
    refined = refine_nuisance(problem, x, ident.cost)
    if refined is not None and refined.accepted:
        x = refined.x
    hint = problem.unstated_speed_filter(x)
    record["unstated_speed_filter"] = None if hint is None else {**dataclasses.asdict(hint), "warning": hint.warning}
    record["speed_misfit"] = speed_misfit(problem, x[None, :], [problem.speed_lag]) if problem.speed_measured else None
    est = problem.estimate(x)
    if int(base_case) == 1:
        est["fc"] = 0.0
    return est, problem.dataset_with_nuisance(), record


def run_diagnosis(run: Mapping, dataset: StartupDataset, outdir: Path, identify: Callable,
                  progress: Callable[[str], None] | None = None) -> dict:
    """Diagnose ``dataset`` and write the results into ``outdir``; returns the document."""
    t0, c0 = time.perf_counter(), time.process_time()
    settings = diagnosis_settings(run)
    problem_settings = TimeDomainSettings.from_run(run)
    candidates = run.get("candidates")
    effects = load_effects("timedomain", list(candidates) if candidates else None)
    base, dataset, base_runs = identify_base(problem_settings, dataset, settings.base_case, identify,
                                             seed=int(run.get("seed", 0) or 0))
    t_base = time.perf_counter() - t0
    doc = diagnose(dataset, base, effects, settings, progress=progress)
    models = doc.pop("_models")
    doc["wall_time_s"] = time.perf_counter() - t0
    doc["cpu_time_s"] = time.process_time() - c0  # all threads: wall time on a loaded machine misleads
    doc["wall_time_base_identification_s"] = t_base
    doc["base_identification"] = base_runs
    doc["warnings"] = diagnosis_warnings(doc)
    doc["data"] = (run.get("data") or {}).get("path") or "synthetic (in memory; truth kept away)"
    doc["stator_dc_resistance"] = stated_resistance_check(dataset, (doc.get("base") or {}).get("estimate") or {},
                                                          problem_settings.stator_resistance)
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    write_text_atomic(outdir / "diagnosis.json", json.dumps(doc, indent=2) + "\n")
    write_text_atomic(outdir / "diagnosis.md", render_markdown(doc))
    if run.get("figures", True):
        from benchmark.problems.timedomain.diagnosis.figures import diagnosis_figures

        doc["figures"] = diagnosis_figures(models, doc, outdir)
        write_text_atomic(outdir / "diagnosis.json", json.dumps(doc, indent=2) + "\n")
    return doc


def diagnosis_warnings(doc: dict) -> list[str]:
    """What may make the verdict wrong, in words (``warnings`` of the document; the API's
    :attr:`~benchmark._api.results.Diagnosis.warnings`): a speed that reads as through a filter the
    record does not state (every model then reads it unfiltered, and an effect may be named for
    the filter's lag)."""
    hint = (doc.get("base_identification") or {}).get("unstated_speed_filter")
    return [f"Base identification: {hint['warning']}. The effects here were chosen reading the speed "
            "unfiltered: one may stand for the filter's lag."] if hint else []


def stated_resistance_check(dataset: StartupDataset, final: Mapping, rs_mode: str) -> dict | None:
    """meta.yaml's ``stator_dc_resistance`` against the final model's Rs (None when the data set
    states none): the deviation, the copper winding temperature it would take
    (:func:`~benchmark.problems.timedomain.stator_prior.copper_temperature`), whether that is one a
    winding can have, and whether the diagnosis used the stated value (only when asked:
    ``problem.stator_resistance=prior|fixed``; its base keeps Rs free by default)."""
    dc = getattr(dataset, "stator_dc_resistance", None)
    if not dc or "Rs" not in final:
        return None
    theta_dc = getattr(dataset, "winding_temperature", None)
    theta = copper_temperature(final["Rs"], dc, theta_dc)
    lo, hi = WINDING_TEMPERATURE_RANGE_C
    return {"ohm": float(dc), "winding_temperature_C": theta_dc, "final_Rs_ohm": float(final["Rs"]),
            "relative_deviation": float(final["Rs"]) / float(dc) - 1.0, "copper_temperature_C": theta,
            "copper_can_reach": bool(lo <= theta <= hi), "used": rs_mode in ("prior", "fixed")}


def stated_resistance_lines(check: dict | None) -> list[str]:
    """What diagnosis.md says about a stated DC stator resistance (:func:`stated_resistance_check`)."""
    if not check:
        return []
    at = "" if check["winding_temperature_C"] is None else f" at {check['winding_temperature_C']:g} deg C"
    used = ("used as the run asks (problem.stator_resistance)" if check["used"] else
            "not used: the diagnosis fits Rs from the record (problem.stator_resistance=prior makes it a prior)")
    line = (f"Stated DC stator resistance (meta.yaml): {check['ohm']:.4g} ohm{at}, {used}. The final model's Rs, "
            f"{check['final_Rs_ohm']:.4g} ohm, is {100 * check['relative_deviation']:+.0f} % off it: a copper winding "
            f"at {check['copper_temperature_C']:.0f} deg C"
            + (f" (the DC value taken at {DEFAULT_TEMPERATURE_C:g} deg C: meta.yaml states no winding_temperature)"
               if check["winding_temperature_C"] is None else ""))
    if not check["copper_can_reach"]:
        lo, hi = WINDING_TEMPERATURE_RANGE_C
        line += (f", which no winding reaches ({lo:g} to {hi:g} deg C): the model's Rs stands for more than the "
                 "winding (a drop, a heating, a form the model lacks)")
    return [line + "."]


def base_identification_lines(bi: dict | None) -> list[str]:
    """What diagnosis.md says about the base identification: seeds that ended apart, a stop
    record set aside (or kept although the start-up alone found another J)."""
    lines: list[str] = []
    if bi and not bi["agree"]:
        costs = ", ".join(f"seed {r['seed']}: {r['cost']:.6g}" for r in bi["runs"])
        lines.append(f"Base identification: the runs from different seeds ended apart ({costs}); the lowest "
                     f"(seed {bi['kept_seed']}) is used. The others stopped in another basin: the landscape "
                     "is hard, and a run with one seed alone may land there.")
    return lines + stop_record_lines((bi or {}).get("stop_record"))


def fitted_parameter(name: str, p: dict) -> str:
    """``name = value unit +- standard_error unit`` of an effect's fitted extra parameter (``p``:
    ``value``, ``standard_error``, ``unit``; a dimensionless ``-`` or a document without units
    shows the bare numbers)."""
    u = unit_suffix(p.get("unit"))
    return f"{name} = {p['value']:.4g}{u} +- {p['standard_error']:.2g}{u}"


def capped_fit_lines(fits: dict | None) -> list[str]:
    """The warning of diagnosis.md when local fits meant to converge stopped at their safety cap."""
    if not fits or not fits.get("stopped_at_cap"):
        return []
    return [f"**Not converged:** {fits['stopped_at_cap']} of {fits['to_convergence']} local fits stopped at the safety "
            f"cap of {fits['cap']} evaluations (`diagnosis.max_iterations`) instead of converging: the verdict may "
            "hang on where they stopped (run again with a higher cap to see whether it moves).", ""]


def render_markdown(doc: dict) -> str:
    loc = doc["localisation"]
    gb, ga = doc["gap_before"], doc["gap_after"]
    lines = [f"# Diagnosis: **{doc['verdict']}** ({doc['status'].replace('_', ' ')})", "",
             f"Data: {doc['data']}", "",
             f"Held-out gap (RMS residual over noise, 1.0 = the noise level): {gb['heldout_rms_over_noise']:.3f} "
             f"before, {ga['heldout_rms_over_noise']:.3f} after; at the noise level up to "
             f"{gb['noise_band'][1]:.3f} (the noise estimate's own uncertainty).",
             f"Share of the excess held-out misfit (above the noise) explained: "
             f"{100 * doc['explained_share']:.0f} %.", "",
             f"Where: {loc['summary']}." if doc["status"] != "no_gap" else _no_gap_where(loc), ""]
    lines += [line for w in doc.get("warnings", []) for line in (f"**Check:** {w}", "")]
    lines += capped_fit_lines(doc.get("fits"))
    if doc["per_effect"]:
        lines += ["| effect (in order of selection) | own share (drop-one) | share beside the others (the rule's) "
                  "| fitted parameters (+- standard error) |", "|---|---|---|---|"]
        for pe in doc["per_effect"]:
            par = ", ".join(fitted_parameter(k, v) for k, v in pe["parameters"].items())
            lines.append(f"| {pe['effect']} | {100 * pe['drop_one_share']:.0f} % "
                         f"| {100 * pe['share_beside_the_others']:.0f} % | {par} |")
        lines.append(f"\nAn effect earns its place when the model without it is above the noise band and it removes "
                     f"at least {100 * doc['rule']['selection_share']:.0f} % of the excess that model leaves.")
        lines += not_firm_lines(doc)
        lines.append("")
    base = doc.get("base") or {}
    if base.get("estimate"):
        se, first = base.get("standard_errors") or {}, base.get("identification") or {}
        lines += ["| base model parameter | unit | in the final model (+- standard error) | identified alone |",
                  "|---|---|---|---|"]
        for k, v in base["estimate"].items():
            value = f"{v:.5g}" + (f" +- {se[k]:.2g}" if se.get(k) is not None else "")
            alone = f"{first[k]:.5g}" if k in first else "-"
            lines.append(f"| {k} | {PARAMETER_UNITS.get(k, '-')} | {value} | {alone} |")
        lines += ["", "\"Identified alone\" is the diagnosis's own base identification (two seeds and its own budgets: "
                  "conf/diagnose.yaml); `python -m benchmark` on the same folder runs the run's optimiser and "
                  "budget, and may end a few digits apart.", ""]
    for group in doc["indistinguishable"]:
        lines.append(f"Indistinguishable on this experiment (same held-out signature): {', '.join(group)}.")
    lines += pruned_lines(doc)
    for ex in doc["excluded"]:
        lines.append(f"Not a candidate: {ex['effect']}: {ex['reason']}.")
    for h in doc.get("held_by_base", []):
        lines.append(f"Held by the base model: {h['effect']} ({h['form']}): {h['why']}.")
    if doc.get("removed_by_conditioning"):
        lines.append("Found and removed by the conditioning on load (the diagnosis ran on the conditioned record): "
                     + ", ".join(doc["removed_by_conditioning"]) + ".")
    for c in doc.get("conditioning_check", []):
        if "excess_reduction" in c:
            where = c.get("where") or f"beside {' + '.join(c['effects_beside']) or 'the base'}"
            lines.append(f"The conditioning's {c['effect']} checked by the rule {where}: removing it takes "
                         f"{100 * c['excess_reduction']:.0f} % of the excess held-out chi^2 "
                         f"({c['heldout_chi2_put_back']:.4g} -> {c['heldout_chi2']:.4g}): "
                         + ("named." if c["earns"] else "not named (the models stay fitted to the conditioned "
                                                        "record)."))
    lines += stated_resistance_lines(doc.get("stator_dc_resistance"))
    lines += base_identification_lines(doc.get("base_identification"))
    lines += ["", "## Where the base model misses", "",
              f"chi^2 per held-out residual: {loc['chi2_per_residual']:.3f}", "",
              "| channel | share of residual energy |", "|---|---|"]
    lines += [f"| {k} | {100 * v:.1f} % |" for k, v in loc["by_channel"].items()]
    lines += ["", "| segment | share |", "|---|---|"]
    lines += [f"| {k} | {100 * v:.1f} % |" for k, v in loc["by_segment"].items()]
    if loc["excess_windows"]:
        lines += ["", "| excess window | start (s) | end (s) | share of the excess |", "|---|---|---|---|"]
        lines += [f"| {k + 1} | {w['start_s']:.4g} | {w['end_s']:.4g} | {100 * w['excess_share']:.0f} % |"
                  for k, w in enumerate(loc["excess_windows"])]
    for rnd in doc["selection"]:
        start = f"base{''.join(' + ' + e for e in rnd['from'])}"
        if rnd.get("pairs"):
            lines += ["", f"## Pairs from {start} (no single candidate earns its place; each pair's fold-B held-out "
                          "chi^2 predicted by a score test; the best and those that may earn fitted fully)", "",
                      "| pair | predicted held-out chi^2 (fold B) | may earn |", "|---|---|---|"]
            lines += [f"| {r['effect']} | {r['heldout_chi2_fold_B']:.3f} | {'yes' if r['may_earn'] else 'no'} |"
                      for r in rnd["screening"][:8]]
            lines += ["", "| pair | held-out chi^2 | shares beside each other (held out / in sample) | earns |",
                      "|---|---|---|---|"]
            lines += [f"| {r['effect']} | {r['heldout_chi2']:.3f} | "
                      + ", ".join(f"{k} {100 * v:.0f} / {100 * r['in_sample_shares_beside_each_other'][k]:.0f} %"
                                  for k, v in r["shares_beside_each_other"].items())
                      + f" | {'yes' if r['earns'] else 'no'} |" for r in rnd["candidates"]]
            continue
        lines += ["", f"## Selection round {rnd['round']} (from {start}, held-out chi^2 "
                      f"{rnd['heldout_chi2_from']:.3f})", "",
                  "| candidate | held-out chi^2 | share of the excess removed (held out) | in sample | earns |",
                  "|---|---|---|---|---|"]
        for r in rnd["candidates"]:
            lines.append(f"| {r['effect']} | {r['heldout_chi2']:.3f} | {100 * r['excess_reduction']:.1f} % "
                         f"| {100 * r['in_sample_reduction']:.1f} % | {'yes' if r['earns'] else 'no'} |")
        lines += [f"| {r['effect']} | screened {r['screened_heldout_chi2']:.3f} | | | not fitted (its screening "
                  "removes less than the share; another earns) |" for r in rnd.get("screening", []) if not r["fitted"]]
        if rnd.get("refused"):
            lines += ["", f"`{rnd['refused']['effect']}` earns its place, but {rnd['refused']['why']}: out of the "
                          "candidates."]
    lines += ["", "Noise estimated from the data: "
              + "; ".join(f"{k} {v['std']:.3g} (+-{100 * v['rel_uncertainty']:.0f} %, {v['method']})"
                          for k, v in doc["noise"].items()),
              "", f"Wall time: {doc['wall_time_s']:.1f} s (CPU {doc.get('cpu_time_s', float('nan')):.1f} s).", ""]
    return "\n".join(lines)


def pruned_lines(doc: dict) -> list[str]:
    """What the backward check dropped (``pruned``, in order; an effect dropped right after an
    entry may enter again beside another and is then in the final set)."""
    final = set(doc.get("effects", []))
    gone = list(dict.fromkeys(n for n in doc.get("pruned", []) if n not in final))
    back = list(dict.fromkeys(n for n in doc.get("pruned", []) if n in final))
    out = []
    if gone:
        out.append("Chosen, then dropped (no longer earning its place beside the others): " + ", ".join(gone) + ".")
    if back:
        out.append("Dropped once (another effect made it redundant), then chosen again beside the others: "
                   + ", ".join(back) + ".")
    return out


def not_firm_lines(doc: dict) -> list[str]:
    """A line for each named effect that is not firm (:meth:`.rule.Rule.firm`): its share
    beside the others as the noise floor moves within its band, against the rule's share."""
    out = []
    for pe in doc["per_effect"]:
        if pe.get("firm", True):
            continue
        low, high = pe["share_over_noise_band"]
        span = f"{100 * low:.0f} % to {100 * high:.0f} %" if math.isfinite(high) else f"{100 * low:.0f} % or more"
        out.append(f"**Not firm: {pe['effect']}.** Beside the others it removes {span} of the excess as the noise "
                   f"floor moves within its band (the noise estimate's own uncertainty), against the rule's "
                   f"{100 * doc['rule']['selection_share']:.0f} %: a noise estimate a few per cent off would not "
                   f"have named it, and the data do not settle it.")
    return out


def _no_gap_where(loc: dict) -> str:
    """Where, when there is no gap: the record's largest local rise above the band, which noise makes
    somewhere in any record, without the share of an excess there is not."""
    w = loc.get("excess_window")
    if not w:
        return "Where: nowhere (the held-out gap is within the band, and no part of the start-up exceeds it)."
    return (f"Where: nowhere (the held-out gap is within the band); its largest local rise above the band, "
            f"t = {w['start_s']:.3g}-{w['end_s']:.3g} s, is what noise gives somewhere in a record.")
