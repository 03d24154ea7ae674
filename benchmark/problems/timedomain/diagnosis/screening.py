"""Linearised screening of the selection's candidates (:mod:`.score_tests`): what a single
effect, or a pair, added to the current set is predicted to reach on the held-out samples,
before (or instead of) a full fit. The decisions that read it are the selection's
(:meth:`.selection.Selector.round_fits`, :meth:`.selection.Selector.pair_step`); a fit that ends
above the current set where its screening earns is fitted again from the screening's points."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from benchmark.problems.timedomain.diagnosis.engine import side_by_side
from benchmark.problems.timedomain.diagnosis.fit import JointModel
from benchmark.problems.timedomain.diagnosis.score_tests import score_tests
from benchmark.problems.timedomain.diagnosis.set_fit import FOLDS, SetFit


class Screened(NamedTuple):
    """One candidate's screening beside a fit (:meth:`Screening.screen_singles`)."""

    chi2: float  #: held-out chi^2 per residual it is predicted to reach, the folds pooled
    points: dict  #: per fold, the point the test scored (parameter names to values)
    one_shape: bool  #: some of its parameters changed nothing at the step's start (either fold)


NOT_SCREENED = Screened(float("nan"), {}, False)


def _fit_key(cur: SetFit) -> tuple:
    """The key of a set's fit in ``screened_beside``: its effects and each fold's parameters."""
    return (tuple(cur.names), *(cur.xs[f].tobytes() for f in FOLDS))


class Screening:
    """The screening part of :class:`.selection.Selector` (it provides ``data``, ``settings``,
    ``ctx``, ``centre``, ``fc_scale``, ``masks``, ``rule``, the starts, :meth:`composed`,
    :meth:`profiled` and :meth:`fits`, and ``screened_beside``, a dict), with
    the refit of a fit that missed the basin its screening reached (:meth:`missed_basins`)."""

    def in_given_order(self, effects) -> JointModel:
        """The model of ``effects`` with the parameters in the order given (the fitted set's, then
        the new effects'), as the score tests read them; :meth:`model` orders by the catalogue."""
        return JointModel(self.data, self.settings.base_case, list(effects), self.ctx, self.centre, self.fc_scale,
                          self.settings.base_span)

    def screen_singles(self, cur: SetFit, pool) -> dict[str, float]:
        """The held-out chi^2 each candidate of ``pool`` is predicted to reach beside ``cur``:
        the score test (:func:`.score_tests.score_tests`, its ``score``) of adding it to each
        fold's fit of ``cur``, linearised at the starts its full fit takes (:meth:`composed`,
        :meth:`profiled`) and scored on the other fold; the two folds' held-out chi^2 pooled as
        :attr:`SetFit.chi2` pools them. Each candidate's test depends on ``cur``'s fit and the
        candidate alone: kept in ``screened_beside`` (a round that starts from the same fit again,
        after an effect refused on entry left, screens only what it has not), with each fold's
        point the test scored (:meth:`screened_points`)."""
        kept = self.screened_beside.setdefault(_fit_key(cur), {})
        todo = [e for e in pool if e.name not in kept]

        def fold(f):
            other = "B" if f == "A" else "A"

            def starts(model, x_fit, new):  # the new effect is the model's last
                composed = self.composed(model, cur, [cur], f)
                return self.profiled(model, composed, self.masks[f], [len(model.effects) - 1])

            rows = score_tests(self.in_given_order, cur.effects, cur.xs[f], self.masks[f], self.masks[other],
                               [(e,) for e in todo], self.ctx, starts=starts)
            n = int(np.count_nonzero(self.masks[other]))
            return {r["effect"]: (n * r["score"], r["point"], bool(r["unseen"])) for r in rows}

        if todo:
            parts = side_by_side(fold, FOLDS)
            total = sum(int(np.count_nonzero(self.masks[f])) for f in FOLDS)
            kept |= {e.name: Screened((parts[0][e.name][0] + parts[1][e.name][0]) / total,
                                      {f: part[e.name][1] for f, part in zip(FOLDS, parts, strict=True)},
                                      any(part[e.name][2] for part in parts)) for e in todo}
        return {e.name: kept[e.name].chi2 for e in pool}

    def screened(self, cur: SetFit, name: str) -> Screened:
        """Candidate ``name``'s screening beside ``cur`` (:data:`NOT_SCREENED` where there is none)."""
        return self.screened_beside.get(_fit_key(cur), {}).get(name, NOT_SCREENED)

    def seen_in_one_shape(self, cur: SetFit, name: str) -> bool:
        """Whether candidate ``name``'s screening beside ``cur`` (:meth:`screen_singles`) saw it in
        its start's shape only: some of its parameters changed nothing where the step was taken
        (``unseen`` of :func:`.score_tests.score_tests`, on either fold; a load torque starting at
        0, whose instant and shape then do nothing). Its screened chi^2 then rates that shape, not
        the effect."""
        return self.screened(cur, name).one_shape

    def screened_points(self, cur: SetFit, name: str) -> dict[str, list[dict[str, float]]]:
        """Per fold, the point at which candidate ``name``'s screening beside ``cur`` scored it
        (:meth:`screen_singles`; parameter names to values), as further starts of its fit."""
        return {f: [point] for f, point in self.screened(cur, name).points.items()}

    def fold_b(self, sf: SetFit) -> float:
        """Fold B's held-out chi^2 of ``sf`` (fold B predicted by the fit on fold A)."""
        return float(np.mean(sf.held[self.masks["B"]] ** 2))

    def screen_pairs(self, pool, singles: dict) -> dict[frozenset, float]:
        """Fold B's held-out chi^2 each pair of ``pool`` is predicted to reach: the linearised
        score test (:func:`.score_tests.score_tests`) of adding ``b`` to the single fit of the
        current set plus ``a`` (on fold A; the masking partner's signature shows once ``a`` is
        in), the better of the two orders."""
        def given(a):
            sa = singles[a.name]
            rows = score_tests(self.in_given_order, sa.effects, sa.xs["A"], self.masks["A"], self.masks["B"],
                               [(b,) for b in pool if b is not a], self.ctx)
            return {frozenset((a.name, r["effect"])): r["predicted_heldout_chi2"] for r in rows}

        out: dict[frozenset, float] = {}
        for part in side_by_side(given, pool):
            for key, chi2 in part.items():
                out[key] = min(chi2, out.get(key, np.inf))
        return out

    def missed_basins(self, cur: SetFit, ranked, fits: dict, screened: dict, band: float, progress=None) -> dict:
        """The fits of the candidates whose screening says they earn their place beside ``cur``
        but whose fit ends above ``cur``'s held-out chi^2 (a model that holds ``cur`` and does
        worse than it: its fold fits missed the basin the screening's one step reached),
        refitted with the points the screening scored as further starts; by name. The fits
        still choose by their own samples (:meth:`best`), so a refit ends where its fold fits
        best, which may be where it was (motulator, held-out seed 415 set 28, a DC generator
        from 0.27 s: its load's fold fits at the record's start, 256 against the base's 152,
        where its screening scored 83.5; from the screening's points, 1.13)."""
        missed = [e for e in ranked if e.name in fits and fits[e.name].chi2 > cur.chi2
                  and self.rule.earns(cur.chi2, screened[e.name], band)]
        jobs = [(cur.effects + [e], [(cur, [cur])], True, self.screened_points(cur, e.name)) for e in missed]
        return dict(zip([e.name for e in missed], self.fits(jobs, progress), strict=True)) if jobs else {}
