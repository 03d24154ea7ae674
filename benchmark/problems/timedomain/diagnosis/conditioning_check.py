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
rule's share of the excess it leaves. One that does not is not named; the models stay fitted to
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

**Masked peaks.** The flattened current peaks the conditioning masked are checked on those
samples (:func:`masked_peaks_row`): each is predicted by the final model fitted on the other
fold (its held-out prediction, as in the score), with and without a probe's compression
``L tanh(i / L)`` on the phase currents, ``L`` fitted to the other fold's masked samples. A probe
that compresses the peaks leaves residuals there that the compression takes away, whatever gap
the rest of the record holds; a machine whose own currents are peaky (main saturation) is
under-predicted there, and a compression cannot help. Judged on the whole record beside a gap
of 120 times the noise, real compressed peaks took 1 % of its excess.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.optimize import minimize_scalar

from benchmark.core.uncertainty import misfit_ratio
from benchmark.problems.timedomain.conditioning import restored
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, unit_noise
from benchmark.problems.timedomain.diagnosis.folds import segment_folds
from benchmark.problems.timedomain.diagnosis.rule import share_removed
from benchmark.problems.timedomain.diagnosis.selection import FOLDS, Selector, SetFit
from benchmark.problems.timedomain.frames import clarke, inverse_clarke


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
        if name == "current_sensor_saturation":
            rest = masked_peaks_row(ds, sel, final)
        if rest is not None:
            rows.append({"effect": name, "effects_beside": list(final.names), **rest})
            continue
        key = (name, frozenset(final.names))
        if key not in cache:
            cache[key] = selector_for(restored(ds, name), sel)
        without = cache[key].fit(final.effects, [(final, [final])]).chi2  # kept in its memo
        rows.append({"effect": name, "effects_beside": list(final.names), "heldout_chi2_put_back": without,
                     "heldout_chi2": final.chi2, "excess_reduction": share_removed(without, final.chi2),
                     "earns": sel.rule.earns(without, final.chi2, band)})
    return rows


