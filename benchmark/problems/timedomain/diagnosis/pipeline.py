"""Sim-to-real gap diagnosis for the time-domain problem.

1. Identify the base model: the paper's full model (the configured optimiser on the eq. 13-15
   cost, then polish) with the case-2 mechanical pre-identification (Coulomb and viscous
   friction) from the stop record; without one, ``fv`` and ``fc`` are searched.
   ``diagnosis.base_case=1`` drops Coulomb friction from the base (``coulomb_friction`` is
   then a candidate).
2. Noise of every channel from the data, with its own uncertainty
   (:mod:`benchmark.problems.timedomain.noise`, the one estimate the identification uses too).
3. Refit the base jointly (start-up currents and speed, free-motion stop), each channel
   divided by its noise, on two interleaved folds of blocks; the held-out residual (each
   fold predicted by the fit on the other) is the gap.
4. Screen the candidates by the experiment's facts (``Effect.applies_to``; inverter effects
   need ``dc_link_voltage`` or ``input_hold: zoh``...).
5. Forward selection on the held-out folds (:mod:`.selection`): add the candidate
   with the largest held-out reduction, refit base + all chosen effects jointly, repeat
   while the next one earns its parameters; when none does and the gap left is far above the
   noise, a pair look-ahead (two effects that mask each other enter together when they earn
   together); then the backward check (``Selector.prune``): every
   chosen effect must still earn the band part of that rule beside the others and, where the
   final model is within ``final_share_gap`` (2) of the noise, remove ``min_final_share``
   (60 %) of the excess the model leaves without it (further from the noise ``min_far_share``,
   5 %), else the weakest is dropped (``pruned``) and the check repeats; an effect dropped frees
   its place, and the forward selection resumes once from what is left, without it.
6. Verdict (:func:`verdict_of`) with the statuses below, each chosen effect's drop-one
   share, fitted parameters and standard errors, candidates that leave the same signature,
   and where in time the excess lies.

Numbers of the contract (``DiagnosisSettings``; the same band as the fit-quality verdict of
:func:`benchmark.core.uncertainty.misfit_ratio`):

* the held-out RMS over noise ``rho`` (1 = noise alone) is *at the noise level* when it lies
  in ``misfit_ratio``'s band ``1 +- (2 u + 0.05)``, ``u`` the one-sigma relative
  uncertainty of the ratio (the noise estimate's and the residual's own, with its AR(1)
  coefficient);
* ``no_gap``: the base model's held-out ``rho`` is at (or below) the noise level;
* ``explained``: effects were chosen and what is left is at the noise level, or they remove
  at least ``explained_share`` (90 %) of the excess held-out misfit ``rho^2 - 1`` and what is
  left is within twice the band (``rho - 1 <= 2 (threshold - 1)``): a gap still many times the
  noise is never called explained, whatever share of a huge excess was removed;
* ``partly_explained``: effects were chosen and remove at least ``partly_share`` (30 %);
* ``unexplained``: a gap that no candidate set removes 30 % of (verdict ``unexplained``).

A candidate earns its place when (all three): it removes at least ``min_excess_reduction``
(15 %) of the current excess held-out misfit; that drop exceeds ``min_band_drop`` (half) of
the noise band ``(1 + 2u + 0.05)^2 - 1`` in chi^2 per residual; and the information
criterion ``n_eff ln(SSR_new / SSR_old) + k ln n_eff`` is negative, ``n_eff`` the effective
sample count of the in-sample residual (``n (1 - phi)/(1 + phi)`` per channel, ``phi`` its
AR(1) coefficient), so a smooth model error that correlates thousands of samples does not let
every extra parameter in.

It never reads ``truth.yaml``: the data set is loaded by :func:`load_startup_dataset`,
which reads only ``meta.yaml`` and the record tables.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from benchmark.core.effects import Effect, effect_context
from benchmark.core.uncertainty import misfit_ratio
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel, unit_noise
from benchmark.problems.timedomain.diagnosis.input_noise import with_voltage_noise
from benchmark.problems.timedomain.diagnosis.selection import Selector, SetFit
from benchmark.problems.timedomain.noise import combined

__all__ = ["STATUSES", "DiagnosisSettings", "SetFit", "base_context", "diagnose", "estimated_rated_torque",
           "friction_scale", "held_by_base", "localise", "pullout_torque", "rated_torque", "screen", "verdict_of"]

SEGMENTS = ("electrical_start", "acceleration", "steady_state", "free_stop")
HARMONIC_ORDERS = (-11, -7, -5, -1, 1, 5, 7, 11, 13)
STATUSES = ("no_gap", "explained", "partly_explained", "unexplained")
#: Inverter-only effects when an effect does not say itself (``applies_to``).
INVERTER_EFFECTS = ("inverter_drop",)
SPEED_SENSOR_EFFECTS = ("speed_sensor_gain",)


@dataclass
class DiagnosisSettings:
    """Knobs of the diagnosis (``conf/diagnose.yaml``, key ``diagnosis``); see the module
    docstring for what the numbers mean.

    base_case : 2 (the paper's full model, Coulomb + viscous friction) or 1 (no Coulomb
        friction; ``coulomb_friction`` is then a candidate).
    min_excess_reduction : share of the current excess held-out misfit a new effect must remove.
    min_band_drop : that drop must also exceed this fraction of the noise band (chi^2 units).
    min_final_share : backward check: in the final model (two or more effects), dropping an
        effect must raise the held-out chi^2 by this share of the excess left without it ...
    final_share_gap : ... when the final model's held-out RMS over noise is at most this;
        further from the noise, this smaller share, ``min_far_share``: an effect that removes
        nothing of its own beside the others (a rider that tied with a real effect in its round).
    explained_share, partly_share : shares of the excess separating the statuses.
    max_effects : at most this many effects are chosen.
    indistinguishable_margin : a candidate whose held-out excess reduction in the round an
        effect was chosen is within this of the chosen one's is reported as indistinguishable.
    fit_iterations : trust-region iterations of each local fit.
    screen_keep, screen_iterations : in every round with more remaining candidates than
        ``screen_keep``, each is first fitted cheaply with the chosen ones (fold A,
        ``screen_iterations``, scored on fold B) and only the best ``screen_keep`` are fitted fully.
    band_k, band_floor : ``misfit_ratio``'s k and bias floor.
    pair_keep : when no single candidate earns and the gap left is more than twice the band,
        every pair of candidates is screened and the best ``pair_keep`` pairs are fitted fully
        (:mod:`.selection`); 0 turns the pair look-ahead off.
    final_iterations : trust-region iterations of the final model's fit on all the data (the
        reported parameters and standard errors); the fold fits of the selection stop earlier.
    base_span : the local fits search the base model's electrical and inertia parameters in
        ``[c / base_span, c base_span]`` about the base identification ``c``: an identification
        pulled far off by the unmodelled effects (a stator resistance three times its DC value)
        must stay inside the box, or the augmented model can never return to the motor.
    load_friction_share : a case-2 base whose Coulomb friction exceeds this share of the rated
        torque (nameplate), or without a nameplate of the rated torque estimated from the base
        model's pull-out torque (:func:`estimated_rated_torque`) holds a constant load torque:
        an induction motor's own friction is 0.3-2 % of its rated torque, a constant passive
        load has the same equation, so the record cannot tell them apart; the document then
        lists ``load_torque`` under ``held_by_base``.
    voltage_noise : with measured continuous voltages (``input_hold: linear``), each channel's
        noise level includes the voltage's noise carried through the model (:mod:`.input_noise`).
    """

    base_case: int = 2
    min_excess_reduction: float = 0.15
    min_band_drop: float = 0.5
    min_final_share: float = 0.6
    final_share_gap: float = 2.0
    min_far_share: float = 0.05
    explained_share: float = 0.9
    partly_share: float = 0.3
    max_effects: int = 4
    indistinguishable_margin: float = 0.03
    fit_iterations: int = 12
    screen_keep: int = 6
    screen_iterations: int = 6
    band_k: float = 2.0
    band_floor: float = 0.05
    base_span: float = 5.0
    pair_keep: int = 2
    final_iterations: int = 60
    load_friction_share: float = 0.04
    voltage_noise: bool = True


#: Standard errors by which a base model's Coulomb friction must exceed
#: ``DiagnosisSettings.load_friction_share`` to be called a held load (:func:`held_by_base`).
HELD_LOAD_Z = 2.0

#: Share of the estimated rated torque (:func:`estimated_rated_torque`) that the local fits may
#: always give the friction, whatever the base identification says.
FRICTION_FLOOR_SHARE = 0.03


def friction_scale(estimate: dict[str, float], ctx) -> float:
    """Scale of the friction's search range (N m): 0.3 of the viscous torque at synchronous
    speed plus :data:`FRICTION_FLOOR_SHARE` of the estimated rated torque. ``fc`` is searched
    in ``[0, 5 fc + this]``, ``fv`` up to ``5 fv + this / w_sync``. The floor keeps a friction
    that the base identification put at zero free: a tachometer that reads above synchronous
    speed pulls both to zero (the model then gets as close to it as it can), and a box of
    ``[0, 5 x 0]`` would lock them there for every augmented model, so that a load torque
    would be chosen to stand in for the motor's own friction."""
    return 0.3 * estimate["fv"] * ctx.w_sync + FRICTION_FLOOR_SHARE * estimated_rated_torque(estimate, ctx) + 1e-9


