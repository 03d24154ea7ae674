"""Sim-to-real gap diagnosis for the time-domain problem.

1. Identify the base model (:mod:`.run`): the paper's full model (the configured optimiser on
   the eq. 13-15 cost, then polish) with the case-2 mechanical pre-identification (Coulomb and
   viscous friction) from the stop record; without one, ``fv`` and ``fc`` are searched.
   ``diagnosis.base_case=1`` drops Coulomb friction from the base (``coulomb_friction`` is then
   a candidate).
2. Noise of every channel from the data, with its own uncertainty
   (:mod:`benchmark.problems.timedomain.noise`, the one estimate the identification uses too).
3. The machine's physical scales (:mod:`.scales`: rated torque and current, friction range)
   and each effect's prior range from them and from the experiment's facts (``docs/effects.md``).
4. Refit the base jointly (start-up currents and speed, free-motion stop), each channel divided
   by its noise, on two folds cut by segment of the experiment (:mod:`.folds`); the held-out
   residual (each fold predicted by the fit on the other) is the gap.
5. Screen the candidates by the experiment's facts (``Effect.applies_to``: an inverter drop
   needs an inverter-fed record, a channel skew a stated acquisition skew, ...).
6. Forward selection, pairs, backward check (:mod:`.selection`), every decision by the one rule
   of :mod:`.rule`: an effect earns its place when the model without it is above the noise band
   and it removes at least ``diagnosis.selection_share`` of the excess that model leaves.
7. The conditioning's removals (offsets, masked flattened peaks) checked by the same rule
   beside the chosen effects (:mod:`.conditioning_check`): one is named only when it earns its
   place; the models stay fitted to the conditioned record.
8. Status (:func:`.rule.status_of`): ``no_gap``, ``explained`` (what is left is within the
   band), ``partly_explained`` (effects named, a gap left), ``unexplained`` (a gap that no
   effect earns its place against); each named effect's drop-one share, fitted parameters and
   standard errors; candidates whose held-out score is within ``band_k`` standard errors of the
   chosen one's (``indistinguishable``); where in time the excess lies (:mod:`.localise`).

It never reads ``truth.yaml``: the data set is loaded by :func:`load_startup_dataset`,
which reads only ``meta.yaml`` and the record tables.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from benchmark.core.effects import Effect
from benchmark.core.uncertainty import misfit_ratio
from benchmark.problems.timedomain.conditioning import offsets_left
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.conditioning_check import check_removals, unnamed_line
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel, unit_noise
from benchmark.problems.timedomain.diagnosis.folds import segment_folds
from benchmark.problems.timedomain.diagnosis.input_noise import with_voltage_noise
from benchmark.problems.timedomain.diagnosis.localise import localise
from benchmark.problems.timedomain.diagnosis.rule import STATUSES, Rule, share_over_noise_band, status_of
from benchmark.problems.timedomain.diagnosis.scales import (
    base_context,
    estimated_rated_torque,
    friction_scale,
    held_by_base,
    pullout_torque,
    rated_torque,
    speed_reading_at_rest,
)
from benchmark.problems.timedomain.diagnosis.selection import Selector, SetFit
from benchmark.problems.timedomain.noise import combined

__all__ = ["STATUSES", "DiagnosisSettings", "SetFit", "base_context", "diagnose", "estimated_rated_torque",
           "friction_scale", "held_by_base", "localise", "pullout_torque", "rated_torque", "screen", "status_of"]

#: Inverter-only effects when an effect does not say itself (``applies_to``).
INVERTER_EFFECTS = ("inverter_drop",)
SPEED_SENSOR_EFFECTS = ("speed_sensor_gain",)


@dataclass
class DiagnosisSettings:
    """Knobs of the diagnosis (``conf/diagnose.yaml``, key ``diagnosis``); ``docs/diagnosis.md``
    lists each constant that can change a verdict and how it was set.

    base_case : 2 (the paper's full model, Coulomb + viscous friction) or 1 (no Coulomb
        friction; ``coulomb_friction`` is then a candidate).
    selection_share : ``tau`` of :mod:`.rule`: the share of the excess held-out chi^2 of the
        model without an effect that the effect must remove: 0.5, the smallest share with the
        fewest false selections on development data and form variants (none within 5 % by its
        Wilson interval; ``benchmark.studies.calibration``, ``docs/diagnosis.md``).
    band_k, band_floor : the noise band ``1 +- (band_k u + band_floor)`` of ``misfit_ratio`` (the
        identification's fit-quality band); ``band_k`` is also the number of standard errors
        that makes a difference (a held load, indistinguishable candidates).
    base_span : the local fits search the base model's electrical and inertia parameters in
        ``[c / base_span, c base_span]`` about the base identification ``c``: an identification
        pulled far off by the unmodelled effects (a stator resistance three times its DC value)
        must stay inside the box, or the augmented model can never return to the motor.
    load_friction_share : a case-2 base whose Coulomb friction exceeds this share of the rated
        torque (nameplate; else estimated from the pull-out torque) by ``band_k`` standard
        errors holds a constant load torque (a motor's own friction is 0.3-2 % of its rated
        torque; a constant passive load has the same equation): listed as ``held_by_base``.
    max_iterations : safety cap of each local fit's function evaluations; fits stop at
        convergence (an iteration that changes the whitened SSR by less than 1e-5 of itself, or
        the parameters by 1e-5 of their box) long before it.
    screen_iterations : every start of a fit runs this many evaluations; the one that ends lowest goes on
        to convergence.
    max_effects : at most this many effects are named (None: no cap; 0: the base's gap only).
    voltage_noise : with measured continuous voltages (``input_hold: linear``), each channel's
        noise level includes the voltage's noise carried through the model (:mod:`.input_noise`).
    """

    base_case: int = 2
    selection_share: float = 0.5
    band_k: float = 2.0
    band_floor: float = 0.05
    base_span: float = 5.0
    load_friction_share: float = 0.04
    max_iterations: int = 200
    screen_iterations: int = 6
    max_effects: int | None = None
    voltage_noise: bool = True


def screen(effects: dict[str, Effect], facts: dict) -> tuple[list[Effect], list[dict]]:
    """The candidates the experiment allows, and those excluded with the reason."""
    keep, excluded = [], []
    for name, eff in effects.items():
        reason = None
        if name == "coulomb_friction" and facts["base_case"] == 2:
            reason = "Coulomb friction is in the case-2 base model (diagnosis.base_case=1 makes it a candidate)"
        applies = getattr(eff, "applies_to", None)
        if reason is None and applies is not None:
            reason = applies(dict(facts))
        if reason is None:  # the experiment's facts, also for effects that do not say themselves
            inverter = facts.get("dc_link_voltage") or facts.get("input_hold") == "zoh"
            if name in INVERTER_EFFECTS and not inverter:
                reason = "needs an inverter-fed start (dc_link_voltage or input_hold: zoh in meta.yaml)"
            if name in SPEED_SENSOR_EFFECTS and not facts.get("has_speed"):
                reason = "the record has no speed sensor"
        if reason:
            excluded.append({"effect": name, "reason": str(reason)})
        else:
            keep.append(eff)
    return keep, excluded


def _parameters(model: JointModel, x: np.ndarray, se: np.ndarray, j: int) -> dict:
    """Effect ``j``'s extra parameters: value, standard error and unit (:attr:`Effect.extra_units`)."""
    s, eff = model.slices[j], model.effects[j]
    return {p: {"value": float(x[k]), "standard_error": float(se[k]), "unit": eff.extra_unit(p)}
            for k, p in zip(range(s.start, s.stop), (n.split(".", 1)[1] for n in model.names[s]), strict=True)}


def diagnose(ds: StartupDataset, base_estimate: dict[str, float], effects: dict[str, Effect],
             settings: DiagnosisSettings, progress=None, selector: Selector | None = None) -> dict:
    """Steps 2-8 from a base estimate; returns the diagnosis document (no truth). ``selector``:
    one made by an earlier call on the same data (its fits are reused; the calibration study
    runs the rule at several shares this way)."""
    t0 = time.perf_counter()
    data = DiagnosisData.from_dataset(ds)
    facts = {**ds.facts(), **data.facts(settings.base_case), "offsets_left": offsets_left(ds),
             "speed_reading_at_rest": speed_reading_at_rest(data, base_estimate)}
    ctx = base_context(data, base_estimate, ds.dc_link_voltage, ds.nameplate, facts)
    fold_a, fold_b = segment_folds(data)
    masks = {"A": fold_a, "B": fold_b}
    fc_scale = friction_scale(base_estimate, ctx)
    centre = dict(base_estimate)
    input_noise = None
    rule = Rule(settings.selection_share)
    if selector is not None:
        data, input_noise = selector.data, selector.input_noise
        sel = selector
        sel.settings, sel.rule = settings, rule
    else:
        if settings.voltage_noise:
            first = JointModel(data, settings.base_case, [], ctx, centre, fc_scale, settings.base_span)
            data, input_noise = with_voltage_noise(data, first, np.array([centre[n] for n in first.base_names]))
        order = {name: k for k, name in enumerate(effects)}
        sel = Selector(data, settings, ctx, centre, fc_scale, masks, rule, order)
        sel.input_noise = input_noise  # the document reports it; a reused selector hands it on
    base = sel.model([])
    if sel.base_full is None:  # the base on all data, then on each fold from there
        sel.base_full = base.fit(np.array([centre[n] for n in base.base_names]), None, settings.max_iterations)
        sel.fit([], [(SetFit(base, {"A": sel.base_full, "B": sel.base_full}, masks), [])])
    base_full = sel.base_full
    counts = {ch: s.stop - s.start for ch, s in data.channel_slices().items()}
    noise_all = combined(data.noise, counts)

    def quality(held):
        return misfit_ratio(held, unit_noise(noise_all.rel_uncertainty, noise_all.n_effective),
                            k=settings.band_k, bias_floor=settings.band_floor)

    band_quality = quality(sel.memo[frozenset()].held_used)  # the band every decision uses
    band = band_quality.threshold
    candidates, excluded = screen(effects, facts)
    final, full_x, withouts, order, pruned, rounds = sel.memo[frozenset()], None, {}, [], [], []
    if sel.memo[frozenset()].chi2 > band**2 and settings.max_effects != 0:
        final, full_x, withouts, order, pruned, rounds = sel.select(candidates, sel.memo[frozenset()], band, progress)
    base_fit = sel.memo[frozenset()]  # the best base fit found (drop-one refits may have improved it)
    checks = check_removals(ds, sel, final, band)  # the conditioning's removals, named only when they earn
    unnamed = [r for r in checks if not r["earns"]]
    q_before, q_after = quality(base_fit.held_used), quality(final.held_used)
    status, verdict, share = status_of(q_before, q_after, order)
    if status == "no_gap":  # the best base fit found is at the noise level: nothing to name
        order, q_after = [], q_before

    # each named effect's own share (drop-one) and its parameters with standard errors
    per_effect = []
    excess = q_before.ratio**2 - 1.0
    se = final.model.standard_errors(full_x) if order else None
    for name in order:
        j = final.names.index(name)
        without = withouts[name].chi2
        own = (without - final.chi2) / excess if excess > 0 else 0.0
        per_effect.append({"effect": name, "drop_one_share": float(own),
                           "share_beside_the_others": float((without - final.chi2) / max(without - 1.0, 1e-300)),
                           "share_over_noise_band": list(share_over_noise_band(without, final.chi2,
                                                                               band_quality.lower, band)),
                           "firm": rule.firm(without, final.chi2, band_quality.lower, band),
                           "parameters": _parameters(final.model, full_x, se, j),
                           "physical": final.model.effects[j].describe_fit(full_x[final.model.slices[j]], ctx)})
    indist = [[r["chosen"]] + r["indistinguishable"] for r in rounds if r.get("chosen") and r["indistinguishable"]]
    loc = localise(data, base_fit.held, q_before.threshold)
    k_base = len(base.base_names)  # the base parameters of the final model (fitted on all data)
    base_x, base_se = (full_x[:k_base], se[:k_base]) if order else (base_full, base.standard_errors(base_full))
    rated = rated_torque(ds.nameplate)
    doc = {
        "status": status,
        "verdict": verdict,
        "effects": list(order),
        "explained_share": share,
        "per_effect": per_effect,
        "indistinguishable": indist,
        "excluded": excluded,
        "pruned": pruned,
        "gap_before": {"heldout_rms_over_noise": q_before.ratio, "heldout_chi2_per_residual": q_before.ratio**2,
                       "noise_band": [q_before.lower, q_before.threshold], "at_noise_level": q_before.at_noise_level},
        "gap_after": {"heldout_rms_over_noise": q_after.ratio, "heldout_chi2_per_residual": q_after.ratio**2,
                      "noise_band": [q_after.lower, q_after.threshold], "at_noise_level": q_after.at_noise_level},
        "localisation": loc,
        "selection": rounds,
        "ranking": next((r["candidates"] for r in rounds if "candidates" in r and not r.get("pairs")), []),
        "rule": {"selection_share": settings.selection_share, "band": band},
        "base": {"case": settings.base_case,
                 "estimate": dict(zip(base.base_names, map(float, base_x), strict=True)),
                 "standard_errors": dict(zip(base.base_names, map(float, base_se), strict=True)),
                 "identification": base_estimate},
        "noise": {ch: {"std": float(v.std), "rel_uncertainty": float(v.rel_uncertainty), "method": v.method}
                  for ch, v in data.noise.items()},
        "noise_level": data.sigma,
        "voltage_noise": input_noise,
        "facts": {k: v for k, v in facts.items() if k != "nameplate"},
        "scales": {"rated_torque_Nm": ctx.T_rated, "rated_current_A": ctx.I_rated, "I2t_A2s": ctx.I2t},
        "conditioning": list(ds.conditioning) + [unnamed_line(r) for r in unnamed],
        "removed_by_conditioning": [e for e in ds.conditioning_removed if e not in {r["effect"] for r in unnamed}],
        "conditioning_check": checks,
        "held_by_base": held_by_base(list(base.base_names), base_x, ctx, settings, rated, base_se),
        "settings": dict(settings.__dict__),
        "fits": fits_ended(sel.data.fits, settings.max_iterations),
        "wall_time_s": time.perf_counter() - t0,
    }
    doc["_models"] = {"base": base_fit, "final": final, "full_x": full_x, "band": q_before.threshold,
                      "selector": sel}
    return doc


def fits_ended(tally, cap: int) -> dict:
    """How the selection's local fits ended (:class:`.record.FitTally`): of those run to convergence
    (evaluation cap ``cap``, ``diagnosis.max_iterations``), how many stopped at the cap instead;
    ``by_cap`` every cap's ``[fits, stopped at it]`` (the screening's brief legs stop at theirs by design)."""
    n, at_cap = tally.by_cap.get(int(cap), [0, 0])
    return {"cap": int(cap), "to_convergence": int(n), "stopped_at_cap": int(at_cap),
            "by_cap": {str(k): list(v) for k, v in sorted(tally.by_cap.items())}}
