"""The conditioning's removals, checked by the one rule of :mod:`.rule`.

The conditioning on load (:mod:`benchmark.problems.timedomain.conditioning`) removes channel
offsets and masks flattened current peaks by its own tests on part of the record (a pre-trigger,
a steady tail, the peaks' shape). Such a test can be fooled: coloured noise or a current
transformer's remanence moves a short pre-trigger's mean by more than three of its estimated
standard errors, and a main-saturated machine's own currents can look like a probe's flattened
peaks. So the diagnosis names a removal only when it earns its place by the same rule as every
effect: the final model (base plus the chosen effects) is refitted on the record with the
removal put back (:func:`~benchmark.problems.timedomain.conditioning.restored`), and the removal
earns its place when that model is above the noise band and the removal takes at least the
rule's share of the excess it leaves (:meth:`.rule.Rule.earns_fit`, as for every effect; the
in-sample share is reported beside it). One that does not is not named; the models stay fitted to
the conditioned record, as the identification's are (putting a real removal back where a large
gap is left, on a bench record with offsets and saturating probes, made the final model worse:
its stator resistance four times the identification's). Where the selection chose the effect of
the same name beside the removal (an offset left on another channel), the name stands either
way and is not checked.

**Offsets measured at rest.** An offset the conditioning took from a pre-trigger (supply off,
rotor at rest: every channel truly zero) is checked there instead (:func:`at_rest_row`): the
model is exact at rest, so the residual of the record without the removal is the offset plus
the noise, and the rule compares it with the offset held out (each half of the pre-trigger
predicted by the other half's mean), each channel whitened by its own spread about its mean
there, with the noise band of that segment. Beside a large gap (a bench record with a flexible
coupling, 120 times the noise left) a real offset takes almost nothing of the whole record's
excess and would go unnamed; at rest it is what there is to see. A mean that is noise (a short
pre-trigger of coloured noise, a fifth of a sigma) is not visible per sample and is not named.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from benchmark.core.uncertainty import misfit_ratio
from benchmark.problems.timedomain.conditioning import AT_REST, offsets_left, restored
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, unit_noise
from benchmark.problems.timedomain.diagnosis.folds import segment_folds
from benchmark.problems.timedomain.diagnosis.rule import share_removed
from benchmark.problems.timedomain.diagnosis.selection import FOLDS, Selector, SetFit


def check_removals(ds: StartupDataset, sel: Selector, final: SetFit, band: float) -> list[dict]:
    """One row per effect the conditioning removed from ``ds``: the held-out chi^2 of ``final``'s
    effect set refitted with the removal put back (same noise levels), ``final``'s own, the share
    of the excess the removal takes and whether it earns its place (module docstring). Fits are
    kept on ``sel`` (``sel.removal_fits``: a selector of the record with each removal put back,
    :func:`selector_for`): the calibration asks again at other shares."""
    rows, cache = [], sel.removal_fits
    for name in ds.conditioning_removed:
        if name in final.names:  # the selection chose the effect itself beside the removal: named either way
            rows.append({"effect": name, "effects_beside": list(final.names), "chosen_too": True, "earns": True})
            continue
        rest = at_rest_row(ds, sel) if name == "sensor_offset" else None
        if rest is not None:
            rows.append({"effect": name, "effects_beside": list(final.names), **rest})
            continue
        key = (name, frozenset(final.names))
        if key not in cache:
            cache[key] = selector_for(restored(ds, name), sel)
        without = cache[key].fit(final.effects, [(final, [final])])  # kept in its memo
        rows.append({"effect": name, "effects_beside": list(final.names), "heldout_chi2_put_back": without.chi2,
                     "heldout_chi2": final.chi2, "excess_reduction": share_removed(without.chi2, final.chi2),
                     "in_sample_reduction": share_removed(without.in_sample_chi2, final.in_sample_chi2),
                     "earns": sel.rule.earns_fit(without, final, band)})
    return rows


def at_rest_row(ds: StartupDataset, sel: Selector) -> dict | None:
    """The rule's check of the offsets removed at rest (module docstring), or None unless every
    record's offsets were measured on its pre-trigger: the held-out chi^2 per residual at rest
    with the offsets put back (``heldout_chi2_put_back``: the samples themselves, whitened) and
    removed (``heldout_chi2``: each half less the other half's mean), the share of the excess
    and whether the removal earns its place there (against the segment's own noise band: the
    whole record's is another segment's). Only ``sel``'s settings and rule are used."""
    pieces = [(rec.removed or {}).get(AT_REST) for rec in ds.startups
              if "sensor_offset" in (rec.removed or {})]
    if not pieces or any(p is None for p in pieces):
        return None
    without, held, channels = [], [], []
    for piece in pieces:
        for channel, x in piece.items():
            x = np.asarray(x, float)
            a, b = x[: len(x) // 2], x[len(x) // 2:]
            sigma = float(np.std(x, ddof=1))
            if len(a) < 2 or len(b) < 2 or not sigma > 0:
                return None
            without.append(x / sigma)
            held.append(np.concatenate([a - b.mean(), b - a.mean()]) / sigma)
            channels.append((channel, len(x)))
    without, held = np.concatenate(without), np.concatenate(held)
    n = len(held)
    noise_u = 1.0 / np.sqrt(2.0 * (n - len(channels)))  # the spreads' own relative uncertainty
    rest_band = misfit_ratio(held, unit_noise(noise_u, n), k=sel.settings.band_k,
                             bias_floor=sel.settings.band_floor).threshold
    s_without, s_with = float(np.mean(without**2)), float(np.mean(held**2))
    return {"where": "at rest: the pre-trigger the offsets were measured on ("
                     + ", ".join(f"{c} {m} samples" for c, m in channels) + ")",
            "heldout_chi2_put_back": s_without, "heldout_chi2": s_with, "band": rest_band,
            "excess_reduction": share_removed(s_without, s_with),
            "earns": sel.rule.earns(s_without, s_with, rest_band)}


def selector_for(ds: StartupDataset, sel: Selector) -> Selector:
    """A selector of ``ds`` (the record with removals put back) with ``sel``'s noise levels,
    scales, settings and rule, so that its held-out chi^2 compare with ``sel``'s, and ``sel``'s
    tally of fits (:class:`.record.FitTally`), so that the document's ``fits`` counts these refits too."""
    data = replace(DiagnosisData.from_dataset(ds), noise=sel.data.noise)
    data.fits = sel.data.fits
    masks = dict(zip(FOLDS, segment_folds(data), strict=True))
    ctx = replace(sel.ctx, facts={**sel.ctx.facts, "offsets_left": offsets_left(ds)})
    other = Selector(data, sel.settings, ctx, sel.centre, sel.fc_scale, masks, sel.rule, sel.order)
    other.input_noise = sel.input_noise
    return other


def unnamed_line(row: dict) -> str:
    """The report line of a removal the rule does not name."""
    what = {"sensor_offset": "the offsets", "current_sensor_saturation": "the masked samples"}
    where = "the record at rest is within the noise" if "where" in row else "the model fits the record about as well"
    return (f"{row['effect']} removed on load but not named: {where} with "
            f"{what.get(row['effect'], 'it')} put back (held-out chi^2 {row['heldout_chi2_put_back']:.4g}, "
            f"{row['heldout_chi2']:.4g} removed: {100 * row['excess_reduction']:.0f} % of the excess, below the "
            "rule's share or within the noise band); the diagnosis ran on the conditioned record")