def rated_torque(nameplate: dict | None) -> float | None:
    """Rated torque (N m) of a nameplate with rated power (W) and speed (rpm), else None."""
    if not nameplate or not nameplate.get("rated_power") or not nameplate.get("speed"):
        return None
    return float(nameplate["rated_power"]) / (float(nameplate["speed"]) * 2.0 * np.pi / 60.0)


#: Pull-out over rated torque of the motor whose rated torque :func:`estimated_rated_torque`
#: guesses: induction motors have 2-3.5 (IEC, NEMA design B; the validation motors 2.3-4.9).
PULLOUT_OVER_RATED = 3.0


def pullout_torque(Rs: float, Le: float, ctx) -> float:
    """The base model's pull-out (breakdown) torque at the record's final supply, N m:
    ``3 p V1^2 / (4 w_e (Rs + sqrt(Rs^2 + (w_e Le)^2)))`` with ``V1`` the fundamental phase
    voltage amplitude (V), ``w_e`` its angular frequency (rad/s), ``Rs`` (ohm) and the leakage
    ``Le`` (H); the magnetising branch is neglected (it lowers the torque by a few per cent)."""
    w_e = float(ctx.w_e)
    if w_e <= 0 or ctx.V1 <= 0:
        return 0.0
    return 3.0 * ctx.pole_pairs * ctx.V1**2 / (4.0 * w_e * (Rs + np.hypot(Rs, w_e * Le)))