def at_rest_row(ds: StartupDataset, sel: Selector) -> dict | None:
    """The rule's check of the offsets removed at rest (module docstring), or None unless every
    record's offsets were measured on its pre-trigger: the held-out chi^2 per residual at rest
    with the offsets put back (``heldout_chi2_put_back``: the samples themselves, whitened) and
    removed (``heldout_chi2``: each half less the other half's mean), the share of the excess
    and whether the removal earns its place there (against the segment's own noise band: the
    whole record's is another segment's). Only ``sel``'s settings and rule are used."""
    pieces = [(rec.removed or {}).get("sensor_offset_at_rest") for rec in ds.startups
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


def masked_peaks_row(ds: StartupDataset, sel: Selector, final: SetFit) -> dict | None:
    """The rule's check of the masked current peaks (module docstring), or None where there is
    no mask on the one start-up record: the held-out chi^2 per residual of the masked samples
    (both currents, whitened by their noise estimates) as ``final`` predicts them
    (``heldout_chi2_put_back``) and through a compression fitted on the other fold
    (``heldout_chi2``), the share of the excess, and whether the removal earns its place against
    the noise band of those samples."""
    mask = (ds.startups[0].removed or {}).get("current_sensor_saturation") if len(ds.startups) == 1 else None
    if mask is None or not np.any(mask):
        return None
    back = selector_for(restored(ds, "current_sensor_saturation"), sel)
    model, data = back.model(final.effects), back.data
    n = data.n_startup
    if len(mask) != n:
        return None
    predicted = {f: model.simulate(final.xs[other][None, :])[0][: 2 * n].reshape(2, n)
                 for f, other in (("A", "B"), ("B", "A"))}  # fold f's held-out prediction
    in_a = back.masks["A"][:n]
    y = np.where(in_a, predicted["A"], predicted["B"])[:, mask]
    meas = data.meas[:2, mask]
    sigma = np.array([data.noise["i_alpha"].std, data.noise["i_beta"].std])[:, None]
    fold_a = in_a[mask]
    u_fit = {f: _compression(y[:, sel_], meas[:, sel_], sigma) for f, sel_ in (("A", fold_a), ("B", ~fold_a))}
    held = np.where(fold_a, (meas - _compressed(y, u_fit["B"])) / sigma, (meas - _compressed(y, u_fit["A"])) / sigma)
    raw = (meas - y) / sigma
    noise = data.noise["i_alpha"]
    band = misfit_ratio(held.ravel(), unit_noise(noise.rel_uncertainty, noise.n_effective),
                        k=sel.settings.band_k, bias_floor=sel.settings.band_floor).threshold
    s_without, s_with = float(np.mean(raw**2)), float(np.mean(held**2))
    return {"where": f"on the {int(mask.sum())} masked samples, held out, with a probe's compression fitted",
            "heldout_chi2_put_back": s_without, "heldout_chi2": s_with, "band": band,
            "compression_limit_a": [None if u == 0 else float(1.0 / u) for u in (u_fit["A"], u_fit["B"])],
            "excess_reduction": share_removed(s_without, s_with), "earns": sel.rule.earns(s_without, s_with, band)}


def _compressed(i_ab: np.ndarray, u: float) -> np.ndarray:
    """Alpha-beta currents (2, m) as two phase probes (R, S) read them when each compresses as
    ``tanh(u i) / u`` (``u = 1 / L``, 1/A; 0: no compression)."""
    if u <= 0:
        return i_ab
    i_r, i_s, _ = inverse_clarke(i_ab[0], i_ab[1])
    r, s = np.tanh(u * i_r) / u, np.tanh(u * i_s) / u
    return np.vstack(clarke(r, s, -r - s))


def _compression(y: np.ndarray, meas: np.ndarray, sigma: np.ndarray) -> float:
    """``u`` (1/A) of the compression that brings the predictions ``y`` closest to ``meas``
    (whitened least squares), from none (0) to a limit of a third of the largest predicted
    phase current."""
    if y.size == 0:
        return 0.0
    peak = float(np.max(np.abs(inverse_clarke(y[0], y[1]))))
    if not peak > 0:
        return 0.0

    def ssr(u):
        return float(np.sum(((meas - _compressed(y, u)) / sigma) ** 2))

    best = minimize_scalar(ssr, bounds=(0.0, 3.0 / peak), method="bounded", options={"xatol": 1e-4 / peak})
    return float(best.x) if best.fun < ssr(0.0) else 0.0


def selector_for(ds: StartupDataset, sel: Selector) -> Selector:
    """A selector of ``ds`` (the record with removals put back) with ``sel``'s noise levels,
    scales, settings and rule, so that its held-out chi^2 compare with ``sel``'s."""
    data = replace(DiagnosisData.from_dataset(ds), noise=sel.data.noise)
    masks = dict(zip(FOLDS, segment_folds(data), strict=True))
    other = Selector(data, sel.settings, sel.ctx, sel.centre, sel.fc_scale, masks, sel.rule, sel.order)
    other.input_noise = sel.input_noise
    return other


def unnamed_line(row: dict) -> str:
    """The report line of a removal the rule does not name."""
    what = {"sensor_offset": "the offsets", "current_sensor_saturation": "the masked samples"}
    numbers = (f"(held-out chi^2 {row['heldout_chi2_put_back']:.4g}, {row['heldout_chi2']:.4g} removed: "
               f"{100 * row['excess_reduction']:.0f} % of the excess, below the rule's share or within the noise band)")
    if "where" in row:
        how = f"checked {row['where']}, removing it makes little difference {numbers}"
    else:
        how = f"the model fits the record about as well with {what.get(row['effect'], 'it')} put back {numbers}"
    return f"{row['effect']} removed on load but not named: {how}; the diagnosis ran on the conditioned record"
