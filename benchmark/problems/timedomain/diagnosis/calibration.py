"""Calibrating the rule's one share (``diagnosis.selection_share``, :mod:`.rule`).

:func:`diagnose_at_shares` runs the diagnosis of one data set at several shares: the base is
identified once, and the selections share one :class:`~.selection.Selector` (a set fitted for
one share is not fitted again for the next; the fits are the same whichever share asked for
them). :func:`rates` scores the verdicts of many sets against what was injected, per share:
the false-selection rate (sets whose verdict names an effect that was not injected), the rate
of sets named exactly, and ``channel_delay`` named where it was not injected, each with a
bootstrap interval over the sets (the sets are the effect-form variants: every effect drawn in
its varied forms and sizes). :func:`chosen_share` picks the smallest share whose
false-selection rate is within the target.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping

import numpy as np

from benchmark.core.effects import load_effects
from benchmark.core.uncertainty import wilson
from benchmark.problems.timedomain.data import StartupDataset
from benchmark.problems.timedomain.diagnosis.named import named_effects
from benchmark.problems.timedomain.diagnosis.pipeline import diagnose
from benchmark.problems.timedomain.diagnosis.run import diagnosis_settings, identify_base
from benchmark.problems.timedomain.settings import TimeDomainSettings

#: Shares the calibration tries (the rule's ``tau``).
SHARES = (0.3, 0.4, 0.5, 0.6, 0.7, 0.8)


def diagnose_at_shares(run: Mapping, dataset: StartupDataset, identify: Callable, shares=SHARES,
                       first_form=()) -> list[dict]:
    """The verdict of ``dataset`` at each share (ascending), as ``{share, status, effects,
    held_by_base, removed_by_conditioning, gap_before, gap_after, explained_share}``. The
    candidates named in ``first_form`` are fitted in their first form
    (:meth:`~benchmark.core.effects.Effect.reduce_to_first_form`): a form variant, the injected
    effect in a form the catalogue cannot fit."""
    settings = diagnosis_settings(run)
    candidates = run.get("candidates")
    effects = load_effects("timedomain", list(candidates) if candidates else None)
    for name in first_form:
        if name in effects:
            effects[name].reduce_to_first_form()
    base, ds, _ = identify_base(TimeDomainSettings.from_run(run), dataset, settings.base_case, identify,
                                seed=int(run.get("seed", 0) or 0))
    out, selector = [], None
    for share in sorted(shares):
        doc = diagnose(ds, base, effects, dataclasses.replace(settings, selection_share=float(share)),
                       selector=selector)
        selector = doc["_models"]["selector"]
        out.append({"share": float(share), "status": doc["status"], "effects": doc["effects"],
                    "held_by_base": doc["held_by_base"], "removed_by_conditioning": doc["removed_by_conditioning"],
                    "gap_before": doc["gap_before"]["heldout_rms_over_noise"],
                    "gap_after": doc["gap_after"]["heldout_rms_over_noise"],
                    "explained_share": doc["explained_share"], "wall_time_s": doc["wall_time_s"]})
    return out


def _rates(sets: list[dict], share: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per set at ``share``: (false selection, named exactly, channel_delay named though not
    injected, channel_delay was a candidate and not injected) as 0/1 arrays."""
    false, exact, skew, skew_free = [], [], [], []
    for s in sets:
        v = next(v for v in s["verdicts"] if v["share"] == share)
        injected = set(s["injected"])
        got = set(named_effects(v))
        # an injected effect the base cannot see (no gap) and that nothing names is not a miss (the
        # blind score leaves such a set out); one the conditioning removed is scored
        seen = injected if v["status"] != "no_gap" or got else set()
        false.append(bool(got - injected))
        exact.append(got == seen)
        skew_free.append("channel_delay" not in injected and s.get("skew_candidate", False))
        skew.append("channel_delay" in got and "channel_delay" not in injected)
    return tuple(np.array(a, float) for a in (false, exact, skew, skew_free))


def rates(sets: list[dict], shares=SHARES, n_boot: int = 2000, seed: int = 0) -> list[dict]:
    """Per share: false-selection rate, exact rate and ``channel_delay`` false rate (over the sets
    where it was a candidate and not injected), each with a 95 % percentile bootstrap interval
    over the sets (resampled ``n_boot`` times) and a Wilson 95 % interval
    (:func:`~benchmark.core.uncertainty.wilson`: a rate with no event has a bootstrap interval of
    nothing, and the choice reads the Wilson one)."""
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, len(sets), size=(n_boot, len(sets)))
    out = []
    for share in shares:
        false, exact, skew, skew_free = _rates(sets, share)
        row = {"share": float(share), "sets": len(sets)}
        for name, x in (("false_selection", false), ("exact", exact)):
            boot = x[idx].mean(axis=1)
            row[name] = float(x.mean())
            row[name + "_ci95"] = [float(np.percentile(boot, 2.5)), float(np.percentile(boot, 97.5))]
            row[name + "_wilson95"] = wilson(int(round(x.sum())), len(x))
        n_free = skew_free.sum()
        row["channel_delay_candidate_not_injected"] = int(n_free)
        row["channel_delay_named_not_injected"] = int(skew.sum())
        out.append(row)
    return out


def chosen_share(table: list[dict], target: float) -> float | None:
    """The smallest share whose false-selection rate is within ``target`` with its interval: the
    upper end of its Wilson 95 % interval at most ``target`` (a rate at the target by its count
    alone, 2 of 40 for 5 %, is not within it), or None."""
    ok = [r["share"] for r in table if r["false_selection_wilson95"][1] <= target]
    return min(ok) if ok else None


def fewest_false(table: list[dict]) -> float:
    """Where no share is within the target (:func:`chosen_share` None): the smallest share with
    the fewest false selections."""
    return min(table, key=lambda r: (r["false_selection"], r["share"]))["share"]