def estimated_rated_torque(params: Mapping[str, float], ctx) -> float:
    """A rated torque (N m) for a record without a nameplate: the pull-out torque of the base
    model ``params`` over :data:`PULLOUT_OVER_RATED`; 0 when it has no ``Rs`` and ``Le``. It is
    within 0.75-1.6 times the rated torque of the validation motors, whatever their start (a
    slow inverter ramp makes ``T_acc`` a fraction of the rated torque)."""
    if "Rs" not in params or "Le" not in params:
        return 0.0
    return pullout_torque(float(params["Rs"]), float(params["Le"]), ctx) / PULLOUT_OVER_RATED


def held_by_base(names: list[str], x: np.ndarray, ctx, settings: DiagnosisSettings,
                 rated: float | None = None, standard_errors: np.ndarray | None = None) -> list[dict]:
    """Effects the base model already holds under another name: a Coulomb friction above
    ``settings.load_friction_share`` of the rated torque ``rated`` (N m, from the nameplate),
    or without one of :func:`estimated_rated_torque`, is a constant (passive) load torque.

    With ``standard_errors`` (of ``x``, N m for ``fc``) the friction must exceed the share by
    :data:`HELD_LOAD_Z` standard errors: without a stop record the start-up alone leaves the
    friction loosely determined (it trades with the inertia, an iron loss, the heating), and a
    friction that could be the motor's own is not called a load."""
    if rated:
        scale, label = rated, "rated torque"
    else:
        scale = estimated_rated_torque(dict(zip(names, map(float, x), strict=True)), ctx)
        label = "rated torque estimated as 1/3 of the pull-out torque"
    if "fc" not in names or not scale or scale <= 0:
        return []
    k = names.index("fc")
    fc = float(x[k])
    se = float(standard_errors[k]) if standard_errors is not None else 0.0
    se = se if np.isfinite(se) else fc  # not determined: as uncertain as it is large
    share = fc / scale
    if (fc - HELD_LOAD_Z * se) / scale <= settings.load_friction_share:
        return []
    return [{"effect": "load_torque", "form": "constant", "torque_Nm": fc, "standard_error_Nm": se,
             "share_of_scale": share, "scale": label,
             "why": f"the base model's Coulomb friction, {fc:.4g} +- {se:.2g} N m, is {100 * share:.0f} % of the "
                    f"{label} {scale:.4g} N m (a motor's own friction is 0.3-2 % of rated torque): a "
                    f"constant load torque, which acts as Coulomb friction does and cannot be told "
                    f"apart from it on this record"}]


def base_context(data: DiagnosisData, estimate: dict[str, float], dc_link_voltage: float | None):
    """The effects' reference scales from the record and the base estimate, with the rated
    torque of :func:`estimated_rated_torque`."""
    ctx = effect_context(data.t, data.v_alpha, data.v_beta, data.meas[0], data.meas[1],
                         data.meas[2] if data.has_speed else None,
                         data.pole_pairs, estimate["J"], estimate["Ls"] - estimate["Le"], estimate["Le"],
                         dc_link_voltage)
    return replace(ctx, T_rated=estimated_rated_torque(estimate, ctx))


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


def segment_masks(data: DiagnosisData) -> dict[str, np.ndarray]:
    """Masks over the residual vector for the four segments of the experiment."""
    n = data.n_startup
    if data.has_speed:
        w = data.meas[2]
        final = float(np.mean(w[int(0.9 * n):]))
        reached = np.flatnonzero(w >= 0.98 * final)
        t_acc = data.t[reached[0]] if len(reached) else data.t[-1]
    else:
        t_acc = data.t[int(0.6 * n)]
    t_el = min(data.t[0] + 3.0 / data.supply_frequency, t_acc)
    seg = np.where(data.t < t_el, 0, np.where(data.t < t_acc, 1, 2))
    parts = [seg] * len(data.startup_channels())
    if data.stop_t is not None:
        parts.append(np.full(len(data.stop_t), 3))
    seg_all = np.concatenate(parts)
    return {name: seg_all == k for k, name in enumerate(SEGMENTS)}


def localise(data: DiagnosisData, r: np.ndarray, band_hi: float) -> dict:
    """Where the residual ``r`` (noise-normalised) lies: shares by channel and segment, the
    current residual's harmonics, and the time windows of the excess (where its smoothed
    square, over one supply period, exceeds the noise band)."""
    e = r**2
    total = float(e.sum()) or 1.0
    by_channel = {ch: float(e[s].sum() / total) for ch, s in data.channel_slices().items()}
    segs = segment_masks(data)
    by_segment = {k: float(e[m].sum() / total) for k, m in segs.items()}
    n = data.n_startup
    ss = segs["steady_state"][:n]
    sl = data.channel_slices()
    spectrum = {}
    if ss.sum() > 64:
        res_i = (r[sl["i_alpha"]] * data.sigma["i_alpha"] + 1j * r[sl["i_beta"]] * data.sigma["i_beta"])[ss]
        tt = data.t[ss]
        for h in HARMONIC_ORDERS:
            spectrum[str(h)] = float(abs(np.mean(res_i * np.exp(-1j * 2 * np.pi * h * data.supply_frequency * tt))))
    # time windows of the excess over the start-up
    chans = [s for ch, s in sl.items() if ch != "stop_speed"]
    et = np.mean([e[s] for s in chans], axis=0)
    period = max(int(round(1.0 / (data.supply_frequency * data.sample_time))), 1)
    smooth = np.convolve(et, np.ones(period) / period, mode="same")
    above = smooth > band_hi**2
    windows = []
    if above.any():
        idx = np.flatnonzero(above)
        cuts = np.flatnonzero(np.diff(idx) > period) + 1
        for run in np.split(idx, cuts):
            if len(run) < period // 2:
                continue
            excess = float(np.sum(smooth[run] - 1.0))
            windows.append({"start_s": float(data.t[run[0]]), "end_s": float(data.t[run[-1]]),
                            "excess_share": excess})
        tot = sum(w["excess_share"] for w in windows) or 1.0
        for w in windows:
            w["excess_share"] = w["excess_share"] / tot
        windows.sort(key=lambda w: -w["excess_share"])
    stop = None
    if "stop_speed" in sl:
        es = e[sl["stop_speed"]]
        stop = {"chi2_per_residual": float(np.mean(es)), "above_band": bool(np.mean(es) > band_hi**2)}
    main = windows[0] if windows else None
    text = (f"the excess starts at t = {main['start_s']:.3g} s and ends at {main['end_s']:.3g} s "
            f"({100 * main['excess_share']:.0f} % of the start-up's excess)" if main else
            "no part of the start-up exceeds the noise band")
    if stop and stop["above_band"]:
        text += "; the free stop exceeds it too"
    return {"chi2_per_residual": float(e.sum() / len(e)), "by_channel": by_channel, "by_segment": by_segment,
            "current_residual_harmonics_A": spectrum, "excess_windows": windows[:5], "excess_window": main,
            "stop_record": stop, "summary": text}


def verdict_of(settings: DiagnosisSettings, before, after, effects: list[str]) -> tuple[str, str, float]:
    """(status, verdict, explained share) from the held-out fit qualities before/after."""
    excess = before.ratio**2 - 1.0
    share = 0.0
    if effects and excess > 0:
        share = float(np.clip((before.ratio**2 - after.ratio**2) / excess, 0.0, 1.0))
    if before.ratio <= before.threshold:
        return "no_gap", "none", 0.0
    near = after.ratio - 1.0 <= 2.0 * (after.threshold - 1.0)
    if effects and (after.ratio <= after.threshold or (share >= settings.explained_share and near)):
        return "explained", "+".join(effects), share
    if effects and share >= settings.partly_share:
        return "partly_explained", "+".join(effects), share
    return "unexplained", "unexplained", share


def diagnose(ds: StartupDataset, base_estimate: dict[str, float], effects: dict[str, Effect],
             settings: DiagnosisSettings, progress=None) -> dict:
    """Steps 2-6 from a base estimate; returns the diagnosis document (no truth)."""
    t0 = time.perf_counter()
    data = DiagnosisData.from_dataset(ds)
    ctx = base_context(data, base_estimate, ds.dc_link_voltage)
    fold_a, fold_b = data.folds()
    masks = {"A": fold_a, "B": fold_b}
    fc_scale = friction_scale(base_estimate, ctx)
    centre = dict(base_estimate)
    input_noise = None
    if settings.voltage_noise:
        first = JointModel(data, settings.base_case, [], ctx, centre, fc_scale, settings.base_span)
        data, input_noise = with_voltage_noise(data, first, np.array([centre[n] for n in first.base_names]))

    sel = Selector(data, settings, ctx, centre, fc_scale, masks)
    base = sel.model([])
    x0 = np.array([centre[n] for n in base.base_names])
    base_full = base.fit(x0, None, 2 * settings.fit_iterations)
    base_fit = sel.cross_start(SetFit(base, {"A": base.fit(base_full, fold_a, settings.fit_iterations),
                                             "B": base.fit(base_full, fold_b, settings.fit_iterations)}, masks))
    counts = {ch: s.stop - s.start for ch, s in data.channel_slices().items()}
    noise_all = combined(data.noise, counts)

    def quality(held):
        return misfit_ratio(held, unit_noise(noise_all.rel_uncertainty, noise_all.n_effective),
                            k=settings.band_k, bias_floor=settings.band_floor)

    q_before = quality(base_fit.held_used)
    facts = data.facts(settings.base_case)
    candidates, excluded = screen(effects, facts)
    # what the base holds under another name (a load torque in its Coulomb friction) is a suspect:
    # fitted fully in every round of the selection whatever its screening (Selector.forward_selection)
    rated = rated_torque(ds.nameplate)
    held_before = held_by_base(list(base.base_names), base_full, ctx, settings, rated)
    if held_before:  # the point value is above the share: is it with its standard error (a Jacobian)?
        held_before = held_by_base(list(base.base_names), base_full, ctx, settings, rated,
                                   base.standard_errors(base_full))
    suspects = tuple(e for e in candidates if e.name in {h["effect"] for h in held_before})
    if q_before.ratio > q_before.threshold:
        final, rounds = sel.forward_selection(candidates, base_fit, q_before.threshold, progress, suspects)
    else:
        final, rounds = base_fit, []
    full_x = None
    if final.names:  # the fit on all data, also a start for the fold fits (cross_start)
        full_x = final.model.fit(0.5 * (final.xs["A"] + final.xs["B"]), None, settings.final_iterations)
        final = sel.cross_start(final, [full_x])
    before_prune = final.model
    final, withouts, pruned = sel.prune(final, base_fit, q_before.threshold)
    if pruned and len(final.names) < settings.max_effects and final.chi2 > q_before.threshold**2:
        # the pruned effect's place is free: resume the selection once, without the pruned ones
        rest = [e for e in candidates if e.name not in pruned]
        final, more = sel.forward_selection(rest, final, q_before.threshold, progress,
                                            tuple(e for e in suspects if e in rest))
        done = sum(1 for r in rounds if "candidates" in r)
        for r in more:
            r["round"] += done if "candidates" in r else 0
            r["resumed_after_pruning"] = list(pruned)
        rounds += more
        final, withouts, again = sel.prune(final, base_fit, q_before.threshold)
        pruned += again
    q_after = quality(final.held_used)
    chosen = final.names
    status, verdict, share = verdict_of(settings, q_before, q_after, chosen)

    # each chosen effect's own share (drop-one) and its parameters with standard errors
    per_effect = []
    excess = q_before.ratio**2 - 1.0
    if chosen and final.model is not before_prune:  # pruned, or more chosen after: fit the final set again
        full_x = final.model.fit(0.5 * (final.xs["A"] + final.xs["B"]), None, settings.final_iterations)
    se = final.model.standard_errors(full_x) if chosen else None
    for j, name in enumerate(chosen):
        without = withouts[j]
        own = (without.chi2 - final.chi2) / excess if excess > 0 else 0.0
        s = final.model.slices[j]
        per_effect.append({
            "effect": name, "drop_one_share": float(own),
            "parameters": {n.split(".", 1)[1]: {"value": float(full_x[k]), "standard_error": float(se[k])}
                           for k, n in zip(range(s.start, s.stop), final.model.names[s], strict=True)},
        })
    indist = []
    for rnd in rounds:
        if rnd.get("chosen") and rnd["indistinguishable"]:
            indist.append([rnd["chosen"]] + rnd["indistinguishable"])
    weak = []
    if status == "unexplained" and chosen:
        weak = chosen
        chosen = []
    loc = localise(data, base_fit.held, q_before.threshold)
    k_base = len(base.base_names)  # the base parameters of the final model (fitted on all data)
    base_x, base_se = (full_x[:k_base], se[:k_base]) if final.names else (base_full, base.standard_errors(base_full))
    doc = {
        "status": status,
        "verdict": verdict,
        "effects": chosen,
        "explained_share": share,
        "per_effect": per_effect if chosen else [],
        "indistinguishable": indist,
        "excluded": excluded,
        "weak_effects": weak,
        "pruned": pruned,
        "gap_before": {"heldout_rms_over_noise": q_before.ratio, "heldout_chi2_per_residual": q_before.ratio**2,
                       "noise_band": [q_before.lower, q_before.threshold], "at_noise_level": q_before.at_noise_level},
        "gap_after": {"heldout_rms_over_noise": q_after.ratio, "heldout_chi2_per_residual": q_after.ratio**2,
                      "noise_band": [q_after.lower, q_after.threshold], "at_noise_level": q_after.at_noise_level},
        "localisation": loc,
        "selection": rounds,
        "ranking": next((r["candidates"] for r in rounds if "candidates" in r), []),
        "base": {"case": settings.base_case,
                 "estimate": dict(zip(base.base_names, map(float, base_x), strict=True)),
                 "standard_errors": dict(zip(base.base_names, map(float, base_se), strict=True)),
                 "identification": base_estimate},
        "noise": {ch: {"std": float(v.std), "rel_uncertainty": float(v.rel_uncertainty), "method": v.method}
                  for ch, v in data.noise.items()},
        "noise_level": data.sigma,
        "voltage_noise": input_noise,
        "facts": {k: v for k, v in facts.items()},
        "conditioning": list(ds.conditioning),
        "removed_by_conditioning": list(ds.conditioning_removed),
        "held_by_base": held_by_base(list(base.base_names), base_x, ctx, settings, rated, base_se),
        "settings": dict(settings.__dict__),
        "wall_time_s": time.perf_counter() - t0,
    }
    doc["_models"] = {"base": base_fit, "final": final, "full_x": full_x, "band": q_before.threshold}
    return doc
